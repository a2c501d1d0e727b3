"""docs/cli.md from the argument parser itself, docs/fields.md from the JSON schemas: every option, every field.

python -m verify.cli.doc            # print docs/cli.md
python -m verify.cli.doc --check    # fail when either page differs (tests/cli/test_cli.py does the same)
python -m verify.cli.doc --write    # write both
"""
import argparse
import sys
from pathlib import Path

from . import COMMANDS, parser

PATH = Path(__file__).resolve().parents[2] / "docs" / "cli.md"
FIELDS_PATH = PATH.with_name("fields.md")
HEADER = ("# The command line\n\nGenerated from the argument parser (`python -m verify.cli.doc --write`; a test "
          "fails when it drifts). `garant COMMAND --help` prints the same.\n")


def _row(action):
    flags = ", ".join(f"`{f}`" for f in action.option_strings) or f"`{action.metavar or action.dest}`"
    choices = f"{{{','.join(map(str, action.choices))}}}" if action.choices else action.dest.upper()
    meta = "" if action.nargs == 0 else (action.metavar or choices)
    default = action.default
    shown = ("" if default in (None, False, [], argparse.SUPPRESS) or not action.option_strings
             or "default" in (action.help or "") else f" (default {default})")
    text = (action.help or "").replace("|", "\\|").replace("\n", " ")
    return f"| {flags} | {meta} | {text}{shown} |"


def markdown():
    """The whole page: for each command its one-line purpose, its usage (100 columns, whatever the terminal)
    and a table of its arguments."""
    import os
    width = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"
    try:
        return _page()
    finally:
        if width is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = width


def _page():
    ap = parser()
    sub = next(a for a in ap._actions if isinstance(a, argparse._SubParsersAction))
    helps = {c.dest: c.help for c in sub._choices_actions}
    out = [HEADER]
    for name in COMMANDS:
        p = sub.choices[name]
        out += [f"## garant {name}", "", f"{helps.get(name, '')}.", "", "```text", p.format_usage().strip(), "```", "",
                "| argument | value | meaning |", "|---|---|---|"]
        out += [_row(a) for a in p._actions if not isinstance(a, argparse._HelpAction)]
        out.append("")
    return "\n".join(out)


def fields_markdown():
    """docs/fields.md: each JSON a command writes or reads, its schema's title and, a row each, every field of its
    top level with its type and meaning (the schemas are the one home of the fields)."""
    import json

    from ..io.schemas import FOLDER
    out = ["# The fields of every JSON file", "", "Generated from the schemas in `docs/schemas/` (`python -m "
           "verify.cli.doc --write`; a test fails when it drifts). Each schema admits no field it does not list; "
           "the API's results (`import garant`) have the same fields as the command's `--json`.", ""]
    for path in sorted(FOLDER.glob("*.schema.json")):
        schema = json.loads(path.read_text())
        required = set(schema.get("required", ()))
        out += [f"## {path.name}", "", f"{schema['title']}.", "", "| field | type | meaning |", "|---|---|---|"]
        for name, sub in schema["properties"].items():
            sub = {**schema.get("$defs", {}).get(sub.get("$ref", "").removeprefix("#/$defs/"), {}), **sub}
            kind = sub.get("type") or ("one of " + ", ".join(map(str, sub["enum"])) if "enum" in sub else
                                       f"= {sub['const']}" if "const" in sub else "see the schema")
            kind = " or ".join(kind) if isinstance(kind, list) else kind
            text = sub.get("description", "").replace("|", "\\|").replace("\n", " ")
            out.append(f"| `{name}`{' (always)' if name in required else ''} | {kind} | {text} |")
        out.append("")
    return "\n".join(out)


def main(argv=None):
    """Print docs/cli.md, or check or write it and docs/fields.md; exit status 1 when --check finds a difference."""
    argv = sys.argv[1:] if argv is None else argv
    pages = ((PATH, markdown()), (FIELDS_PATH, fields_markdown()))
    if "--check" in argv:
        stale = [p.name for p, text in pages if not (p.exists() and p.read_text() == text)]
        print(f"docs/{', docs/'.join(stale)} differ(s): python -m verify.cli.doc --write" if stale
              else "docs/cli.md and docs/fields.md are up to date")
        return 1 if stale else 0
    if "--write" in argv:
        from ..io.report import write_text
        for path, text in pages:
            write_text(path, text)
            print(f"wrote {path}")
        return 0
    print(pages[0][1])
    return 0


if __name__ == "__main__":
    sys.exit(main())
