"""python -m verify.power: a developer tool, run from a checkout (not in the wheel)."""
import sys

from . import main

sys.exit(main())
