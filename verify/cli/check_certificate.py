"""garant check-certificate: re-check an optimality certificate without any solver."""
from ..outcomes import Exit
from pathlib import Path

from ..errors import DataError


def add(sub):
    """The `garant check-certificate` subcommand and its options."""
    p = sub.add_parser("check-certificate", help="re-check optimality certificates, independently of any solver")
    p.add_argument("files", metavar="FILE.json", nargs="+", help="one or more certificates (e.g. DIR/*.json)")
    return p


def _escaped(value, limit=300):
    """A value a file supplies, printable: control characters escaped, cut at `limit` characters (a file
    cannot print a fake PASS line or hide the rest of the output)."""
    text = value if isinstance(value, str) else repr(value)
    text = "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in text)
    return text if len(text) <= limit else text[:limit] + "..."


def run(args):
    """`garant check-certificate`: parse, call the job, print; the exit status."""
    from ..proof import check
    held = 0
    for path in args.files:
        try:
            cert = check.read(path)
            steps = check.check(cert, base=str(Path(path).resolve().parent))
        except check.MalformedCertificate as e:
            raise DataError(f"{path}: not a valid certificate: {e}", param="files") from None
        print(f"{_escaped(cert.get('claim', '?'))} ({_escaped(cert.get('model', '?'))}), value "
              f"{_escaped(cert.get('value', '?'))}")
        for step, ok, detail in steps:
            print(f"  {'PASS' if ok else 'FAIL'} {step}: {_escaped(detail, 2000)}")
        ok = all(ok for _, ok, _ in steps)
        held += ok
        print("certificate holds" if ok else "certificate REJECTED")
    if len(args.files) > 1:
        print(f"{held} of {len(args.files)} certificates hold")
    return Exit.OK if held == len(args.files) else Exit.FAILED
