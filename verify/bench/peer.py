"""python -m verify.bench.peer: `garant calibrate-norm` against the real imu_tk (C++, Ceres), side by side.

imu_tk is the peer a user would pick instead: its accelerometer multi-position calibration, built from
its own source (`../shared/peers/imu_tk/build.sh`; `.ci/run` builds a copy into `.venv/peers/imu_tk/`; or the
IMU_TK_ACC environment variable naming the binary). Both run as fresh processes on the same log, alternately,
REPEAT times each; the figures are the medians of CPU seconds (user + system of the child), wall seconds and
peak memory (ru_maxrss of the child). Then the parameters: imu_tk's biases and scale factors against garant's
estimates and guaranteed bounds (imu_tk's misalignments are upper-triangular, garant's lower: not comparable
one by one).
"""
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared"
REAL = SHARED / "data" / "real"
REPEAT = 5
G_LOGS = 9.81744            # the local gravity the repeat sessions and the Xsens sample were recorded under
#: Real logs: (file, imu_tk's initial bias guess in raw units: 0 for m/s^2, mid-scale for 16-bit counts).
LOGS = (("repeat_session1_acc.txt", 0), ("repeat_session2_acc.txt", 0), ("repeat_session3_acc.txt", 0),
        ("repeat_session4_acc.txt", 0), ("imu_tk_xsens_acc.txt", 32768))


def imu_tk_binary():
    """The imu_tk_acc binary, or None when it is not built."""
    for p in (os.environ.get("IMU_TK_ACC"), SHARED / "peers" / "imu_tk" / "imu_tk_acc",
              ROOT / ".venv" / "peers" / "imu_tk" / "imu_tk_acc"):
        if p and Path(p).is_file() and os.access(p, os.X_OK):
            return str(p)
    return None


def measured(cmd, env=None):
    """(CPU s, wall s, peak MiB, stdout, exit status) of one run of cmd as a child process. CPU from
    wait4 (the child and what it waited for); the peak from GNU time's %M (ru_maxrss of a fresh child
    would report this large process's own peak)."""
    with tempfile.NamedTemporaryFile("r") as peak:
        t0 = time.perf_counter()
        p = subprocess.Popen(["/usr/bin/time", "-f", "%M", "-o", peak.name, *cmd], stdout=subprocess.PIPE,
                             stderr=subprocess.DEVNULL, text=True, env=env)
        out = p.stdout.read()
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        kib = float((peak.read().split() or ["nan"])[-1])
    return ru.ru_utime + ru.ru_stime, wall, kib / 1024, out, os.waitstatus_to_exitcode(status)


def side_by_side(log, bias0, binary, json_path):
    """Alternate runs of both: medians of (CPU, wall, MiB) per side, imu_tk's printed result, garant's JSON."""
    garant = [str(Path(sys.executable).with_name("garant")), "calibrate-norm", str(log), "--g", str(G_LOGS),
              "--json", json_path]
    peer = [binary, str(log), str(G_LOGS), "5", *[str(bias0)] * 3]
    runs = {"garant": [], "imu_tk": []}
    out = {}
    for _ in range(REPEAT):
        for name, cmd in (("garant", garant), ("imu_tk", peer)):
            cpu, wall, mib, text, code = measured(cmd)
            runs[name].append((cpu, wall, mib))
            out[name] = (text, code)
    med = {k: tuple(float(np.median([r[i] for r in v])) for i in range(3)) for k, v in runs.items()}
    return med, out


def imu_tk_result(text):
    """imu_tk's nine parameters from its RESULT line, or None when it reported failure."""
    line = next((t for t in text.splitlines() if t.startswith("RESULT")), None)
    ok = next((t for t in text.splitlines() if t.startswith("samples")), "")
    if line is None or " ok 1 " not in ok + " ":
        return None
    parts = line.split()[1:]
    return dict(zip(parts[::2], map(float, parts[1::2])))


def compare(peer, res):
    """imu_tk's biases (raw units) and scale factors against garant's, in units of garant's bound.

    Biases: b is the same raw-axis offset in both conventions. Scale: imu_tk's s_j against the norm of
    garant's column M e_j (the rotation between the lower- and upper-triangular frames keeps column
    norms). To first order (the misalignments squared, 1e-6 here, aside): the column norm's bound is
    |M e_j| times that of lambda_j; the bias's is g times that of eps_j/g for a log in m/s^2 (whose bounds
    are given relative to the raw axes), and |M^-1| g e_eps for a log in counts (whose bounds are those
    of the calibrated block's parameters)."""
    M, b = np.array(res["matrix"]), np.array(res["bias"])
    err = res["guaranteed_error"]
    e_eps = G_LOGS * np.array([err[f"eps{j + 1}/g"] for j in range(3)])
    bias_bound = e_eps if res["raw_unit"] == "m/s^2" else np.abs(np.linalg.inv(M)) @ e_eps
    rows = []
    for j, ax in enumerate("XYZ"):
        norm = np.linalg.norm(M[:, j])
        rows.append((f"b{ax} (raw units)", peer[f"b{ax}"], b[j], bias_bound[j]))
        rows.append((f"s{ax}", peer[f"s{ax}"], norm, norm * err[f"lambda{j + 1}"]))
    return rows


BATCH_COPIES = 10          # the production line: 10 copies of each of repeat sessions 2-4, 30 logs


def batch(binary, repeat=3):
    """The production line: 30 logs (BATCH_COPIES copies of repeat sessions 2-4) in one `garant calibrate-norm
    LOG... --out DIR` (every core, then --jobs 1) against imu_tk run once per log, alternately, `repeat` times;
    medians of CPU (user + system, the pool's workers included) and wall seconds, and whether --jobs 1 and
    the default write the same files."""
    import filecmp
    import shutil
    with tempfile.TemporaryDirectory() as tmp:
        logs = _batch_logs(tmp)
        garant = str(Path(sys.executable).with_name("garant"))
        runs = {"garant, every core": [], "garant --jobs 1": [], "imu_tk, once per log": []}
        for _ in range(repeat):
            for name in runs:
                out = Path(tmp) / name.split(",")[0].replace(" ", "")
                shutil.rmtree(out, ignore_errors=True)
                if name.startswith("imu_tk"):
                    each = [measured([binary, str(log), str(G_LOGS), "5", "0", "0", "0"]) for log in logs]
                    runs[name].append((sum(r[0] for r in each), sum(r[1] for r in each)))
                    continue
                jobs = ["--jobs", "1"] if "jobs" in name else []
                cpu, wall, _, _, code = measured([garant, "calibrate-norm", *map(str, logs), "--g", str(G_LOGS),
                                                  "--out", str(out), *jobs])
                if code != 0:
                    raise SystemExit(f"garant calibrate-norm on the batch exited with {code}")
                runs[name].append((cpu, wall))
        a, b = Path(tmp) / "garant", Path(tmp) / "garant--jobs1"
        files = sorted(p.name for p in a.iterdir())
        same = all(filecmp.cmp(a / f, b / f, shallow=False) for f in files if f.endswith((".json", ".csv")))
    med = {k: (float(np.median([r[0] for r in v])), float(np.median([r[1] for r in v]))) for k, v in runs.items()}
    peer_cpu = med["imu_tk, once per log"][0] / len(logs)
    print(f"\nThe production line: {len(logs)} logs ({BATCH_COPIES} copies of repeat sessions 2-4), medians of "
          f"{repeat} "
          f"alternating runs; CPU includes the pool's workers")
    print(f"{'run':24s} {'CPU s':>7s} {'wall s':>7s} {'CPU s per log':>14s} {'/ imu_tk':>9s}")
    for name, (cpu, wall) in med.items():
        print(f"{name:24s} {cpu:7.2f} {wall:7.2f} {cpu / len(logs):14.4f} {cpu / len(logs) / peer_cpu:9.2f}")
    print(f"--jobs 1 and every core wrote the same calibrations and summary.csv: {'yes' if same else 'NO'}")
    return med, same


def _batch_logs(tmp):
    """The production line's 30 logs in the folder tmp: BATCH_COPIES copies of repeat sessions 2-4."""
    import shutil
    logs = []
    for copy in range(BATCH_COPIES):
        for k in (2, 3, 4):
            logs.append(Path(tmp) / f"unit{copy:02d}_session{k}.txt")
            shutil.copyfile(REAL / f"repeat_session{k}_acc.txt", logs[-1])
    return logs


def profile():
    """Where the production line's CPU goes: its 30 logs calibrated in this process (`--jobs 1`), once to load
    every module, then again with HiGHS's solves, the logs' reading and their still intervals timed apart (CPU of
    this process), and the LP ends a rejected premise box did not solve (hull.Beyond: it stops at its first end
    proven past the box)."""
    import contextlib
    import io
    from garant.verify.cli import main as garant         # the installed package's modules, as the command runs them
    from garant.verify.io import recordings
    from garant.verify.solve import highs, hull
    from garant.verify.workflows import stills
    spent, count = {"solves": 0.0, "read": 0.0, "still": 0.0}, {"solves": 0, "unsolved": 0}

    def timing(owner, name, key):
        inner = getattr(owner, name)

        def timed_call(*a, **k):
            t = time.process_time()
            try:
                return inner(*a, **k)
            finally:
                spent[key] += time.process_time() - t
                count["solves"] += key == "solves"
        return inner, timed_call

    def ranges(*a, **k):
        before = count["solves"]
        try:
            return plain_ranges(*a, **k)
        except hull.Beyond:           # the ends of C it did not solve
            count["unsolved"] += 2 * len(np.atleast_2d(a[5])) - (count["solves"] - before)
            raise
    plain_ranges = hull.ranges
    patches = [(highs, "solve", *timing(highs, "solve", "solves")), (recordings, "read_log",
               *timing(recordings, "read_log", "read")), (stills, "still_intervals",
               *timing(stills, "still_intervals", "still")), (hull, "ranges", plain_ranges, ranges)]
    with tempfile.TemporaryDirectory() as tmp:
        logs = _batch_logs(tmp)
        argv = ["calibrate-norm", *map(str, logs), "--g", str(G_LOGS), "--out", f"{tmp}/out", "--jobs", "1"]
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            garant(argv)
            for owner, name, _, patched in patches:
                setattr(owner, name, patched)
            try:
                t = time.process_time()
                garant(argv[:-4] + ["--out", f"{tmp}/again", "--jobs", "1"])
                total = time.process_time() - t
            finally:
                for owner, name, inner, _ in patches:
                    setattr(owner, name, inner)
    rest = total - sum(spent.values())
    print(f"Where the production line's CPU goes: {len(logs)} logs in one process (--jobs 1), its modules loaded")
    for label, value in ((f"all {len(logs)} logs", total),
                         (f"HiGHS's solves ({count['solves']:,} LPs, {count['solves'] / len(logs):.1f} per log)",
                          spent["solves"]), ("reading the logs", spent["read"]),
                         ("their still intervals", spent["still"]),
                         ("the rest: fits, remainders, proofs and files, in Python", rest)):
        print(f"  {label:64s} {value:6.3f} s")
    print(f"  LP ends a rejected premise box did not solve (it stops at its first end proven past the box): "
          f"{count['unsolved']:,}")


def main():
    """Both tools on every real log, then on synthetic logs of 1e5 and 1e6 samples; then the production line
    (`--batch`: that alone; `--profile`: where its CPU goes, no imu_tk needed)."""
    if "--profile" in sys.argv[1:]:
        profile()
        return
    binary = imu_tk_binary()
    if binary is None:
        print("imu_tk is not built (../shared/peers/imu_tk/build.sh, or IMU_TK_ACC=path): no peer rows")
        return
    from . import byte_compiled
    print(byte_compiled())
    if "--batch" in sys.argv[1:]:
        batch(binary)
        return
    print(f"garant calibrate-norm against imu_tk ({binary}); medians of {REPEAT} alternating runs each")
    one_thread = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}      # as the garant command sets it
    floor = np.median([measured([sys.executable, "-c", "import numpy, highspy"], one_thread)[0]
                       for _ in range(REPEAT)])
    print(f"the floor of any Python command here: the interpreter with numpy (one BLAS thread, as garant "
          f"runs it) and highspy imported, {floor:.3f} s CPU")
    print(f"{'log':34s} {'garant CPU s':>12s} {'imu_tk CPU s':>12s} {'ratio':>6s} {'wall g/i':>12s} {'MiB g/i':>11s}")
    with tempfile.TemporaryDirectory() as tmp:
        logs = [(REAL / f, b) for f, b in LOGS] + _synthetic(tmp)
        compared = []
        for log, b0 in logs:
            med, out = side_by_side(log, b0, binary, f"{tmp}/r.json")
            (gc, gw, gm), (ic, iw, im) = med["garant"], med["imu_tk"]
            gres = json.loads(Path(f"{tmp}/r.json").read_text()) if out["garant"][1] in (0, 3) else None
            note = "" if gres is not None else " (garant refuses the log)"
            peer = imu_tk_result(out["imu_tk"][0])
            note += "" if peer is not None else " (imu_tk reports failure)"
            print(f"{log.name:34s} {gc:12.3f} {ic:12.3f} {gc / ic:6.2f} {gw:5.2f}/{iw:5.2f} {gm:5.0f}/{im:5.0f}{note}")
            if gres is not None and gres.get("consistent") and peer is not None and log.parent == REAL:
                compared.append((log.name, compare(peer, gres)))
    print("\nimu_tk's parameters against garant's guaranteed bounds (|imu_tk - garant| / bound):")
    for name, rows in compared:
        worst = max(abs(p - g) / e for _, p, g, e in rows)
        print(f"{name:34s} " + "  ".join(f"{k.split()[0]} {abs(p - g) / e:.2f}" for k, p, g, e in rows)
              + f"  -> {'within' if worst <= 1 else 'OUTSIDE'}")
    batch(binary)


def _synthetic(tmp):
    """Synthetic logs in m/s^2 (40 orientations, noise 0.01 m/s^2) of 1e5 and 1e6 samples at 100 Hz."""
    rng = np.random.default_rng(0)
    out = []
    for samples in (100_000, 1_000_000):
        rows, per = [], samples // 40
        for d in rng.normal(size=(40, 3)):
            n = d / np.linalg.norm(d)
            still = per * 2 // 3
            rows.append(np.tile(G_LOGS * n, (still, 1)) + rng.normal(0, 0.01, (still, 3)))
            rows.append(rng.normal(0, 3, (per - still, 3)) + G_LOGS * n)
        raw = np.vstack(rows)
        path = Path(tmp) / f"synthetic_{samples:.0e}.txt"
        np.savetxt(path, np.column_stack([np.arange(len(raw)) * 0.01, raw]), fmt="%.6f")
        out.append((path, 0))
    return out


if __name__ == "__main__":
    main()
