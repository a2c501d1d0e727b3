"""python -m verify.bench: a developer tool, run from a checkout (not in the wheel)."""
from . import main

main()
