"""Start-up: `garant --help`, `garant CMD --help`, an unknown option and a missing argument answer before the
numerics load (numpy, SymPy, cvxpy, matplotlib, HiGHS are imported only by the commands that compute). Checked by
the modules a fresh interpreter holds afterwards, not by timing; docs/bench.md gives the time
(`python -m verify.bench`, bench_startup)."""
import json
import subprocess
import sys

from conftest import REAL, needs_real
from garant.verify.cli import COMMANDS

HEAVY = ("numpy", "sympy", "cvxpy", "matplotlib", "highspy", "scipy", "pandas")

PROBE = """
import json, sys
from garant.verify.cli import main
codes = []
for argv in json.loads(sys.argv[1]):
    try:
        codes.append(main(argv))
    except SystemExit as e:
        codes.append(e.code)
print(json.dumps({"codes": codes, "heavy": sorted({m.split('.')[0] for m in sys.modules} & set(%r))}))
""" % (HEAVY,)


def _probe(argvs):
    out = subprocess.run([sys.executable, "-c", PROBE, json.dumps(argvs)], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_help_and_argument_errors_load_no_numerics():
    # `garant --help` took 0.45 s, 0.41 s over a bare interpreter: the argument definitions imported the models,
    # the noise rule and the plan search, which load numpy and more. Red when a command's parser imports one.
    argvs = [["--help"], ["--version"]] + [[c, "--help"] for c in COMMANDS]
    argvs += [["calibrate-norm", "--bogus"], ["estimate"], ["plan", "--model", "two-axis", "--search-nodes", "x"]]
    got = _probe(argvs)
    assert got["heavy"] == [], got
    assert got["codes"][:len(COMMANDS) + 2] == [0] * (len(COMMANDS) + 2)
    assert all(c == 2 for c in got["codes"][len(COMMANDS) + 2:]), got["codes"]


@needs_real
def test_a_small_log_s_calibration_loads_no_masked_arrays():
    # numpy.ma costs 8 ms to import, a twentieth of calibrate-norm on a small log (the batch and the peer's ratio on
    # repeat session 4 and the Xsens log, docs/bench.md), and np.unique loads it: hull.stacked merged the multipliers'
    # rows with it. Red when any step of a small calibration calls np.unique (or another function that loads it).
    # So for numpy.random (9 ms: support's cell names were drawn at import), the process pool and tomllib (10 ms:
    # loaded by batch.py for one log without --spec), the effects' and thermal modules (for a log without
    # temperature or effects): red when any is imported for one log again.
    unused = ["numpy.ma", "numpy.random", "concurrent.futures", "multiprocessing", "tomllib",
              "garant.verify.workflows.norm_effects", "garant.verify.workflows.norm_thermal"]
    code = ("import sys; from garant.verify.cli import main; main(['calibrate-norm', sys.argv[1], '--g', '9.81744']); "
            f"print([m for m in {unused!r} if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code, str(REAL / "repeat_session4_acc.txt")], capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"
