import os
import tempfile
from pathlib import Path

# One BLAS thread a process, as the command sets it (verify/cli/__init__.py), here before numpy loads (the
# xdist workers and the commands tests start inherit it): in-process tests then compute as `garant` does, and
# BLAS threads on these small matrices only competed with the other worker (whole suite 189 s -> 161 s).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import sys

# Bytecode caches written even where PYTHONDONTWRITEBYTECODE is set: pytest's assertion-rewritten test modules and
# the package's own modules, read back by every later worker and by the commands the tests start, instead of being
# rewritten and compiled afresh in each (collecting the fast lane: 3.6 -> 1.6 s CPU a process). __pycache__/ is ignored.
sys.dont_write_bytecode = False

import numpy as np  # noqa: E402
import pytest  # noqa: E402

#: Where things are, for every test: the repository, the tests' data and stands, and the real recordings of
#: ../shared beside the clone (GARANT_SHARED names another place: tests/cli/test_any_checkout.py runs a slice of
#: the suite with it at a long path).
TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
DATA = TESTS / "data"
STANDS = DATA / "stands"
REAL = Path(os.environ.get("GARANT_SHARED") or ROOT.parent / "shared") / "data" / "real"
G_REAL = 9.81744                 # the g the recordings' authors used (shared/data/real/README.md), m/s^2
# Skipped on a machine without shared/, never in CI (CI=true): there the data must be present.
needs_real = pytest.mark.skipif(not REAL.is_dir() and not os.environ.get("CI"),
                                reason="../shared/data/real is not present")

# Derived descriptions are cached (verify/models.py); the tests keep theirs apart from the user's, in a
# folder made once by the process that starts the run (the workers inherit it) and removed at its end.
_OWN_CACHE = None
if "GARANT_CACHE" not in os.environ:
    _OWN_CACHE = os.environ["GARANT_CACHE"] = tempfile.mkdtemp(prefix="garant-test-cache-")

from garant.generated import two_axis as two_axis  # noqa: E402  (after the cache is set)


@pytest.fixture(scope="session")
def mod():
    return two_axis


def C(n, x):
    """The independent oracle of the rotation chains (numpy, written apart from garant): the passive rotation
    by x about the unit vector n, cos x E + (1 - cos x) n n^T - sin x [n x] (C1-C3 of section 2 of 000;
    Rodrigues for a tilted axis)."""
    n = np.asarray(n, float) / np.linalg.norm(n)
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.cos(x) * np.eye(3) + (1 - np.cos(x)) * np.outer(n, n) - np.sin(x) * K


def simulate(mod, positions_deg, physical, sigma, g=9.81, seed=0):
    """Readings (N, 3) in m/s^2 from the exact model plus noise bounded by sigma (units of g)."""
    P = np.deg2rad(np.asarray(positions_deg, float))
    f = mod.readings(P[:, 0], P[:, 1], physical, g).T
    rng = np.random.default_rng(seed)
    return f + g * rng.uniform(-sigma, sigma, f.shape)


def write_csv(path, positions_deg, f, extra=None):
    with open(path, "w") as fh:
        cols = ["alpha_deg", "beta_deg", "f1", "f2", "f3"] + list(extra or {})
        fh.write(",".join(cols) + "\n")
        for k, ((a, b), row) in enumerate(zip(positions_deg, f)):
            cells = [repr(float(a)), repr(float(b))] + [repr(float(v)) for v in row]
            cells += [str(v[k]) for v in (extra or {}).values()]
            fh.write(",".join(cells) + "\n")
    return path


def pytest_sessionfinish(session):
    """Remove the cache folder this run made (by the process that made it, after every worker is done)."""
    import shutil
    if _OWN_CACHE and not hasattr(session.config, "workerinput"):
        shutil.rmtree(_OWN_CACHE, ignore_errors=True)


def flat(text):
    """Printed text with the command line's wrapping at 100 columns undone: every run of spaces and line breaks as
    one space (a check for a phrase then holds wherever the line was wrapped)."""
    return " ".join(text.split())


def command_line(text, prefix):
    """The command printed on the line that starts with `prefix` (after any indent), its shell continuations (a
    backslash at a line's end) joined: what a user pastes into a shell."""
    lines = text.splitlines()
    k = next(i for i, x in enumerate(lines) if x.strip().startswith(prefix))
    parts = [lines[k].strip()]
    while parts[-1].endswith(" \\"):
        k += 1
        parts[-1] = parts[-1][:-2]
        parts.append(lines[k].strip())
    return " ".join(parts)


def warm_truth_readings(truth, g, count, lo, hi, seed):
    """A simulated warm-up unit's noise-free raw readings (simulate's truth: raw = M^-1 g (m + Phi(m, T) theta) + b)
    at `count` random directions m (3, count) and temperatures T within [lo, hi] C: (m, T, raw (count, 3))."""
    from garant.generated import norm
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(3, count))
    m /= np.linalg.norm(m, axis=0)
    T = rng.uniform(lo, hi, count)
    term = sum(np.einsum("j,jik->ik", np.array(list(th.values())), norm.effect_basis(x, m, 0.0, T, np.zeros(count)))
               for x, th in truth["effects"].items())
    return m, T, np.linalg.solve(np.array(truth["matrix"]), g * (m + term)).T + np.array(truth["bias"])



def fast_first(cases, keep=1):
    """Parametrize cases with the first `keep` in the fast lane and the rest marked slow (`pytest -m "not slow"` runs a
    case of the test, the whole suite every case). A case of several arguments is a tuple."""
    return [c if k < keep else pytest.param(*(c if isinstance(c, tuple) else (c,)), marks=pytest.mark.slow)
            for k, c in enumerate(cases)]


_SET_LPS = {}


def set_max(st, c):
    """(max over a file's information set `st` of c^T x, an x where it is reached): HiGHS directly (as scipy's
    linprog(method="highs") runs it, without scipy's checks of the whole problem at each objective, 4 ms an LP), on
    x = xc + dc y over the box's half-widths y in [-1, 1], each row over its bound, -1 <= (R x - s) / bound <= 1,
    feasibility to 1e-10. One model a set, built at its first objective; each next objective changes the cost only.
    The set's shift (q = x + s, |s| <= shift) is the caller's."""
    import highspy
    got = _SET_LPS.get(id(st))
    if got is None or got[0] is not st:
        R, s, bd = (np.array(st[k], float) for k in ("rows", "centre", "bound"))
        lo, hi = np.array(st["box_lo"], float), np.array(st["box_hi"], float)
        xc, dc = (lo + hi) / 2, (hi - lo) / 2
        A, t = R * dc / bd[:, None], (s - R @ xc) / bd
        rows, cols = A.shape
        h = highspy.Highs()
        for option, value in (("output_flag", False), ("threads", 1), ("primal_feasibility_tolerance", 1e-10),
                              ("dual_feasibility_tolerance", 1e-10)):
            h.setOptionValue(option, value)
        h.passModel(cols, rows, rows * cols, 1, 1, 0.0, np.zeros(cols), -np.ones(cols), np.ones(cols), t - 1, t + 1,
                    np.arange(0, rows * cols, rows, dtype=np.int32), np.tile(np.arange(rows, dtype=np.int32), cols),
                    np.ascontiguousarray(A.T).ravel(), np.zeros(cols, dtype=np.int32))
        got = _SET_LPS[id(st)] = (st, h, xc, dc)
    _, h, xc, dc = got
    cs = np.asarray(c, float) * dc
    k = max(np.abs(cs).max(), 1e-300)
    h.changeColsCost(len(cs), np.arange(len(cs), dtype=np.int32), -cs / k)
    h.run()
    assert h.getModelStatus() == highspy.HighsModelStatus.kOptimal
    return -h.getInfo().objective_function_value * k + np.asarray(c, float) @ xc, xc + np.array(
        h.getSolution().col_value) * dc
