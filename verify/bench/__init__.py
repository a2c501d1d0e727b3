"""python -m verify.bench: speed figures, each as a ratio against a baseline measured in the same run.

Baselines are the straightforward way of doing the same job on the same machine, each actually run
(on a smaller problem where the full one would take minutes, as its row says), with the same
statistic on both sides (the median of REPEAT runs, wall and CPU seconds): per-target HiGHS LPs on a
grid or on the data (what scipy's linprog gives a user), LP-per-subset enumeration for the
minimal-plan proof, an imu_tk-style fit for calibrate-norm, and a naive Jacobian for the derivation.
docs/bench.md says what each baseline is and why.
"""
import os

# One BLAS thread, as the command runs (verify/cli/__init__.py), set before numpy loads: the in-process rows
# and baselines then measure what `garant` does, not threads waiting on small matrices (a user's setting wins).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import subprocess
import sys
import time
import warnings
from itertools import combinations
from pathlib import Path

import numpy as np

from .baseline import per_target_lp
from ..models import load
from ..papers import stand_000
from ..solve import lp, plans

ROOT = Path(__file__).resolve().parents[2]      # the repository: where `python -m derive` runs


REPEAT = 3


class Timing(float):
    """Median wall-clock seconds of REPEAT runs, with the median CPU seconds beside it."""

    def __new__(cls, wall, cpu):
        """Wall seconds, with the CPU seconds beside them."""
        t = super().__new__(cls, wall)
        t.cpu = cpu
        return t


def timed(fn, repeat=REPEAT):
    """The same statistic on both sides of every ratio: the median of `repeat` runs (wall and CPU)."""
    walls, cpus = [], []

    def cpu():                                     # this process and its finished children (subprocess rows)
        t = os.times()
        return t.user + t.system + t.children_user + t.children_system
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), cpu()
        out = fn()
        walls.append(time.perf_counter() - w0)
        cpus.append(cpu() - c0)
    return Timing(float(np.median(walls)), float(np.median(cpus))), out


#: Appended to a child's code: print its peak resident memory in KiB. VmHWM, unlike ru_maxrss (kept
#: across exec on Linux, so a child of a large process reports the parent's peak), starts afresh.
PEAK_KIB = """
try:
    print(next(l.split()[1] for l in open("/proc/self/status") if l.startswith("VmHWM")), file=sys.stderr)
except (OSError, StopIteration):
    import resource
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)
"""


def bench_derive():
    """Derivation and rendering of the two-axis model (in process, cache cleared) vs a naive Jacobian."""
    import sympy as sp
    from garant.derive import codegen, derivation
    from garant.derive.builtin import TWO_AXIS_MODEL

    def run():
        derivation.derive.cache_clear()
        return codegen.model_files(TWO_AXIS_MODEL)

    t, _ = timed(run)
    from garant.derive.model import residual
    z = residual(TWO_AXIS_MODEL)
    syms = [p.symbol for p in TWO_AXIS_MODEL.parameters]
    zero = {s: 0 for s in syms}
    base, _ = timed(lambda: [sp.simplify(sp.diff(z[i], s).subs(zero)) for i in range(3) for s in syms])
    return ("derivation + generation, two-axis model", t,
            "naive Jacobian: sp.simplify on each of its 63 entries", base)


def bench_guaranteed_errors(mod):
    """The 15 optimal errors proven on the continuum, the derivation that gives their closed forms
    included (cache cleared, module rendered and loaded), vs per-target LPs on a 5-degree grid."""
    import types

    from garant.derive import codegen, derivation
    from garant.derive.builtin import TWO_AXIS_MODEL

    def run():
        derivation.derive.cache_clear()
        text = codegen.model_files(TWO_AXIS_MODEL)["generated/two_axis.py"]
        fresh = types.ModuleType("two_axis_fresh")
        exec(compile(text, "two_axis_fresh", "exec"), fresh.__dict__)
        return list(stand_000.continuum_optimum(fresh))
    t, rows = timed(run)
    assert all(r.passed for r in rows)
    g = np.deg2rad(np.arange(0, 360, 5))
    A = lp.measurement_matrix(mod.H, np.array([(a, b) for a in g for b in g]))
    base, (_, err) = timed(lambda: per_target_lp(A))
    assert np.allclose(err, 1, atol=1e-7)
    return ("15 optimal errors proven on the continuum (derivation included)", t,
            "per-target LP on a 5 deg grid (a grid value, no proof)", base)


def bench_plan_search():
    """Minimal plan and count of optimal plans of the single-axis stand (12 reachable positions) vs
    solving the LP on every subset of 7 and 8 of them (all 1,287, actually run). The two-axis search
    (19,448 subsets, about a minute of LPs) is not brute-forced here."""
    mod = load("single-axis")
    t, r = timed(lambda: plans.search(mod))
    angles, mounts = plans.grid(mod)
    A = lp.measurement_matrix(mod, np.deg2rad(np.asarray(angles, float)), mounts)
    best = np.array(r.errors)

    def brute():
        found = {}
        for k in (r.min_positions - 1, r.min_positions):
            for sub in combinations(range(len(angles)), k):
                cols = (3 * np.array(sub)[:, None] + np.arange(3)).reshape(-1)
                if not lp.unidentifiable(A[:, cols]) and np.allclose(lp.primal(A[:, cols])[1], best, rtol=1e-9):
                    found.setdefault(k, []).append(sub)
        return found
    base, found = timed(brute)
    assert r.min_positions - 1 not in found and len(found[r.min_positions]) == len(r.optimal_plans)
    return (f"single-axis: minimal plan ({r.min_positions}) and its {len(r.optimal_plans)} optimal plans", t,
            f"LP on every subset of {r.min_positions - 1} and {r.min_positions} of {len(angles)} positions", base)


def bench_diagnose(mod):
    """A diagnosis with the whole catalogue on 96 positions (fresh caches) vs rendering every
    extended model's module (what scoring would cost without the derived-H path)."""
    import tempfile

    from garant.derive import codegen, derivation, effects
    from garant.derive.builtin import TWO_AXIS_MODEL

    from ..io.positions import read_positions
    from ..workflows import diagnose, simulate
    from ..workflows.premises import premises
    P, f, t, T, _, _ = simulate.simulate(TWO_AXIS_MODEL, mod, "grid:30x45", [("scale_quadratic", [1e-4, 0, 0])],
                                      1e-5, 0)
    with tempfile.TemporaryDirectory() as tmp:
        simulate.write(f"{tmp}/d.csv", P, f, t, T)
        pos = read_positions(f"{tmp}/d.csv")

        def run():
            derivation.derive.cache_clear()
            derivation.numeric_H.cache_clear()
            return diagnose.diagnose(TWO_AXIS_MODEL, mod, pos, 1e-5, premises(mod, 1e-5, 9.81))
        t_run, res = timed(run)
    assert res["effects"] == ["scale_quadratic"]
    def render_all():
        derivation.derive.cache_clear()
        return [codegen.model_files(effects.extend(TWO_AXIS_MODEL, [e]), "x", "x") for e in effects.CATALOGUE]
    base, _ = timed(render_all)
    return ("diagnosis, whole catalogue, 96 positions (target < 10 s)", t_run,
            "derive and render every extended module", base)


def bench_guarantee(mod):
    """The verdict on 100 two-axis positions: exact-model minimax fit, proven a posteriori remainder
    (interval Taylor) and the guaranteed errors, vs sampling the exact model's remainder at 100 random
    parameter vectors (what the allowance was before: no proof). Target < 2 s."""
    import tempfile

    from ..io.positions import read_positions
    from ..workflows import estimate, guarantee, simulate
    from ..workflows.premises import premises
    from garant.derive.builtin import TWO_AXIS_MODEL
    P, f, t, T, _, _ = simulate.simulate(TWO_AXIS_MODEL, mod, "grid:36x36", [], 1e-5, 0)
    with tempfile.TemporaryDirectory() as tmp:
        simulate.write(f"{tmp}/d.csv", P, f, t, T)
        pos = read_positions(f"{tmp}/d.csv")
    z = estimate.residuals_table_axes(mod, pos, 9.81, np.eye(3)).reshape(-1)
    A = lp.measurement_matrix(mod.H, np.column_stack(pos.radians))
    prem = premises(mod, 1e-5, 9.81, prior=1e-3, g_uncertainty=1e-3)

    def run():
        lin = guarantee.linearise(mod, pos, z, A, prem)
        return guarantee.verdict(lin, z, 1e-5, lp.primal(lin.A)[0].T)
    t_run, v = timed(run)
    assert v.consistent and len(P) == 100
    rng = np.random.default_rng(0)
    Hs = mod.H(*pos.radians)

    def sampled():
        worst = 0.0
        for _ in range(100):
            p = rng.uniform(-1e-3, 1e-3, len(mod.PARAMETER_NAMES))
            zz = mod.residual(*pos.radians, mod.readings(*pos.radians, p, 9.81), 9.81)
            worst = max(worst, float(np.abs(zz - np.einsum("pns,n->ps", Hs, mod.PHYSICAL_TO_Q @ p)).max()))
        return worst
    base, _ = timed(sampled)
    return ("verdict, 100 positions: exact fit + proven remainder (target < 2 s)", t_run,
            "sampled remainder, 100 draws (no proof)", base)


def bench_hull():
    """A thermal estimate (two-axis, degree 2, 16 positions at each of 5 chamber temperatures): its information
    set's hulls are batches of LPs proven by duality, each from the last basis; by primal simplex (hull.SIMPLEX)
    vs by dual simplex."""
    import tempfile

    from ..models import thermal
    from ..solve import hull
    from ..workflows import jobs
    mod = thermal("two-axis", 2, 20)
    temps = np.repeat([-20.0, 0.0, 20.0, 40.0, 60.0], 16)
    P = np.tile([(a, b) for a in range(0, 360, 90) for b in range(0, 360, 90)], (5, 1)).astype(float)
    p = np.random.default_rng(0).uniform(-1e-4, 1e-4, len(mod.PARAMETER_NAMES))
    f = mod.readings(*np.deg2rad(P).T, p, 9.81, temp_c=temps).T
    f += 9.81 * np.random.default_rng(1).uniform(-1e-4, 1e-4, f.shape)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "chamber.csv"
        path.write_text("alpha_deg,beta_deg,f1,f2,f3,temp_c\n" + "".join(
            ",".join(repr(float(x)) for x in (*a, *r, t)) + "\n" for a, r, t in zip(P, f, temps)))

        def run(strategy):
            hull.SIMPLEX, kept = strategy, hull.SIMPLEX
            try:
                return jobs.estimate("two-axis", str(path), 1e-4, g=9.81, thermal_degree=2)
            finally:
                hull.SIMPLEX = kept
        t, res = timed(lambda: run(4))
        base, res1 = timed(lambda: run(1))
    assert res["consistent"] and res1["consistent"]
    return ("thermal estimate, 80 positions: hulls by primal simplex", t, "the same by dual simplex", base)


def bench_continuum(mod):
    """Exchange method for the 15 two-axis optima vs per-target LPs on a 3-degree grid (all 15
    targets, 14,400 positions, actually run; a 1-degree grid would take minutes)."""
    from ..solve import continuum
    t, sol = timed(lambda: continuum.exchange(mod.H, 2, np.eye(15)))
    assert np.allclose(sol.values, 1, atol=1e-7)
    g = np.deg2rad(np.arange(0, 360, 3))
    A = lp.measurement_matrix(mod.H, np.array([(a, b) for a in g for b in g]))
    base, (_, err) = timed(lambda: per_target_lp(A))
    assert np.allclose(err, 1, atol=1e-7)
    return "15 two-axis optima, exchange method on the continuum", t, "per-target LP on a 3 deg grid", base


def bench_certificates():
    """Build and independently check the 15 two-axis certificates vs solving the 15 LPs on a 15 deg grid."""
    from ..proof import build, check
    mod = load("two-axis")
    t, ok = timed(lambda: [all(o for _, o, _ in check.check(c)) for c in build.for_model("two-axis")])
    assert all(ok)
    g = np.deg2rad(np.arange(0, 360, 15))
    A = lp.measurement_matrix(mod.H, np.array([(a, b) for a in g for b in g]))
    base, _ = timed(lambda: per_target_lp(A))
    return "15 two-axis certificates: build + exact check (target < 5 s)", t, "per-target LP on a 15 deg grid", base


def bench_scale(rows=(1_000, 10_000, 100_000, 1_000_000), distinct=96):
    """Peak memory and time of `garant estimate` and `garant identify --plan` on files of N rows (the
    96 positions of a 30 x 45 degree grid, each read many times, as a static log gives), each command
    in a fresh process. Target: linear in N; 1e6 rows under 2 GB and 60 s."""
    import tempfile
    mod = load("two-axis")
    rng = np.random.default_rng(0)
    p = rng.uniform(-1e-4, 1e-4, len(mod.PARAMETER_NAMES))
    grid = np.array([(a, b) for a in range(0, 360, 30) for b in range(0, 360, 45)], float)[:distinct]
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in rows:
            P = grid[rng.integers(0, len(grid), n)]
            f = mod.readings(*np.deg2rad(P).T, p, 9.81).T + 9.81 * rng.uniform(-0.999e-5, 0.999e-5, (n, 3))
            path = f"{tmp}/d{n}.csv"
            np.savetxt(path, np.column_stack([P, f]), delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3",
                       comments="", fmt="%.10g")
            for argv in (["estimate", "--model", "two-axis", path, "--sigma", "1e-5"],
                         ["identify", "--model", "two-axis", "--plan", path]):
                code = ("import sys, time; from garant.verify.cli import main; t = time.perf_counter(); "
                        f"main({argv!r}); print(time.perf_counter() - t, file=sys.stderr)\n" + PEAK_KIB)
                r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
                t, kb = r.stderr.strip().splitlines()[-2:]
                out.append((argv[0], n, float(t), int(kb) / 1024))
    return out


def distinct_positions(n, path, seed=0):
    """Write a two-axis positions file of n distinct random positions (both angles uniform), read by the exact
    model with errors within 1e-4 and noise within 0.999e-5 g (10 digits: noise up to 1e-5 itself, rounded, put
    readings past sigma at 1e6 positions): what `bench_estimate` times, to run `garant estimate --model two-axis
    PATH --sigma 1e-5` on at any size (docs/bench.md). Returns the path."""
    mod = load("two-axis")
    rng = np.random.default_rng(seed)
    p = rng.uniform(-1e-4, 1e-4, len(mod.PARAMETER_NAMES))
    P = rng.uniform(0, 360, (n, 2))
    f = mod.readings(*np.deg2rad(P).T, p, 9.81).T + 9.81 * rng.uniform(-0.999e-5, 0.999e-5, (n, 3))
    np.savetxt(path, np.column_stack([P, f]), delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3", comments="",
               fmt="%.10g")
    return path


def bench_estimate(ns=(100, 1_000, 10_000)):
    """`garant estimate` on N distinct random two-axis positions vs the per-target baseline
    (baseline.per_target_estimate), each a fresh process, interpreter start and imports included on both sides.
    N = 1e5 (baseline about a minute per run) is left to `garant estimate` alone (docs/bench.md)."""
    import tempfile
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in ns:
            path = distinct_positions(n, f"{tmp}/d{n}.csv")
            garant = [sys.executable, "-c", "import sys; from garant.verify.cli import main; sys.exit(main())",
                      "estimate", "--model", "two-axis", path, "--sigma", "1e-5"]
            t, _ = timed(lambda: subprocess.run(garant, check=True, capture_output=True))
            baseline = [sys.executable, "-c", f"from garant.verify.bench.baseline import per_target_estimate; "
                        f"per_target_estimate({path!r})"]
            base, _ = timed(lambda: subprocess.run(baseline, check=True, capture_output=True))
            out.append((f"garant estimate, {n:,} distinct positions (verdict, proven remainder)", t,
                        "per-target HiGHS LPs, no verdict or remainder", base))
    return out


def bench_startup(mod):
    """`garant --help` and `garant estimate` on a 10-position file, each a fresh process, against
    `python -c pass` (the interpreter alone). Targets: --help and an argument error within 0.15 s of the
    interpreter alone (no numerics loaded: tests/cli/test_startup.py), estimate on 10 positions < 1 s."""
    import tempfile

    from ..workflows import simulate
    from garant.derive.builtin import TWO_AXIS_MODEL
    out = []
    base, _ = timed(lambda: subprocess.run([sys.executable, "-c", "pass"], check=True))
    garant = [sys.executable, "-c",
              "import sys; from garant.verify.cli import main; sys.exit(main())"]   # = the garant script
    with tempfile.TemporaryDirectory() as tmp:
        P, f, t, T, _, _ = simulate.simulate(TWO_AXIS_MODEL, mod, "optimal10", [], 1e-5, 0)
        simulate.write(f"{tmp}/d.csv", P, f, t, T)
        for label, argv in (("garant --help (target: within 0.15 s of the interpreter)", ["--help"]),
                            ("garant calibrate-norm --bogus, an argument error (the same target)",
                             ["calibrate-norm", "--bogus"]),
                            ("garant estimate, 10 positions (target < 1 s)",
                             ["estimate", "--model", "two-axis", f"{tmp}/d.csv", "--sigma", "1e-5"])):
            t_run, _ = timed(lambda: subprocess.run(garant + argv, check=argv[-1] != "--bogus", capture_output=True))
            out.append((label, t_run, "python -c pass", base))
    return out


def bench_apply():
    """`garant apply` core on 1e6 samples: the correction, its per-sample bound and the CSV text, against
    reading the same samples back from a CSV with numpy (what any user of the corrected log pays anyway)."""
    import tempfile

    from ..io import calibration
    cal = {"M": np.eye(3) * 1.001, "b": np.array([0.01, -0.02, 0.03]), "bound_matrix": np.full((3, 3), 1e-4),
           "bound_bias": np.full(3, 1e-3), "bound_delta": np.zeros(3), "pendulosity_axes": np.array([2, 3, 1]),
           "g": 9.81}
    raw = np.random.default_rng(0).normal(size=(1_000_000, 3)) + [0, 0, 9.81]
    from ..io.text import csv_bytes
    t = np.arange(len(raw)) * 0.01

    def run():
        a, bound = calibration.apply(cal, raw)
        return csv_bytes([t, *a.T, *bound.T], up=(4, 5, 6), digits=(12, 8, 8, 8, 4, 4, 4))
    t_run, _ = timed(run)
    with tempfile.TemporaryDirectory() as tmp:
        np.savetxt(f"{tmp}/r.csv", raw, delimiter=",", fmt="%.6f")
        base, _ = timed(lambda: np.loadtxt(f"{tmp}/r.csv", delimiter=","))
    return ("apply: correction + worst-case bound + CSV text, 1e6 samples", t_run, "np.loadtxt of the same samples",
            base)


def _imu_tk_style(path, g=9.81, window=100):
    """The alternative a user would pick: read the log, find still windows by moving variance, and fit
    a = T K (raw - B) with |a| = g by Gauss-Newton (imu_tk's model, 9 parameters), no bounds."""
    data = np.loadtxt(path)
    raw = data[:, 1:4]
    c = np.cumsum(np.vstack([np.zeros(3), raw]), axis=0)
    c2 = np.cumsum(np.vstack([np.zeros(3), raw ** 2]), axis=0)
    var = ((c2[window:] - c2[:-window]) - (c[window:] - c[:-window]) ** 2 / window).sum(axis=1) / window
    still = var < 10 * np.median(var[: 5 * window])
    edges = np.flatnonzero(np.diff(np.r_[0, still.astype(np.int8), 0]))
    means = np.array([raw[a:b].mean(axis=0) for a, b in zip(edges[::2], edges[1::2]) if b - a > 2 * window])
    x = np.r_[np.zeros(3), np.ones(3), np.zeros(3)]                  # misalignment, scale, bias

    def residual(x):
        T = np.array([[1, -x[0], x[1]], [0, 1, -x[2]], [0, 0, 1]])
        return np.linalg.norm((means - x[6:]) @ (T * x[3:6]).T, axis=1) - g
    for _ in range(30):
        r = residual(x)
        J = np.array([(residual(x + 1e-7 * e) - r) / 1e-7 for e in np.eye(9)]).T
        x = x - np.linalg.lstsq(J, r, rcond=None)[0]
    return x


def bench_calibrate_norm(samples=1_000_000):
    """`garant calibrate-norm` (read, still intervals, exact-norm fit, verdict, guaranteed bounds) on a
    simulated log of `samples` rows against the imu_tk-style reference above, both from the same file."""
    import tempfile

    from ..io import recordings
    from ..workflows.stills import still_intervals
    from ..workflows import calibrate_norm, norm_problem
    mod = load("norm")
    rng = np.random.default_rng(0)
    rows = []
    dirs = rng.normal(size=(40, 3))
    per = samples // 40
    for d in dirs:
        n = d / np.linalg.norm(d)
        still = per * 2 // 3
        rows.append(np.tile(9.81 * n, (still, 1)) + rng.normal(0, 0.01, (still, 3)))
        rows.append(rng.normal(0, 3, (per - still, 3)) + 9.81 * n)
    raw = np.vstack(rows)
    with tempfile.TemporaryDirectory() as tmp:
        path = f"{tmp}/log.txt"
        np.savetxt(path, np.column_stack([np.arange(len(raw)) * 0.01, raw]), fmt="%.6f")

        def garant():
            log = recordings.read_log(path, "imu_tk")
            stills, _ = still_intervals(log)
            return calibrate_norm.run(norm_problem.problem(mod, stills, 9.81, 9, path, quantum=recordings.quantum(log)))
        t_run, res = timed(garant)
        base, _ = timed(lambda: _imu_tk_style(path))
    return (f"calibrate-norm, {samples:.0e} samples (read, still, fit, verdict, bounds)", t_run,
            "imu_tk-style: loadtxt, moving variance, Gauss-Newton, no bounds", base)


def codegen_outputs():
    """Every generated file rendered in memory (what `derive --check` compares)."""
    from garant.derive import codegen
    return codegen.outputs()


def byte_compiled():
    """garant's modules byte-compiled beside their sources, as pip does when it installs a package: a garant
    process then reads them instead of compiling about 50 modules (60-70 ms of CPU) each time it starts, which
    an editable install does where PYTHONDONTWRITEBYTECODE is set (as on this machine). Returns the line that
    says so."""
    import compileall
    for part in ("derive", "generated", "verify"):
        compileall.compile_dir(str(ROOT / part), quiet=2)
    compileall.compile_file(str(ROOT / "__init__.py"), quiet=2)
    return ("garant's modules byte-compiled first, as pip installs a package (PYTHONDONTWRITEBYTECODE is "
            f"{'set' if os.environ.get('PYTHONDONTWRITEBYTECODE') else 'not set'} here)")


def main():
    """Run every benchmark and print each figure as a ratio to its baseline measured in this run."""
    from ..solve import highs
    print(byte_compiled())
    warnings.filterwarnings("ignore", category=RuntimeWarning)
    highs.new()                                   # HiGHS prints a banner on its first construction: not here
    mod = load("two-axis")
    fresh, _ = timed(lambda: subprocess.run([sys.executable, "-m", "derive", "--check"], cwd=ROOT,
                                            check=True, capture_output=True))
    from garant.derive import description
    from garant.derive.builtin import STANDS_DIR
    from garant.derive.derivation import derive as derive_model
    three, _ = timed(lambda: (derive_model.cache_clear(),
                              derive_model(description.load(STANDS_DIR / "three_axis.toml"))))
    rows = [bench_derive(), bench_guaranteed_errors(mod), bench_plan_search(), bench_continuum(mod),
            bench_certificates(), bench_guarantee(mod), bench_hull(), bench_diagnose(mod), *bench_estimate(),
            *bench_startup(mod), bench_apply(), bench_calibrate_norm(), bench_calibrate_norm(10_000_000)]
    width = max(len(r[0]) for r in rows)
    print(f"medians of {REPEAT} runs on both sides; wall (CPU) seconds")
    print(f"{'figure'.ljust(width)}  {'time, s':>15}  {'baseline, s':>15}  {'speed-up':>9}  baseline")
    for name, t, bname, base in rows:
        print(f"{name.ljust(width)}  {t:7.3f} ({t.cpu:5.2f})  {base:7.3f} ({base.cpu:5.2f})"
              f"  {base / t:8.1f}x  {bname}")
    print(f"\n`python -m derive --check` (all {len(codegen_outputs())} files) in a fresh process, "
          f"interpreter start included: {fresh:.2f} s")
    print(f"derivation of the three-axis stand with its errors: {three:.2f} s")
    print("\nscale (96 distinct positions, repeated rows; fresh process each):")
    print(f"{'command':10s} {'rows':>9s} {'time, s':>8s} {'peak MiB':>9s}")
    for cmd, n, t, mib in bench_scale():
        print(f"{cmd:10s} {n:9d} {t:8.2f} {mib:9.0f}")
