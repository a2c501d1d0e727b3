"""garant derive: a stand description to its generated module and derivation report."""
import time

from ..outcomes import Exit
from ..errors import DataError


def add(sub):
    """The `garant derive` subcommand and its options."""
    p = sub.add_parser("derive", help="derive a stand description: generated module and derivation report")
    p.add_argument("stand", metavar="STAND.toml")
    p.add_argument("--out", default=".", help="directory for the module and report (default: here)")
    return p


def run(args):
    """`garant derive`: parse, call the job, print; the exit status."""
    from garant.derive import codegen, description

    from .. import models
    from ..io import report
    try:
        model = description.load(args.stand)
        t0 = time.perf_counter()
        files = codegen.model_files(model, module_dir=args.out, docs_dir=args.out)
    except description.DescriptionError as e:
        raise DataError(str(e), param="stand") from None
    for rel in report.write_files(files):
        print(f"wrote {rel}")
    mod = models.from_description(args.stand)
    print(f"{model.stand.title}: {len(model.parameters)} physical parameters, {len(mod.Q_NAMES)} "
          f"identifiable combinations, {len(mod.UNSEPARABLE)} unseparable directions "
          f"(derived in {time.perf_counter() - t0:.1f} s)")
    for q, d in zip(mod.Q_NAMES, mod.Q_DEFINITIONS):
        print(f"  {q} = {d}")
    return Exit.OK
