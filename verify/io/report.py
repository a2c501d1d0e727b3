"""Plain-text tables and JSON files for the command line; every file is written whole or not at all."""
import json
import os
import sys
import tempfile
from pathlib import Path

from ..errors import DataError
from . import files


def table(headers, rows, out=None):
    """Print rows under headers, columns padded to their widest cell (to stdout unless `out`)."""
    out = out or sys.stdout
    cells = [[str(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) if cells else len(h) for i, h in enumerate(headers)]
    line = "  ".join(h.ljust(w) for h, w in zip(headers, widths))
    print(line, file=out)
    print("  ".join("-" * w for w in widths), file=out)
    for r in cells:
        print("  ".join(c.ljust(w) for c, w in zip(r, widths)), file=out)


def human(value, unit, bias=False):
    """A value in the unit an engineer reads at a glance, beside SI: a dimensionless scale factor or
    misalignment in ppm, an angle in mrad or urad, a bias (over g, or in m/s^2) in mg or ug."""
    if bias:
        mg = value * 1e3 if unit == "1" else value / 9.80665 * 1e3
        return f"{mg:+.4g} mg" if abs(mg) >= 1 else f"{mg * 1e3:+.4g} ug"
    if unit == "rad":
        return f"{value * 1e3:+.4g} mrad" if abs(value) >= 1e-3 else f"{value * 1e6:+.4g} urad"
    if unit == "1":
        return f"{value * 1e6:+.4g} ppm"
    return f"{value:+.4g} {unit}"


def write_json(path, obj):
    """Strict JSON (no NaN or Infinity), written atomically."""
    try:
        text = json.dumps(obj, indent=2, allow_nan=False, default=json_value) + "\n"
    except ValueError:
        raise DataError(f"{path}: a result is not finite (NaN or infinity); nothing written") from None
    write_text(path, text)


def json_value(x):
    """numpy arrays and numbers in a result become JSON lists and numbers (converted only when written)."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"{type(x).__name__} is not JSON serialisable")


def _umask():
    """The process's umask (read by setting it, then restoring it)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path, text, mode="w"):
    """Write a file atomically: a temporary file beside it, renamed over it when complete. The file gets
    the permissions open() would give it (0666 less the umask), not the temporary file's 0600."""
    write_chunks(path, [text], mode)


def write_chunks(path, chunks, mode="wb"):
    """Write the pieces `chunks` yields (text or bytes, as `mode` says) into one file, atomically as
    write_text: a large output is made piece by piece, never whole in memory."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent or ".", prefix=f".{path.name}.", suffix=".part")
    try:
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, mode) as fh:
            for chunk in chunks:
                fh.write(chunk)
        files.refuse_input(path)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def save_figure(fig, path):
    """A matplotlib figure as PNG, written atomically."""
    import io
    buf = io.BytesIO()
    fig.savefig(buf, dpi=110, format="png")
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


def write_page(folder, title, command, sections):
    """DIR/report.md: the title, the command that reproduces it, then (heading, Markdown) sections."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    text = [f"# {title}", "", "Reproduce with:", "", "```sh", command, "```", ""]
    for heading, body in sections:
        text += [f"## {heading}", "", body, ""]
    write_text(folder / "report.md", "\n".join(text))
    return folder / "report.md"
