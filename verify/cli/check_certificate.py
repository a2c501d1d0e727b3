"""garant check-certificate: re-check an optimality certificate without any solver."""
from pathlib import Path

from ..errors import DataError


def add(sub):
    p = sub.add_parser("check-certificate", help="re-check an optimality certificate, independently of any solver")
    p.add_argument("file", metavar="FILE.json")
    return p


def run(args):
    from ..proof import check
    try:
        cert = check.read(args.file)
        steps = check.check(cert, base=str(Path(args.file).resolve().parent))
    except check.MalformedCertificate as e:
        raise DataError(f"{args.file}: not a valid certificate: {e}") from None
    print(f"{cert.get('claim', '?')} ({cert.get('model', '?')}), value {cert.get('value', '?')}")
    for step, ok, detail in steps:
        print(f"  {'PASS' if ok else 'FAIL'} {step}: {detail}")
    ok = all(ok for _, ok, _ in steps)
    print("certificate holds" if ok else "certificate REJECTED")
    return 0 if ok else 1
