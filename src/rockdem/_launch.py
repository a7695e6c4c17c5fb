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
    try:
        from .cli import main as cli_main

        cli_main()
    except KeyboardInterrupt:  # Ctrl-C while the libraries load (found by fuzzing:
        sys.stderr.write("interrupted\n")  # a 29-68 line traceback)
        sys.exit(130)
