"""python -m verify.bench.outputs OUT [--tree CHECKOUT]: what garant writes for a fixed set of commands, every one
into OUT, so that a change meant to be only faster is shown to change no byte: run it on the checkout before and
after (`--tree`: another checkout, e.g. a `git worktree` of the commit before), then `diff -r OUT_BEFORE OUT_AFTER`.

The inputs are made here from fixed seeds or taken from the repository and ../shared: distinct two-axis positions
(1e5, row generation and the interpolated remainder), a simulated session (next, diagnose), imucal's six-face
session (estimate, and calibrate-norm with the misalignments held by --bound), the real logs of ../shared as a
batch and for repeatability, a synthetic warm-up log with a temperature column (calibrate-norm plain, with an
effect, and over temperature with both flight-stack files), and a plan. The reproduce lines of the batch's pages
name OUT, so those two files are left out.
"""
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from . import distinct_positions
from .peer import G_LOGS, REAL

ROOT = Path(__file__).resolve().parents[2]
IMUCAL = ROOT / "tests" / "data" / "imucal"


def warm_up_log(path, seed=0, directions=36, still_s=10.0, move_s=2.0, rate=100):
    """A csv log (time_s, ax, ay, az in m/s^2, temp_c) of still intervals in random directions joined by moves,
    read by (1.3) of 001 with errors within 2e-3, while the unit warms from 20 C towards 50 C (time constant
    300 s) and its biases drift by g (2e-5, -2e-5, 1.5e-5) per C; noise within 2e-5 g."""
    from garant.generated import norm as N
    g = 9.81
    rng = np.random.default_rng(seed)
    truth = np.concatenate([rng.uniform(-2e-3, 2e-3, 9), np.zeros(7)])
    rows, now = [], 0.0
    for d in rng.normal(size=(directions, 3)):
        m = d / np.linalg.norm(d)
        for still, count in ((True, int(still_s * rate)), (False, int(move_s * rate))):
            for _ in range(count):
                temp = 20 + 30 * (1 - np.exp(-now / 300))
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


def main():
    """Make the inputs, run every command of `commands` with the checkout `--tree` (default this one) as
    `garant`, and leave their files in OUT."""
    args = sys.argv[1:]
    if not args or args[0].startswith("-"):
        raise SystemExit("usage: python -m verify.bench.outputs OUT [--tree CHECKOUT]")
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
    print(f"wrote {out} (from {tree}); compare two such folders with diff -r")


if __name__ == "__main__":
    main()
