"""``python -m urpc``: the command-line interface (see :mod:`urpc.cli`)."""

import sys

from .cli import main

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())
