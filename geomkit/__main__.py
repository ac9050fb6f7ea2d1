"""``python -m geomkit``: the command line (:mod:`geomkit.cli`)."""

import sys

from geomkit.cli import main

sys.exit(main())
