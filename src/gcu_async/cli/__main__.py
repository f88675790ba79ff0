"""``python -m gcu_async.cli`` runs the ``gcu-async`` command line."""

import sys

from gcu_async.cli import main

sys.exit(main())
