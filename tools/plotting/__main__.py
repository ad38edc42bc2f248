"""`python3 -m plotting` (with tools/ on the path): as tools/plot.py."""
import sys

from .cli import main

sys.exit(main())
