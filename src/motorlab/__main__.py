"""``python -m motorlab``."""

import sys

from motorlab.cli import main

sys.exit(main())
