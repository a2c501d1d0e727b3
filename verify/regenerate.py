"""python -m verify.regenerate [--check]: everything derived, by one command (the generated modules and derivation
pages, the certificates, docs/cli.md, docs/fields.md, the module table of docs/architecture.md).

A new stand is a TOML in derive/stands/ and this command. With --check nothing is written: exit 1 naming each file
that differs from a fresh rendering (derive's with a unified diff). `python -m derive`, `python -m verify.proof` and
`python -m verify.cli.doc` each still do their own part.
"""
import argparse
import ast
import difflib
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ARCHITECTURE = ROOT / "docs" / "architecture.md"
#: The packages whose modules the table lists, and the longest line of the table's second column.
PACKAGES, LONGEST = ("derive", "generated", "verify"), 200
_TABLE = re.compile(r"(\| module \| what it is \|\n\|---\|---\|\n)((?:\|.*\|\n)*)")


def summary(path):
    """A module's line in the table: the first sentence of its docstring (at most LONGEST characters, cut at a word
    with " ..."), or None for a module without one (an empty __init__)."""
    doc = ast.get_docstring(ast.parse(Path(path).read_text()))
    if not doc:
        return None
    text = " ".join(doc.split("\n\n")[0].split())
    first = re.match(r"(.+?\.)(?= [A-Z`(]|$)", text)
    text = first.group(1) if first else text
    if len(text) > LONGEST:
        text = text[:LONGEST].rsplit(" ", 1)[0] + " ..."
    return text.replace("|", "\\|")


def module_table(text):
    """docs/architecture.md's text with its module table made from the modules' docstrings."""
    rows = [f"| `{p.relative_to(ROOT)}` | {line} |\n" for pkg in PACKAGES for p in sorted((ROOT / pkg).rglob("*.py"))
            if "__pycache__" not in p.parts and (line := summary(p))]
    return _TABLE.sub(lambda m: m.group(1) + "".join(rows), text, count=1)


def derived():
    """{path relative to the repository: text} of everything derived, rendered now."""
    from garant.derive import codegen

    from .cli import doc
    from .proof.build import COMMITTED, built
    out = dict(codegen.outputs())
    certificates = COMMITTED.relative_to(ROOT)
    out.update({str(certificates / name): text for name, text in built().items()})
    out[str(doc.PATH.relative_to(ROOT))] = doc.markdown()
    out[str(doc.FIELDS_PATH.relative_to(ROOT))] = doc.fields_markdown()
    out[str(ARCHITECTURE.relative_to(ROOT))] = module_table(ARCHITECTURE.read_text())
    return out


def stale(files):
    """The committed certificates no rendering makes any more (a model or a q gone)."""
    from .proof.build import COMMITTED
    return sorted(str(p.relative_to(ROOT)) for p in COMMITTED.glob("*.json") if str(p.relative_to(ROOT)) not in files)


def main(argv=None):
    """Regenerate everything derived, or with --check compare in memory; the exit status."""
    ap = argparse.ArgumentParser(prog="python -m verify.regenerate", description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="render in memory; exit 1 naming each file that differs")
    args = ap.parse_args(argv)
    files = derived()
    differ = [rel for rel, text in files.items()
              if not (ROOT / rel).is_file() or (ROOT / rel).read_text() != text]
    gone = stale(files)
    if args.check:
        for rel in differ:
            old = (ROOT / rel).read_text() if (ROOT / rel).is_file() else ""
            sys.stdout.write("".join(difflib.unified_diff(old.splitlines(True), files[rel].splitlines(True),
                                                          f"a/{rel}", f"b/{rel} (regenerated)", n=1)))
        for rel in gone:
            print(f"{rel}: made by no rendering any more")
        print(f"{len(files)} derived files: " + (f"{len(differ) + len(gone)} differ; run `python -m verify.regenerate`"
                                                 " and commit" if differ or gone else "up to date"))
        return 1 if differ or gone else 0
    from .io.report import write_text
    for rel in differ:
        (ROOT / rel).parent.mkdir(parents=True, exist_ok=True)
        write_text(ROOT / rel, files[rel])
        print(f"wrote {rel}")
    for rel in gone:
        (ROOT / rel).unlink()
        print(f"removed {rel}")
    print(f"{len(files)} derived files; {len(differ) + len(gone)} written or removed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
