"""``python -m nmmm``: the same command line as the ``nmmm`` console script (:mod:`nmmm.cli`)."""

import sys

from nmmm.cli import main

if __name__ == "__main__":
    sys.exit(main())
