"""docs/cli.md from the argument parser itself: every command, every option, its metavar, default and help.

python -m verify.cli.doc            # print it
python -m verify.cli.doc --check    # fail when docs/cli.md differs (tests/cli/test_cli.py does the same)
python -m verify.cli.doc --write    # write docs/cli.md
"""
import argparse
import sys
from pathlib import Path

from . import COMMANDS, parser

PATH = Path(__file__).resolve().parents[2] / "docs" / "cli.md"
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


def main(argv=None):
    """Print, check or write docs/cli.md; exit status 1 when --check finds a difference."""
    argv = sys.argv[1:] if argv is None else argv
    text = markdown()
    if "--check" in argv:
        same = PATH.exists() and PATH.read_text() == text
        print("docs/cli.md is up to date" if same else "docs/cli.md differs: python -m verify.cli.doc --write")
        return 0 if same else 1
    if "--write" in argv:
        from ..io.report import write_text
        write_text(PATH, text)
        print(f"wrote {PATH}")
        return 0
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
