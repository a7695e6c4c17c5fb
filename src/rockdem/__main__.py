"""``python -m rockdem``: the command line."""

from ._launch import main

main()
