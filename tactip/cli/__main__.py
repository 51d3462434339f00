"""`python -m tactip.cli` runs the `tactip` command."""

import sys

from tactip.cli import main

sys.exit(main())
