"""``python -m fvdem``: the same command line as ``fvdem``."""
import sys

from .cli import main

sys.exit(main())
