"""python -m derive [--check]: regenerate the committed files, or fail with a diff on drift."""
import argparse
import sys

from . import codegen


def main(argv=None):
    """Regenerate every committed file, or with --check compare in memory; the exit status."""
    ap = argparse.ArgumentParser(prog="python -m derive", description=__doc__)
    ap.add_argument("--check", action="store_true",
                    help="render in memory and exit 1 with a unified diff if any committed file differs")
    args = ap.parse_args(argv)
    if args.check:
        files = codegen.outputs()
        diffs = codegen.drift(files=files)
        for d in diffs:
            sys.stdout.write(d)
        if diffs:
            print(f"{len(diffs)} generated file(s) differ: run `python -m derive` and commit.",
                  file=sys.stderr)
            return 1
        print(f"{len(files)} generated files up to date.")
        return 0
    for rel in codegen.write():
        print(f"wrote {rel}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
