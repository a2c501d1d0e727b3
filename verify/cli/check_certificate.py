"""garant check-certificate: re-check an optimality certificate without any solver."""
from pathlib import Path

from ..errors import DataError


def add(sub):
    p = sub.add_parser("check-certificate", help="re-check optimality certificates, independently of any solver")
    p.add_argument("files", metavar="FILE.json", nargs="+", help="one or more certificates (e.g. DIR/*.json)")
    return p


def run(args):
    from ..proof import check
    held = 0
    for path in args.files:
        try:
            cert = check.read(path)
            steps = check.check(cert, base=str(Path(path).resolve().parent))
        except check.MalformedCertificate as e:
            raise DataError(f"{path}: not a valid certificate: {e}") from None
        print(f"{cert.get('claim', '?')} ({cert.get('model', '?')}), value {cert.get('value', '?')}")
        for step, ok, detail in steps:
            print(f"  {'PASS' if ok else 'FAIL'} {step}: {detail}")
        ok = all(ok for _, ok, _ in steps)
        held += ok
        print("certificate holds" if ok else "certificate REJECTED")
    if len(args.files) > 1:
        print(f"{held} of {len(args.files)} certificates hold")
    return 0 if held == len(args.files) else 1
