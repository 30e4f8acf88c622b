"""`python -m sortbot.cli` = `sortbot`."""

import sys

from sortbot.cli import main

sys.exit(main())
