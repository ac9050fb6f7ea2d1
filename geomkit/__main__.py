"""``python -m geomkit``: the command line (:mod:`geomkit.cli`)."""

import sys

from .cli import main

sys.exit(main())
