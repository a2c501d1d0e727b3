"""The suite passes in any checkout: a slice of it, the tests that read human output (which wraps at 100 columns,
a path one unbreakable word), run with the recordings and the temporary files at paths of 150 characters.

A fresh clone at a longer path once failed CI (test_repeatability read a file name the wrapping had moved, and
test_cli's 100-column check counted a long path's line); this test would have been red there."""
import os
import subprocess
import sys

import pytest
from conftest import REAL, ROOT, needs_real

#: The tests whose output names files: the commands' human output, batches, repeatability, the norm verdict.
SLICE = ("tests/cli/test_cli.py", "tests/workflows/test_repeatability.py", "tests/workflows/test_batch.py",
         "tests/workflows/test_norm_verdict.py", "tests/cli/test_hostile_round5.py")


@pytest.mark.slow
@needs_real
def test_a_slice_of_the_suite_passes_with_its_files_at_long_paths(tmp_path):
    deep = tmp_path / ("a_checkout_at_a_long_path_" + "x" * 150)[:150]
    deep.mkdir()
    shared = deep / "shared"
    shared.symlink_to(REAL.parents[1])
    env = dict(os.environ, GARANT_SHARED=str(shared))
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-m", "not slow", "-p", "no:cacheprovider",
                        "--dist", "load", f"--basetemp={deep / 'tmp'}", *SLICE],      # test by test: both cores busy
                       cwd=ROOT, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-3000:]
