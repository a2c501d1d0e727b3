"""python -m verify.proof [--check]: rebuild the committed certificates of the built-in models
(verify/proof/certificates/), or fail with the names of those that differ from a rebuild."""
import argparse
import sys


def main(argv=None):
    """Rebuild (or with --check compare) the committed certificates; the exit status."""
    ap = argparse.ArgumentParser(prog="python -m verify.proof", description=__doc__)
    ap.add_argument("--check", action="store_true", help="rebuild in memory; exit 1 naming any file that differs")
    args = ap.parse_args(argv)
    from .build import COMMITTED, built
    from ..io.report import write_text
    fresh = built()
    old = {p.name: p.read_text() for p in COMMITTED.glob("*.json")} if COMMITTED.is_dir() else {}
    differ = sorted(n for n in fresh.keys() | old.keys() if fresh.get(n) != old.get(n))
    if args.check:
        for n in differ:
            print(f"{COMMITTED.name}/{n}: " + ("missing" if n not in old else "stale" if n in fresh else "not built "
                "any more"))
        print(f"{len(fresh)} certificates {'up to date' if not differ else f'built, {len(differ)} differ'}.")
        return 1 if differ else 0
    COMMITTED.mkdir(exist_ok=True)
    for n in differ:
        if n in fresh:
            write_text(COMMITTED / n, fresh[n])
        else:
            (COMMITTED / n).unlink()
    print(f"{len(fresh)} certificates; {len(differ)} written or removed in {COMMITTED}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
