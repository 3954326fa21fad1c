"""``python -m robotdyn`` and the ``robotdyn`` console script."""

import sys

from .cli.commands import main

if __name__ == "__main__":
    sys.exit(main())
