"""Plain-text tables and JSON files for the command line; every file is written whole or not at all."""
import json
import math
import sys
from pathlib import Path

from ..errors import DataError
from . import files


#: The widest line a table prints (the command line wraps its prose at the same width).
WIDTH = 100


def table(headers, rows, out=None, width=WIDTH):
    """Print rows under headers, columns padded to their widest cell (to stdout unless `out`). A table wider
    than `width` is printed as several, one under the other, each repeating the first column (the row's name)
    with as many of the others as fit."""
    out = out or sys.stdout
    cells = [[str(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) if cells else len(h) for i, h in enumerate(headers)]
    groups, group = [], []
    for i in range(1, len(headers)):
        if group and widths[0] + sum(widths[j] + 2 for j in group) + widths[i] + 2 > width:
            groups.append(group)
            group = []
        group.append(i)
    groups.append(group)
    for k, group in enumerate(groups):
        cols = [0, *group]
        if k:
            print(file=out)
        print("  ".join(headers[i].ljust(widths[i]) for i in cols).rstrip(), file=out)
        print("  ".join("-" * widths[i] for i in cols), file=out)
        for r in cells:
            print("  ".join(r[i].ljust(widths[i]) for i in cols).rstrip(), file=out)


def human(value, unit, bias=False, fixed=False):
    """A value in the unit an engineer reads at a glance, beside SI: a dimensionless scale factor or
    misalignment in % (from 0.1 %) or ppm, an angle in mrad or urad, a bias (over g, or in m/s^2) in mg or ug.
    `fixed`: one unit per kind whatever the size (ppm, mrad, mg; four significant digits, no exponent), for a
    table column that should not mix units."""
    if fixed:
        scaled, name = ((value * 1e3 if unit == "1" else value / 9.80665 * 1e3, "mg") if bias else
                        (value * 1e3, "mrad") if unit == "rad" else (value * 1e6, "ppm") if unit == "1" else
                        (value, unit))
        digits = 0 if scaled == 0 else max(0, 3 - int(math.floor(math.log10(abs(scaled)))))
        return f"{scaled:+.{digits}f} {name}"
    if bias:
        mg = value * 1e3 if unit == "1" else value / 9.80665 * 1e3
        return f"{mg:+.4g} mg" if abs(mg) >= 1 else f"{mg * 1e3:+.4g} ug"
    if unit == "rad":
        return f"{value * 1e3:+.4g} mrad" if abs(value) >= 1e-3 else f"{value * 1e6:+.4g} urad"
    if unit == "1":                                    # 1.2 %, 120 ppm: never 1.2e+04 ppm
        return f"{value * 100:+.3g} %" if abs(value) >= 1e-3 else f"{value * 1e6:+.3g} ppm"
    return f"{value:+.4g} {unit}"


def write_json(path, obj):
    """Strict JSON (no NaN or Infinity), written atomically."""
    try:
        text = json.dumps(obj, indent=2, allow_nan=False, default=json_value) + "\n"
    except ValueError:
        raise DataError(f"{path}: a result is not finite (NaN or infinity); nothing written", param="json") from None
    write_text(path, text)


def json_value(x):
    """numpy arrays and numbers in a result become JSON lists and numbers (converted only when written)."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"{type(x).__name__} is not JSON serialisable")


def write_text(path, text, mode="w"):
    """Write a file whole or not at all (io/files.py: beside it, then renamed; never through a link)."""
    files.write(path, [text], mode)


def write_chunks(path, chunks, mode="wb"):
    """Write the pieces `chunks` yields into one file, as write_text: a large output is made piece by
    piece, never whole in memory."""
    files.write(path, chunks, mode)


def write_files(texts):
    """Write {path: text} (a generated module and its report), each folder made and each file written as
    write_text; returns the paths, sorted."""
    for path, text in texts.items():
        files.make_folder(Path(path).parent)
        write_text(path, text)
    return sorted(texts)


#: The formats a figure is written in, by the file name's suffix.
FIGURE_FORMATS = ("png", "svg", "pdf")


def figure_format(path, what="--plot"):
    """The format of a figure file by its name's suffix, or a one-line refusal (before any work)."""
    suffix = Path(str(path)).suffix.lower().lstrip(".")
    if suffix not in FIGURE_FORMATS:
        raise DataError(f"{what} {str(path)[:80]}: name the file .png, .svg or .pdf (the format it is written in)",
                        param=what.lstrip("-").replace("-", "_"))
    return suffix


def save_figure(fig, path):
    """A matplotlib figure in the format its name says (png, svg, pdf), written atomically."""
    import io
    buf = io.BytesIO()
    import matplotlib
    fmt = figure_format(path)
    with matplotlib.rc_context({"svg.hashsalt": "garant"}):        # the same ids in every run: same input, same file
        fig.savefig(buf, dpi=110, format=fmt, metadata={"svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(fmt))
    write_text(path, buf.getvalue(), "wb")


def check_writable(path, what):
    """Refuse an output path before any work (io/files.py: not an input, a folder, a device or a FIFO; its
    folder exists and is writable)."""
    files.check_outputs([(path, what, "file")])


def markdown_table(headers, rows):
    """A Markdown table of rows under headers."""
    out = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    out += ["| " + " | ".join(str(c).replace("|", "\\|") for c in r) + " |" for r in rows]
    return "\n".join(out)


class Table(tuple):
    """A section's table: (headers, rows), rendered as Markdown or HTML by write_page."""

    def __new__(cls, headers, rows):
        """The headers and the rows, each a tuple."""
        return super().__new__(cls, (tuple(headers), [tuple(r) for r in rows]))


class Link(str):
    """A table cell that links to a file beside the page (a unit's calibration file): its text and `href`."""

    def __new__(cls, text, href):
        """The text shown and the relative path it links to."""
        out = super().__new__(cls, text)
        out.href = href
        return out


class Verdict(str):
    """A table cell holding a verdict (pass, fail, undecided, retest), coloured by it on the page."""


class Image(str):
    """A section's plot: the name of a PNG file in the report's folder."""


class Bullets(tuple):
    """A section's list: one item a line (a premise a line), rendered as a Markdown or HTML list."""


def clauses(text):
    """`text` cut at each "; " outside parentheses: the premises of a printed guarantee, one a line."""
    out, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += (ch == "(") - (ch == ")")
        if depth == 0 and text.startswith("; ", i):
            out.append(text[start:i])
            start = i + 2
    return [x.strip() for x in out + [text[start:]] if x.strip()]


def write_page(folder, title, command, sections, inputs=()):
    """DIR/report.md and DIR/index.html: the title, the command that reproduces it, then (heading, body)
    sections, a body being text (with **bold**), a Table or an Image; the HTML is one self-contained file
    (plots embedded, no request to the network, A4 print styles) that also states garant's version and
    the SHA-256 of each input file. Returns the path of index.html."""
    folder = files.make_folder(folder)
    write_text(folder / "report.md", markdown_page(title, command, sections))
    write_text(folder / "index.html", _html(folder, title, command, sections, inputs))
    return folder / "index.html"


def markdown_page(title, command, sections):
    """The page of write_page as Markdown: the title, the command that reproduces it, the sections."""
    text = [f"# {title}", "", "Reproduce with:", "", "```sh", command, "```", ""]
    for heading, body in sections:
        text += [f"## {heading}", "", _markdown(body), ""]
    return "\n".join(text)


def command_line(args, fallback):
    """The command that reproduces a result: the argument list `garant` was given (shell-quoted), or
    `fallback` when the work was not started from the command line."""
    import shlex
    argv = getattr(args, "argv", None)
    return "garant " + shlex.join(argv) if argv else fallback


def _markdown(body):
    if isinstance(body, Table):
        headers, rows = body
        return markdown_table(headers, [[f"[{c}]({c.href})" if isinstance(c, Link) else
                                         f"**{c}**" if isinstance(c, Verdict) and c else c for c in r] for r in rows])
    if isinstance(body, Image):
        return f"![{Path(body).stem}]({body})"
    if isinstance(body, Bullets):
        return "\n".join(f"- {x}" for x in body)
    return body


HTML_STYLE = """body{font-family:sans-serif;max-width:60em;margin:1em auto;padding:0 1em;color:#111}
table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0}th,td{border:1px solid #999;padding:2px 6px;
text-align:left}th{background:#eee}img{max-width:100%}pre{background:#f4f4f4;padding:0.5em;white-space:pre-wrap}
@page{size:A4;margin:15mm}@media print{body{max-width:none;margin:0}h2{break-after:avoid}
table,img{break-inside:avoid}}td.v-pass{background:#c8efc8}td.v-fail{background:#f6c6c6}
td.v-undecided{background:#fbeab0}td.v-retest{background:#ddd}"""


def _cell(c):
    """One table cell as HTML: escaped text, a link to a file beside the page, or a verdict in its colour."""
    from html import escape
    if isinstance(c, Link):
        return f'<td><a href="{escape(c.href)}">{escape(str(c))}</a></td>'
    if isinstance(c, Verdict) and c:
        return f'<td class="v-{escape(str(c))}"><strong>{escape(str(c))}</strong></td>'
    return f"<td>{escape(str(c))}</td>"


def _html(folder, title, command, sections, inputs):
    """The report as one HTML page: every string escaped, plots as data: URIs."""
    import base64
    import hashlib
    import re
    from html import escape

    from ... import __version__
    bold = (lambda t: re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", escape(t)))      # noqa: E731
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">', f"<title>{escape(title)}</title>",
           f"<style>{HTML_STYLE}</style></head><body>", f"<h1>{escape(title)}</h1>",
           f"<p>Reproduce with:</p><pre>{escape(command)}</pre>"]
    for heading, body in sections:
        out.append(f"<h2>{escape(heading)}</h2>")
        if isinstance(body, Table):
            headers, rows = body
            out.append("<table><tr>" + "".join(f"<th>{escape(str(h))}</th>" for h in headers) + "</tr>"
                       + "".join("<tr>" + "".join(_cell(c) for c in r) + "</tr>" for r in rows)
                       + "</table>")
        elif isinstance(body, Image):
            data = base64.b64encode(files.written(folder / body)).decode()
            out.append(f'<img alt="{escape(Path(body).stem)}" src="data:image/png;base64,{data}">')
        elif isinstance(body, Bullets):
            out.append("<ul>" + "".join(f"<li>{bold(x)}</li>" for x in body) + "</ul>")
        else:
            out.append(f"<p>{bold(body)}</p>")
    digests = [(p, hashlib.sha256(Path(p).read_bytes()).hexdigest()) for p in inputs if Path(p).is_file()]
    out.append(f"<h2>Provenance</h2><p>garant {escape(__version__)}</p>"
               + ("<table><tr><th>input</th><th>SHA-256</th></tr>" + "".join(
                   f"<tr><td>{escape(str(p))}</td><td><code>{h}</code></td></tr>" for p, h in digests) + "</table>"
                  if digests else ""))
    out.append("</body></html>")
    return "\n".join(out) + "\n"
