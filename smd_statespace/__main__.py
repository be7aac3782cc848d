"""``python -m smd_statespace`` is the ``smd-statespace`` command (see :mod:`smd_statespace.cli`)."""

import sys

from .cli.main import main

sys.exit(main())
