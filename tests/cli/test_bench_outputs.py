"""python -m verify.bench.outputs --compare: what changed between two runs of the fixed commands, as magnitudes."""
import json
import subprocess
import sys

import pytest

from conftest import ROOT
from garant.verify.bench.outputs import compare


def _folders(tmp_path, after):
    """Two folders with one JSON result and one flight-stack text file each; `after` edits the second's JSON."""
    doc = {"q": {"a": 1.0e-3}, "guaranteed_error": {"a": 2.0e-5}, "effects": {"x": {"bound": [1e-6, 2e-6]}},
           "status": "consistent"}
    for name, d in (("before", doc), ("after", after(json.loads(json.dumps(doc))))):
        (tmp_path / name).mkdir()
        (tmp_path / name / "r.json").write_text(json.dumps(d))
        (tmp_path / name / "p.parm").write_text("INS_ACCSCAL_X 1.000123\nINS_ACC1_ID 42\n")
    return tmp_path / "before", tmp_path / "after"


def test_identical_folders_say_so(tmp_path):
    lines, passed = compare(*_folders(tmp_path, lambda d: d))
    assert passed and lines[0] == "2 files: 2 identical, 0 differ" and lines[1].startswith("bounds: 0 changed")


def test_an_estimate_moved_and_a_bound_tightened_pass_with_their_magnitudes(tmp_path):
    def edit(d):
        d["q"]["a"] *= 1 + 3e-13
        d["effects"]["x"]["bound"][1] *= 1 - 1e-12
        return d
    lines, passed = compare(*_folders(tmp_path, edit))
    assert passed, lines
    assert lines[0].startswith("2 files: 1 identical, 1 differ; largest relative change of a number 1.0e-12")
    assert lines[1] == "bounds: 1 changed, 1 tighter, 0 looser"
    assert "r.json: 2 numbers changed (largest relative 1.0e-12)" in lines


def test_a_loosened_bound_or_a_changed_word_fails(tmp_path):
    # Red when the direction of a bound's change is not read (a loosening beyond the tolerance passes), or when a
    # word that is not a number is let through.
    before, after = _folders(tmp_path, lambda d: {**d, "guaranteed_error": {"a": 2.0e-5 * (1 + 2e-9)}})
    lines, passed = compare(before, after)
    assert not passed and "the largest loosening 2.0e-09 relative (r.json /guaranteed_error/a:" in lines[1]
    assert compare(before, after, tolerance=1e-8)[1]
    for sub, edit in (("w", lambda d: {**d, "status": "refuted"}), ("k", lambda d: {**d, "extra": 1})):
        (tmp_path / sub).mkdir()
        lines, passed = compare(*_folders(tmp_path / sub, edit))
        assert not passed, lines


def test_a_ratio_to_a_bound_is_no_bound(tmp_path):
    # The verdict's worst_over_bound (the worst residual over its interval's bound) grows when a remainder is proven
    # smaller: not a bound that loosened. Red when a key naming "bound" is read as one whatever it is.
    before, after = _folders(tmp_path, lambda d: {**d, "worst_over_bound": 0.5 * (1 + 2e-9)})
    doc = json.loads((before / "r.json").read_text())
    (before / "r.json").write_text(json.dumps({**doc, "worst_over_bound": 0.5}))
    lines, passed = compare(before, after)
    assert passed and lines[1] == "bounds: 0 changed, 0 tighter, 0 looser", lines


def test_the_command_exits_1_on_a_loosened_bound(tmp_path):
    before, after = _folders(tmp_path, lambda d: {**d, "guaranteed_error": {"a": 3e-5}})
    run = subprocess.run([sys.executable, "-m", "verify.bench.outputs", "--compare", str(before), str(after)],
                         cwd=ROOT, capture_output=True, text=True)
    assert run.returncode == 1 and "a bound loosened by more than 1e-09 relative" in run.stdout, run.stdout


@pytest.mark.slow
def test_the_peer_profile_times_the_functions_the_batch_calls(capsys):
    # `python -m verify.bench.peer --profile` patched highs.run and recordings.still_intervals after both had moved
    # (to highs.solve, workflows/stills.py): it stopped at an AttributeError. Each patched function is timed only
    # if the batch reaches it by that name, so each count and time is checked to be positive. Red with a renamed
    # function, or one patched where the batch no longer looks it up (its time then 0).
    from garant.verify.bench import peer
    peer.profile()
    out = capsys.readouterr().out
    figures = {line.split("  ")[1].strip(): float(line.split()[-2]) for line in out.splitlines()[1:6]}
    assert len(figures) == 5 and all(v > 0 for v in figures.values()), out
    assert "HiGHS's solves (" in out and "(0 LPs" not in out, out
