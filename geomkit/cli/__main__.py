"""``python -m geomkit.cli``."""

import sys

from . import main

sys.exit(main())
