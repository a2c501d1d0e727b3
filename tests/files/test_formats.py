"""The examples of docs/formats.md and docs/api.md are read and run, so the docs stay true."""
import re

import numpy as np
import pytest

from garant.verify.io import calibration, recordings
from garant.verify.errors import DataError
from garant.verify.io.positions import read_positions
from conftest import ROOT

DOCS = ROOT / "docs"


def block(doc, tag):
    m = re.search(rf"```{tag}\n(.*?)```", (DOCS / doc).read_text(), re.S)
    assert m, f"no ```{tag} block in docs/{doc}"
    return m.group(1)


def test_positions_example(tmp_path):
    (tmp_path / "p.csv").write_text(block("formats.md", "csv positions"))
    pos = read_positions(str(tmp_path / "p.csv"))
    assert pos.angles_deg.tolist() == [[0, 0], [0, 180]] and list(pos.extra["time_s"]) == [0.0, 60.0]  # a number


def test_log_example(tmp_path):
    path = tmp_path / "l.csv"
    head, *rows = block("formats.md", "csv log").strip().splitlines()
    t = np.arange(200) * 10.0                                         # the example's rows, repeated
    path.write_text(head + "\n" + "\n".join(f"{ti:g},{rows[k % 2].split(',', 1)[1]}" for k, ti in enumerate(t)) + "\n")
    log = recordings.read_log(str(path), "csv")
    assert log.t[1] == pytest.approx(0.01) and log.raw[0].tolist() == [0.01, -0.02, 9.81]


def test_calibration_and_imu_tk_examples_agree(tmp_path):
    (tmp_path / "c.json").write_text(block("formats.md", "json calibration"))
    (tmp_path / "c.calib").write_text(block("formats.md", "text imu_tk"))
    cal = calibration.read(tmp_path / "c.json")
    M, b = calibration.read_imu_tk(tmp_path / "c.calib")
    np.testing.assert_allclose(M, cal["M"], rtol=1e-15, atol=1e-18)
    np.testing.assert_allclose(b, cal["b"])
    a, bound = calibration.apply(cal, np.array([[0.0, 0.0, 9.8]]))
    assert np.all(bound > cal["bound_bias"])


@pytest.mark.slow
def test_api_example_runs(capsys):
    # The example needs no file beside the clone (it made a log of 001's plan in memory).
    exec(compile(block("api.md", "python"), "docs/api.md", "exec"), {})
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("10 [1.0, 1.0, 1.0]") and out[1].startswith("consistent noise rule")


def test_means_example(tmp_path):
    from garant.verify.io import means
    (tmp_path / "m.csv").write_text(block("formats.md", "csv means"))
    runs = means.read(str(tmp_path / "m.csv"), imu=1)
    assert len(runs) == 1 and runs[0].stills[0].mean.tolist() == [-0.203, -9.391, 2.858]
    assert runs[0].stills[0].std_error[0] == pytest.approx(0.036 / 1380 ** 0.5)
    assert runs[0].nominal.tolist() == [[0, -0.934172, 0.356822]]


def test_a_large_numeric_positions_file_is_read_in_c_exactly_as_cell_by_cell(tmp_path, monkeypatch):
    # The fast reader (np.loadtxt, files of only the required columns) and the cell-by-cell reader
    # (which names any bad cell) give the same numbers; any file the fast one cannot read falls through.
    from garant.verify.io import positions
    rng = np.random.default_rng(0)
    rows = np.column_stack([rng.uniform(0, 360, (50, 2)), rng.normal(0, 9.81, (50, 3))])
    path = tmp_path / "p.csv"
    path.write_text("alpha_deg,beta_deg,f1,f2,f3\n"
                    + "\n".join(",".join(repr(float(x)) for x in r) for r in rows) + "\n")
    assert positions._numeric(str(path), ["alpha_deg", "beta_deg", "f1", "f2", "f3"]) is not None
    fast = positions.read_positions(str(path))
    monkeypatch.setattr(positions, "_numeric", lambda *a: None)
    slow = positions.read_positions(str(path))
    assert np.array_equal(fast.angles_deg, slow.angles_deg) and np.array_equal(fast.f, slow.f)
    monkeypatch.undo()
    timed = tmp_path / "t.csv"                            # the model's variables read in C too, as numbers
    timed.write_text("alpha_deg,beta_deg,f1,f2,f3,time_s,temp_c\n"
                     + "\n".join(",".join(repr(float(x)) for x in r) + f",{60 * k},{20 + k / 10}"
                                 for k, r in enumerate(rows)) + "\n")
    fast = positions.read_positions(str(timed))
    monkeypatch.setattr(positions, "_numeric", lambda *a: None)
    slow = positions.read_positions(str(timed))
    monkeypatch.undo()
    assert all(np.array_equal(np.asarray(fast.extra[c]), slow.extra[c]) for c in ("time_s", "temp_c"))
    assert isinstance(fast.extra["time_s"], np.ndarray)
    path.write_text(path.read_text().replace(repr(float(rows[7, 3])), "nan", 1))
    with pytest.raises(DataError, match="line 9: column f2"):
        positions.read_positions(str(path))


def test_a_plan_file_with_other_numeric_columns_is_read_in_c_and_a_text_column_falls_back(tmp_path, monkeypatch):
    # A data file used as a plan: its angle columns, the same whether read in C or cell by cell; a text
    # column sends it to the cell-by-cell reader (whose parse of quotes loadtxt does not share).
    from garant.verify.io import positions
    rng = np.random.default_rng(1)
    rows = np.column_stack([rng.uniform(0, 360, (30, 2)), rng.normal(0, 9.81, (30, 3))])
    path = tmp_path / "p.csv"
    path.write_text("f1,alpha_deg,f2,beta_deg,f3\n" + "\n".join(
        ",".join(repr(float(x)) for x in (r[2], r[0], r[3], r[1], r[4])) for r in rows) + "\n")
    assert positions._numeric(str(path), ["alpha_deg", "beta_deg"]) is not None
    fast, _ = positions.read_plan(str(path), ("alpha", "beta"))
    assert np.array_equal(fast, rows[:, :2])
    monkeypatch.setattr(positions, "_numeric", lambda *a, **k: None)
    slow, _ = positions.read_plan(str(path), ("alpha", "beta"))
    assert np.array_equal(fast, slow)
    monkeypatch.undo()
    text = path.read_text().splitlines()
    quoted = tmp_path / "q.csv"
    quoted.write_text("\n".join([text[0] + ",note"] + [t + ',"a, b"' for t in text[1:]]) + "\n")
    assert positions._numeric(str(quoted), ["alpha_deg", "beta_deg"]) is None
    assert np.array_equal(positions.read_plan(str(quoted), ("alpha", "beta"))[0], rows[:, :2])
