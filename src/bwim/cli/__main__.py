"""``python -m bwim.cli``."""

import sys

from bwim.cli import main

sys.exit(main())
