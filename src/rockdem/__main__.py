"""``python -m rockdem``: the command line."""

from .cli import main

main()
