"""garant verify: every check of the built-in models against the papers."""
import sys
import time

from ..outcomes import Exit
from . import flags


def add(sub):
    """The `garant verify` subcommand and its flags."""
    p = sub.add_parser("verify", help="run every check of the built-in models against the papers")
    flags.json(p)
    p.add_argument("--certificates", metavar="DIR", help="write every optimality certificate (JSON) here")
    p.add_argument("--verbose", action="store_true",
                   help="print every check's row (check, source, expected, got); by default each group's count and "
                        "the row of every check that fails")
    return p


def run(args):
    """`garant verify`: parse, call the job, print; the exit status."""
    from .. import models
    from ..io import report
    from ..papers import certificates, norm_001, redundancy_003, stand_000
    groups = (stand_000.all_groups(models.load("two-axis"), models.load_remount("two-axis"))
              + norm_001.all_groups(models.load("norm")) + redundancy_003.all_groups()
              + [(certificates.certificates, (args.certificates,))])
    rows, counts = [], []
    for group, group_args in groups:
        t0 = time.perf_counter()
        got = list(group(*group_args))
        rows += got
        name = f"{group.__module__.rsplit('.', 1)[-1]}.{group.__name__}"
        counts.append((name, len(got), sum(not r.passed for r in got)))
        print(f"[{name}] {len(got)} checks in {time.perf_counter() - t0:.2f} s", file=sys.stderr)
    failed = [r for r in rows if not r.passed]
    shown = rows if args.verbose else failed
    if not args.verbose:
        report.table(("group of checks", "checks", "failed"), [(n, k, f) for n, k, f in counts])
        if failed:
            print("\nthe checks that fail:")
    if shown:
        report.table(("check", "source", "expected", "got", "pass"),
                     [(r.name, r.source, r.expected, r.got, "PASS" if r.passed else "FAIL") for r in shown])
    elif not args.verbose:
        print("(--verbose prints every check: its source in the papers, the expected value and what garant got)")
    print(f"\n{len(rows) - len(failed)} passed, {len(failed)} failed")
    if args.json:
        report.write_json(args.json, {"checks": [
            {"name": r.name, "source": r.source, "expected": r.expected, "got": r.got,
             "passed": bool(r.passed)} for r in rows]})
    return Exit.FAILED if failed else Exit.OK
