"""``python -m proleg``: the same as the ``proleg`` command."""

import sys

from .cli import main

sys.exit(main())
