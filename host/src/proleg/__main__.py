"""``python -m proleg``: the same as the ``proleg`` command."""

import sys

try:
    from .cli import main
except KeyboardInterrupt:  # Ctrl-C while Python loads proleg: no traceback for that
    print("proleg: interrupted", file=sys.stderr)
    sys.exit(130)

sys.exit(main())
