"""``python -m gcu_async`` runs the ``gcu-async`` command line."""

import sys

from gcu_async.cli import main

sys.exit(main())
