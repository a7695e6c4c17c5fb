"""The ``rockdem`` console script: answers ``--version`` before loading the
command line (and with it NumPy, SciPy and PARDISO), then hands over."""

from __future__ import annotations

import sys


def main() -> None:
    """Console script entry point."""
    if sys.argv[1:] == ["--version"]:
        from . import __version__

        sys.stdout.write(f"rockdem {__version__}\n")
        return
    from .cli import main as cli_main

    cli_main()
