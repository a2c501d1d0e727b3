"""The `garant` command: one module per subcommand (`add` its arguments, `run` it), one-line errors.

A command module imports what its work needs inside `run`, so `garant --help` and a light command do
not pay for SymPy, cvxpy or matplotlib.
"""
import argparse
import contextlib
import importlib
import os
import re
import signal
import sys
import warnings

# One BLAS thread for the command: its least-squares fits are thin (3N x 15), where threads cost more CPU
# than they save (estimate on 10,000 positions: 0.70-0.80 s of CPU instead of 1.26-1.42 s, the same wall
# time). Set before numpy loads (no command module imports it before this line); a user's setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

from ..errors import DataError, LPFailed
from ..outcomes import Exit
from . import exports

#: The subcommands, in the order of `garant --help`: command name -> its module.
COMMANDS = {"verify": "verify", "plan": "plan", "next": "next", "estimate": "estimate",
            "calibrate-norm": "calibrate_norm",
            "repeatability": "repeatability", "apply": "apply", "budget": "budget", "identify": "identify",
            "derive": "derive",
            "simulate": "simulate", "diagnose": "diagnose", "check-certificate": "check_certificate"}
#: Output options of the commands: (attribute, what it is, a file or a folder); the exports' are in exports.py.
OUTPUTS = (("json", "the JSON output", "file"), ("plot", "the plot", "file"), ("output", "the data file", "file"),
           ("report", "the report folder", "folder"), ("certificates", "the certificate folder", "folder"),
           ("out", "the output folder", "folder"),
           ("markdown", "the Markdown file", "file"), ("thermal_plot", "the thermal plot", "file"))

class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: `garant: error: ...` and exit status 2."""

    def error(self, message):
        """One line on stderr naming the problem, the close name meant where there is one, and --help; exit 2."""
        self.exit(2, f"{self.prog}: error: {message}{_did_you_mean(self, message)} (see {self.prog} --help)\n")

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)


class _Formatter(argparse.HelpFormatter):
    """--help at most WIDTH columns wide, or a narrower terminal's width (argparse alone takes any terminal's)."""

    def __init__(self, prog, **kwargs):
        import shutil
        kwargs.setdefault("width", min(WIDTH, shutil.get_terminal_size((WIDTH, 24)).columns) - 2)
        super().__init__(prog, **kwargs)


def _did_you_mean(p, message):
    """"; did you mean X?" for a mistyped command or option: the closest of the parser's own names."""
    import difflib
    m = re.match(r"argument \S+: invalid choice: '([^']*)'", message) or re.match(
        r"unrecognized arguments: (--?[\w-]+)", message)
    if not m:
        return ""
    names = [name for a in p._actions for name in a.option_strings]
    for a in p._actions:
        for sub in (a.choices or {}).values() if isinstance(a, argparse._SubParsersAction) else ():
            names += [name for b in sub._actions for name in b.option_strings]
        names += list(a.choices) if isinstance(a, argparse._SubParsersAction) else []
    close = difflib.get_close_matches(m.group(1).split("=")[0], names, n=1, cutoff=0.6)
    return f"; did you mean {close[0]}?" if close else ""


def parser(only=None):
    """The argument parser: every subcommand, or only the one named (its module alone is imported)."""
    from garant import __version__
    ap = _Parser(prog="garant", description="Guaranteed calibration of accelerometer blocks.")
    ap.add_argument("--version", action="version", version=f"garant {__version__}")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in ([only] if only in COMMANDS else COMMANDS):
        command = importlib.import_module(f".{COMMANDS[name]}", __name__)
        p = command.add(sub)
        _in_order(p)
        p.set_defaults(run=command.run)
    return ap


#: The one order of options in every command's --help and usage: its inputs, the model, how the inputs are read,
#: the noise bound, g and the premises, then the command's own options, then what it writes and the calibration
#: files (each export's own options after it).
ORDER = (("--model",), ("--format", "--sensor", "--imu", "--run", "--sections", "--rate"),
         ("--sigma", "--delta-sigma", "--g", "--g-uncertainty", "--bound", "--prior"), (),
         ("--units", "--json", "--plot", "--thermal-plot", "--markdown", "--report", "--output", "--out",
          "--certificates"))


def _in_order(p):
    """The parser's options sorted into ORDER (stable: a group keeps the order its command added them in)."""
    rank = {flag: (g, i) for g, flags in enumerate(ORDER) for i, flag in enumerate(flags)}
    export = {}
    for k, e in enumerate(exports.EXPORTS):
        for j, flag in enumerate([e.option, *(f[0] for f, _ in e.options)]):
            export[flag] = (len(ORDER), 100 * k + j)

    def key(action):
        if not action.option_strings:
            return (-1, 0)                           # positionals first, as given
        if "-h" in action.option_strings:
            return (-2, 0)
        flag = action.option_strings[-1]
        return rank.get(flag) or export.get(flag) or (ORDER.index(()), 0)
    p._actions.sort(key=key)
    for group in p._action_groups:
        group._group_actions.sort(key=key)


def main(argv=None):
    """`garant`: parse, run the command, and turn a DataError into one line and a non-zero exit."""
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser(argv[0] if argv else None).parse_args(argv)
    warnings.simplefilter("ignore", RuntimeWarning)     # inputs are checked; a failure is one line
    if hasattr(signal, "SIGXFSZ"):                     # `ulimit -f`: a write fails (one line), not the process
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    from ..io import files
    try:
        _check_paths(args)
        args.argv = argv                               # the command line, for the reports that reproduce it
        with files.staged(), _reader_may_stop():       # every output placed only if the command succeeds
            return args.run(args)
    except LPFailed as e:
        print(f"garant: error: {_plain(e)}", file=sys.stderr)
        return Exit.BAD_INPUT
    except DataError as e:
        print(f"garant: error: {e}", file=sys.stderr)
        return Exit.BAD_INPUT
    except (ValueError, ArithmeticError, IndexError, KeyError, TypeError) as e:   # not the input: garant's own
        print(f"garant: internal error: {type(e).__name__}: {str(e)[:300]} (not a problem with the input; please "
              "report it with the command line)", file=sys.stderr)
        return Exit.FAILED
    except MemoryError:
        print("garant: error: out of memory: the inputs are too large for this machine (see the size limits in "
              "docs/formats.md)", file=sys.stderr)
        return Exit.BAD_INPUT
    except KeyboardInterrupt:                          # Ctrl-C: outputs are written atomically, none half
        print("garant: interrupted; no output was written after the interruption", file=sys.stderr)
        return Exit.INTERRUPTED
    except BrokenPipeError:                            # (flushing at exit, after the command)
        sys.stderr.close()
        return Exit.OK
    except OSError as e:
        print(f"garant: error: {(e.filename or 'a file') if e.strerror else ''}: {e.strerror or e}", file=sys.stderr)
        return Exit.BAD_INPUT
    finally:
        files.check_inputs([])                         # the API after a command protects nothing stale


from ..io.report import WIDTH  # noqa: E402  (the widest line printed; narrower terminals wrap at their own width)


#: A line that ends in a command to run (`add them: garant calibrate-norm ...`): wrapped with the shell's " \\"
#: continuation, so it still runs when pasted.
_COMMAND = re.compile(r"^\s*(?:[\w ,()-]+: )?garant [a-z-]+ ")


def wrap(text, width=WIDTH):
    """Each line of `text` longer than `width` wrapped at spaces, its continuation indented two columns (a command
    to run: with a backslash at each break, four columns; a word longer than the width, a path, is left whole)."""
    import textwrap
    out = []
    for line in text.split("\n"):
        if len(line) <= width or not line.strip(" -"):      # a table's rule is cut to the width
            out.append(line[:width])
            continue
        indent = len(line) - len(line.lstrip(" "))
        command = bool(_COMMAND.match(line))
        if command:                                      # never break inside a shell-quoted word ('my log.csv')
            line = re.sub(r"'[^']*'", lambda m: m.group(0).replace(" ", "\0"), line)
        parts = textwrap.wrap(line, width - 2 * command, subsequent_indent=" " * (indent + 2 + 2 * command),
                              break_long_words=False, break_on_hyphens=False, drop_whitespace=True)
        out.append((" \\\n" if command else "\n").join(parts).replace("\0", " "))
    return "\n".join(out)


class _Output:
    """Standard output that wraps each line at WIDTH columns (or a narrower terminal's width), on a terminal and
    into a file or a pipe alike (people keep logs with `tee`), and, once its reader stops (`garant ... | head`),
    drops what is printed after: the command still finishes its work and writes its files. What is for programs
    (JSON, CSV) goes to files, or through `buffer` (apply -o -), never wrapped."""

    def __init__(self, stream):
        import shutil
        self.stream, self.stopped, self.pending = stream, False, ""
        tty = getattr(stream, "isatty", lambda: False)()
        self.width = min(WIDTH, shutil.get_terminal_size((WIDTH, 24)).columns) if tty else WIDTH

    def write(self, text):
        """Write to the stream, wrapped, while its reader reads; afterwards, drop the text."""
        whole, _, self.pending = (self.pending + text).rpartition("\n")
        if not whole and "\n" not in text:                # a partial line waits for its end
            return len(text)
        text = wrap(whole, self.width) + "\n"
        if not self.stopped:
            try:
                self.stream.write(text)
            except BrokenPipeError:
                self.stopped = True
        return len(text)

    def flush(self):
        """Flush while the reader reads (a partial line waits for its end on a terminal)."""
        if not self.stopped:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self.stopped = True

    def __getattr__(self, name):
        return getattr(self.stream, name)


@contextlib.contextmanager
def _reader_may_stop():
    """sys.stdout as _Output for the command; a stopped reader's pipe closed quietly at the end."""
    out = sys.stdout = _Output(sys.stdout)
    try:
        yield
    finally:
        if out.pending and not out.stopped:
            out.stream.write(wrap(out.pending, out.width))
        sys.stdout = out.stream
        if out.stopped:                                # no flush of what the reader will never read
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _plain(e):
    """A solver failure said in the user's terms: what it means for the stand or the plan."""
    text = str(e)
    what = text.split(":", 1)[0]
    if "unbounded" in e.status or "infeasible" in e.status:
        return (f"{what}: the positions cannot estimate every combination q (no unbiased estimator exists on "
                "them); add positions (garant identify --model STAND --plan PLAN.csv says which q are missing)")
    return f"{what}: the linear program did not reach an optimum ({text.split(':', 1)[-1].strip()}); " \
           "check the positions and the noise bound for extreme values"


def _check_paths(args):
    """Every input and output path before any work (io/files.py): inputs are regular files, outputs
    never replace an input or each other, so a command that fails writes nothing."""
    from ..io import files
    outputs = OUTPUTS + exports.outputs()
    out_attrs = {attr for attr, _, _ in outputs}
    inputs = []
    for attr, value in vars(args).items():
        if attr in out_attrs:
            continue
        for v in (value if isinstance(value, list) else [value]):
            if isinstance(v, str) and v != "-":
                inputs.append((v, attr))
    files.check_inputs(inputs)
    files.check_outputs([(getattr(args, attr), what, kind, attr) for attr, what, kind in outputs
                         if getattr(args, attr, None) is not None])
    from ..io.report import figure_format
    for attr in ("plot", "thermal_plot"):
        if getattr(args, attr, None):
            figure_format(getattr(args, attr), "--" + attr.replace("_", "-"))


if __name__ == "__main__":
    sys.exit(main())
