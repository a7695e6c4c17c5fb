"""``python -m rockdem.cli``: the command line (as ``python -m rockdem``)."""

import sys

from . import main

sys.exit(main())
