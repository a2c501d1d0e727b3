"""garant verify: every check of the built-in models against the papers."""
import sys
import time

from . import args as options


def add(sub):
    """The `garant verify` subcommand and its options."""
    p = sub.add_parser("verify", help="run every check of the built-in models against the papers")
    options.json(p)
    p.add_argument("--certificates", metavar="DIR", help="write every optimality certificate (JSON) here")
    return p


def run(args):
    """`garant verify`: parse, call the job, print; the exit status."""
    from .. import models
    from ..io import report
    from ..papers import certificates, norm_001, redundancy_003, stand_000
    groups = (stand_000.all_groups(models.load("two-axis"), models.load_remount("two-axis"))
              + norm_001.all_groups(models.load("norm")) + redundancy_003.all_groups()
              + [(certificates.certificates, (args.certificates,))])
    rows = []
    for group, group_args in groups:
        t0 = time.perf_counter()
        got = list(group(*group_args))
        rows += got
        print(f"[{group.__module__.rsplit('.', 1)[-1]}.{group.__name__}] {len(got)} checks in "
              f"{time.perf_counter() - t0:.2f} s", file=sys.stderr)
    report.table(("check", "source", "expected", "got", "pass"),
                 [(r.name, r.source, r.expected, r.got, "PASS" if r.passed else "FAIL") for r in rows])
    failed = [r for r in rows if not r.passed]
    print(f"\n{len(rows) - len(failed)} passed, {len(failed)} failed")
    if args.json:
        report.write_json(args.json, {"checks": [
            {"name": r.name, "source": r.source, "expected": r.expected, "got": r.got,
             "passed": bool(r.passed)} for r in rows]})
    return 1 if failed else 0
