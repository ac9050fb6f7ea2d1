"""``python -m geomkit.cli``."""

import sys

from geomkit.cli import main

sys.exit(main())
