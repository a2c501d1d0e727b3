"""Every optimal value of the built-in models, certified and re-checked independently, for `garant verify`."""
from pathlib import Path

from .. import models
from ..io import files
from ..proof import build, check
from ..proof.reference import MODELS
from .row import Check


def certificates(write_dir=None):
    """Re-check the committed certificate of every optimal value of the built-in models, independently
    of the solvers that built them (verify/proof/certificates/; `python -m verify.proof` rebuilds them)."""
    if write_dir:
        files.make_folder(write_dir)
    for name in MODELS:
        mod = models.load(name)
        done = set()
        for q, cert in build.committed(name, mod.Q_NAMES):
            if cert is None:
                continue
            steps = check.check(cert)
            claimed = cert["claim"].split(" of ", 1)[1].split(" ", 1)[0]
            if claimed != q:
                yield Check(f"certificate {name} {q}", "000 (9)-(10), Theorems 2-4", f"a claim about {q}",
                            f"a claim about {claimed}", False)
                continue
            done.add(q)
            if write_dir:
                check.write(cert, Path(write_dir) / build.file_name(cert))
            how = "exact" if "exact" in steps[-1][2] else steps[-1][2].split(": ")[-1]
            yield Check(f"certificate {name} {q}: (0) model (a) unbiased (b) primal = dual (c) dual feasible",
                        "000 (9)-(10), Theorems 2-4; 001 section 4", f"value {cert['value']}, all hold",
                        ", ".join("ok" if ok else f"FAILS {st}" for st, ok, _ in steps) + f" ({how})",
                        all(ok for _, ok, _ in steps))
        missing = [q for q in mod.Q_NAMES if q not in done]
        if missing:
            yield Check(f"certificates {name}: every optimal value certified", "000 (9)-(10), Theorems 2-4",
                        "a certificate for every q", "none for " + ", ".join(missing), False)
