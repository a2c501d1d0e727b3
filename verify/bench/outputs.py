"""python -m verify.bench.outputs OUT [--tree CHECKOUT]: what garant writes for a fixed set of commands, every one
into OUT, so that a change meant to be only faster is shown to change nothing but the last digits of its numbers:
run it on the checkout before and after (`--tree`: another checkout, e.g. a `git worktree` of the commit before),
then `python -m verify.bench.outputs --compare OUT_BEFORE OUT_AFTER [--tolerance REL]`: which files differ, the
largest relative change of any number, and of every bound (a key naming a bound or a guaranteed error, not a ratio
to one: larger is looser) how many got tighter and looser and the largest loosening. It exits 1 when anything but
a number differs or a bound loosens by more than REL (default 1e-9, relative).

The inputs are made here from fixed seeds or taken from the repository and ../shared: distinct two-axis positions
(1e5, row generation and the interpolated remainder), a simulated session (next, diagnose), imucal's six-face
session (estimate, and calibrate-norm with the misalignments held by --bound), the real logs of ../shared as a
batch and for repeatability, a synthetic warm-up log with a temperature column (calibrate-norm plain, with an
effect, and over temperature with both flight-stack files), and a plan. The reproduce lines of the batch's pages
name OUT, so those two files are left out.
"""
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from . import distinct_positions
from .peer import G_LOGS, REAL

ROOT = Path(__file__).resolve().parents[2]
IMUCAL = ROOT / "tests" / "data" / "imucal"


def warm_up_log(path, seed=0, directions=36, still_s=10.0, move_s=2.0, rate=100, cool=False):
    """A csv log (time_s, ax, ay, az in m/s^2, temp_c) of still intervals in random directions joined by moves,
    read by (1.3) of 001 with errors within 2e-3, while the unit warms from 20 C towards 50 C (time constant
    300 s) and its biases drift by g (2e-5, -2e-5, 1.5e-5) per C; noise within 2e-5 g. `cool`: the unit heats to
    50 C and cools back to 20 C over the log (a half sine), so that its temperature's rate is no function of the
    temperature (warming alone, dT/dt = (50 C - T) / 300 s: a lag reads as the biases' temperature coefficient)."""
    from garant.generated import norm as N
    g = 9.81
    rng = np.random.default_rng(seed)
    truth = np.concatenate([rng.uniform(-2e-3, 2e-3, 9), np.zeros(7)])
    rows, now, total = [], 0.0, directions * (int(still_s * rate) + int(move_s * rate)) / rate
    for d in rng.normal(size=(directions, 3)):
        m = d / np.linalg.norm(d)
        for still, count in ((True, int(still_s * rate)), (False, int(move_s * rate))):
            for _ in range(count):
                temp = 20 + 30 * (np.sin(np.pi * now / total) if cool else 1 - np.exp(-now / 300))
                f = (g * N.readings(m, truth) + g * np.array([2e-5, -2e-5, 1.5e-5]) * (temp - 20)
                     + g * rng.uniform(-2e-5, 2e-5, 3)) if still else g * rng.normal(size=3)
                rows.append([now, *f, temp])
                now += 1 / rate
    np.savetxt(path, np.array(rows), delimiter=",", comments="", fmt="%.10g", header="time_s,ax,ay,az,temp_c")
    return path


def commands(out):
    """(name, argv) of every command, run in the folder of the inputs made here (d1e5.csv, sim.csv, warm.csv);
    each writes into out."""
    sessions = [str(REAL / f"repeat_session{k}_acc.txt") for k in (2, 3, 4)]
    warm, g = "warm.csv", "9.81"
    faces = [str(IMUCAL / "example_ferraris_session.csv"), "--format", "imucal"]
    return [
        ("estimate 1e5", ["estimate", "--model", "two-axis", "d1e5.csv", "--sigma", "1e-5",
                          "--json", f"{out}/estimate.json"]),
        ("next", ["next", "--model", "two-axis", "sim.csv", "--sigma", "1e-5", "--json",
                  f"{out}/next.json"]),
        ("diagnose", ["diagnose", "--model", "two-axis", "sim.csv", "--sigma", "1e-6", "--json",
                      f"{out}/diagnose.json"]),
        ("six faces", ["estimate", "--model", "six-face", *faces, "--sections",
                       str(IMUCAL / "example_ferraris_session_list.json"), "--sigma", "1e-3", "--json",
                       f"{out}/six_faces.json"]),
        ("batch", ["calibrate-norm", str(REAL / "repeat_session1_acc.txt"), *sessions,
                   str(REAL / "imu_tk_xsens_acc.txt"), "--g", str(G_LOGS), "--out", f"{out}/batch"]),
        ("warm-up", ["calibrate-norm", warm, "--g", g, "--json", f"{out}/warm.json"]),
        ("warm-up, effect", ["calibrate-norm", warm, "--g", g, "--effect", "bias_temperature", "--json",
                             f"{out}/warm_effect.json"]),
        ("warm-up, over T", ["calibrate-norm", warm, "--g", g, "--thermal-degree", "1", "--json",
                             f"{out}/warm_thermal.json", "--export-px4", f"{out}/px4.params", "--px4-device-id",
                             "42", "--export-ardupilot", f"{out}/ardupilot.parm"]),
        ("six faces held", ["calibrate-norm", *faces, "--rate", "102.4", "--bound", "alpha=1e-2", "--bound",
                            "beta=1e-2", "--bound", "gamma=1e-2", "--json", f"{out}/faces_held.json"]),
        ("repeatability", ["repeatability", *sessions, "--g", str(G_LOGS), "--json", f"{out}/repeatability.json"]),
        ("plan", ["plan", "--model", "single-axis", "--json", f"{out}/plan.json"]),
    ]


#: A number's key path names a bound when it has one of these words: larger is looser. Not a ratio to a bound (the
#: verdict's worst_over_bound: a smaller remainder makes it larger).
BOUND_WORDS = ("bound", "guaranteed_error", "error_bound")
RATIO_WORDS = ("over_bound",)
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _leaves(value, path=""):
    """(key path, leaf) of a JSON document, depth first."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _leaves(v, f"{path}/{k}")
    elif isinstance(value, list):
        for k, v in enumerate(value):
            yield from _leaves(v, f"{path}[{k}]")
    else:
        yield path, value


def _numbers(text):
    """(key path, leaf) of a text file: each line's numbers by position, the rest of the line as one leaf."""
    for k, line in enumerate(text.splitlines(), 1):
        head = line.split()[0] if line.split() else ""
        yield f"line {k} text", NUMBER.sub("#", line)
        for j, x in enumerate(NUMBER.findall(line)):
            yield f"line {k} ({head}) number {j + 1}", float(x)


def _read(path):
    """A file's leaves: a JSON document's, else a text file's (`_numbers`)."""
    text = path.read_text()
    try:
        return list(_leaves(json.loads(text)))
    except ValueError:
        return list(_numbers(text))


def _file_changes(a, b):
    """(numeric changes [(relative change, path, before, after)], other differences [path]) of two files."""
    if a.read_bytes() == b.read_bytes():
        return [], []
    try:
        left, right = _read(a), _read(b)
    except UnicodeDecodeError:
        return [], ["(binary)"]
    if [k for k, _ in left] != [k for k, _ in right]:
        return [], ["(the structure)"]
    numeric, other = [], []
    for (path, x), (_, y) in zip(left, right):
        if x == y:
            continue
        if isinstance(x, (int, float)) and isinstance(y, (int, float)) and not isinstance(x, bool):
            numeric.append(((y - x) / max(abs(x), abs(y)), path, x, y))
        else:
            other.append(path)
    return numeric, other


def compare(before, after, tolerance=1e-9):
    """The comparison `--compare` prints, as (lines, passed)."""
    before, after = Path(before), Path(after)
    names = sorted({p.relative_to(before) for p in before.rglob("*") if p.is_file()}
                   | {p.relative_to(after) for p in after.rglob("*") if p.is_file()})
    lines, numeric, passed, differ = [], [], True, 0
    for name in names:
        a, b = before / name, after / name
        if not (a.is_file() and b.is_file()):
            lines.append(f"{name}: only in {'the second' if b.is_file() else 'the first'} folder")
            passed = False
            continue
        changes, other = _file_changes(a, b)
        if changes or other:
            differ += 1
            worst = max((abs(c[0]) for c in changes), default=0.0)
            lines.append(f"{name}: {len(changes)} numbers changed (largest relative {worst:.1e})"
                         + (f"; not numbers: {', '.join(other[:3])}{' ...' if len(other) > 3 else ''}" if other
                            else ""))
            passed &= not other
            numeric += [(c, str(name)) for c in changes]
    bounds = [(c, name) for c, name in numeric if any(w in c[1].lower() for w in BOUND_WORDS)
              and not any(w in c[1].lower().rpartition("/")[2] for w in RATIO_WORDS)]
    looser = [(c, name) for c, name in bounds if c[0] > 0]
    largest = max(numeric, key=lambda x: abs(x[0][0]), default=None)
    loosest = max(looser, key=lambda x: x[0][0], default=None)
    lines.insert(0, f"{len(names)} files: {len(names) - differ} identical, {differ} differ" + (
        f"; largest relative change of a number {abs(largest[0][0]):.1e} ({largest[1]} {largest[0][1]})"
        if largest else ""))
    lines.insert(1, f"bounds: {len(bounds)} changed, {len(bounds) - len(looser)} tighter, {len(looser)} looser"
                 + (f", the largest loosening {loosest[0][0]:.1e} relative ({loosest[1]} {loosest[0][1]}: "
                    f"{loosest[0][2]!r} -> {loosest[0][3]!r})" if loosest else ""))
    if loosest and loosest[0][0] > tolerance:
        passed = False
        lines.append(f"a bound loosened by more than {tolerance:g} relative")
    return lines, passed


def main():
    """Make the inputs, run every command of `commands` with the checkout `--tree` (default this one) as
    `garant`, and leave their files in OUT."""
    args = sys.argv[1:]
    if args[:1] == ["--compare"] and (len(args) == 3 or len(args) == 5 and args[3] == "--tolerance"):
        lines, passed = compare(args[1], args[2], float(args[4]) if len(args) == 5 else 1e-9)
        print("\n".join(lines))
        raise SystemExit(0 if passed else 1)
    if not args or args[0].startswith("-"):
        raise SystemExit("usage: python -m verify.bench.outputs OUT [--tree CHECKOUT]\n"
                         "       python -m verify.bench.outputs --compare BEFORE AFTER [--tolerance REL]")
    out = Path(args[0]).resolve()
    tree = Path(args[args.index("--tree") + 1]).resolve() if "--tree" in args else ROOT
    if not (tree / "verify" / "cli" / "__init__.py").is_file():
        raise SystemExit(f"{tree}: not a garant checkout")
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        inputs = Path(tmp)
        (inputs / "pkg").mkdir()
        (inputs / "pkg" / "garant").symlink_to(tree)              # `import garant` is that checkout
        env = {**os.environ, "PYTHONPATH": str(inputs / "pkg"), "OPENBLAS_NUM_THREADS": "1"}
        garant = [sys.executable, "-c", "import sys; from garant.verify.cli import main; sys.exit(main())"]
        distinct_positions(100_000, inputs / "d1e5.csv")
        warm_up_log(inputs / "warm.csv")
        subprocess.run(garant + ["simulate", "--model", "two-axis", "--sigma", "1e-5", "--plan", "quarter16",
                                 "-o", "sim.csv"], env=env, cwd=inputs, check=True, capture_output=True)
        for name, argv in commands(out):          # the inputs made here by relative names: the same in every run
            code = subprocess.run(garant + argv, env=env, cwd=inputs, capture_output=True).returncode
            print(f"{name:18s} exit {code}")        # 3 (refuted) and 5 (a log proves nothing) write their files too
    for page in ("index.html", "report.md"):                  # they name OUT in their reproduce line
        (out / "batch" / page).unlink(missing_ok=True)
    print(f"wrote {out} (from {tree}); compare two such folders with --compare BEFORE AFTER")


if __name__ == "__main__":
    main()
