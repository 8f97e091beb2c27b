"""``python -m raysim`` runs the command line."""

import sys

from raysim.cli import main

sys.exit(main())
