"""python -m verify [--json FILE]: the same as `garant verify`."""
import sys

from .cli import main

sys.exit(main(["verify", *sys.argv[1:]]))
