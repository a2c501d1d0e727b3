"""garant next: a calibration session led position by position reaches the target in the
fewest positions of the plan search ((7)-(12) of 000: on the two-axis stand 10, since no plan of 9 serves
every q), every suggestion reachable, and data that refute sigma stop it."""
import json

import numpy as np
import pytest

import garant
from garant.verify import models
from garant.verify.cli import main

SIGMA = 1e-5


def _readings(tmp_path, model):
    """Readings of one simulated unit at every reachable quarter-turn position (the candidates)."""
    path = tmp_path / "all.csv"
    assert main(["simulate", "--model", model, "--plan", "quarter", "--sigma", str(SIGMA), "--seed", "3",
                 "-o", str(path)]) == 0
    lines = path.read_text().splitlines()
    return lines[0], lines[1:]


def _row_at(header, rows, position):
    cols = header.split(",")
    for row in rows:
        cells = row.split(",")
        angles = [float(cells[cols.index(c)]) for c in cols if c.endswith("_deg")]
        mount = cells[cols.index("mount")] if "mount" in cols else None
        if np.allclose(angles, position[:len(angles)]) and (mount is None or mount == position[-1]):
            return row
    raise AssertionError(f"no reading at {position}")


@pytest.mark.slow
@pytest.mark.parametrize("model", ["two-axis", "single-axis"])
def test_a_session_reaches_the_optimal_errors_in_the_fewest_positions(tmp_path, capsys, model):
    mod = models.load(model)
    header, rows = _readings(tmp_path, model)
    fewest = garant.plan(model).min_positions                     # 8 on single-axis (the plan search)
    assert model != "two-axis" or fewest == 10                    # 000: no plan of 9 serves every q
    session = tmp_path / "s.csv"
    session.write_text(header + "\n")
    ranges = getattr(mod, "ANGLE_RANGES_DEG", ((0, 360),) * len(mod.ANGLES))
    detents = getattr(mod, "ANGLE_DETENTS_DEG", ((),) * len(mod.ANGLES))
    needed = []
    for _ in range(fewest + 1):
        res = garant.next_position(model, str(session), SIGMA)
        if res.done:
            break
        needed.append(res.still_needed)
        assert res.still_needed_proven
        assert models.unreachable(ranges, detents, [res.next[:len(mod.ANGLES)]]) is None
        session.write_text(session.read_text() + _row_at(header, rows, res.next) + "\n")
    assert res.done and res.consistent
    assert needed == list(range(fewest, 0, -1))                   # each step one fewer: exact counts
    assert all(e <= t * (1 + 1e-7) for e, t in zip(res.guaranteed_error_before, res.target))
    # the command says the same, in one step from the same file, and writes its JSON
    assert main(["next", "--model", model, str(session), "--sigma", str(SIGMA), "--json",
                 str(tmp_path / "n.json")]) == 0
    assert "done" in capsys.readouterr().out
    assert json.loads((tmp_path / "n.json").read_text())["done"]


@pytest.mark.slow
def test_data_that_refute_sigma_stop_the_session(tmp_path, capsys):
    header, rows = _readings(tmp_path, "two-axis")
    cells = rows[0].split(",")
    cells[4] = str(float(cells[4]) + 0.1)                        # f3 of the first position 1000 sigma off
    (tmp_path / "s.csv").write_text("\n".join([header, ",".join(cells), *rows[1:]]) + "\n")
    assert main(["next", "--model", "two-axis", str(tmp_path / "s.csv"), "--sigma", str(SIGMA)]) == 3
    assert "refute sigma" in capsys.readouterr().out


def test_a_target_below_the_optimum_is_refused_and_a_looser_one_is_reached(tmp_path, capsys):
    header, rows = _readings(tmp_path, "two-axis")
    (tmp_path / "s.csv").write_text(header + "\n")
    assert main(["next", "--model", "two-axis", str(tmp_path / "s.csv"), "--sigma", str(SIGMA),
                 "--target", "1e-6"]) == 2
    assert "below the stand's optimal error" in capsys.readouterr().err
    res = garant.next_position("two-axis", str(tmp_path / "s.csv"), SIGMA, target=3 * SIGMA)
    assert not res.still_needed_proven and res.still_needed >= 5    # 15 q, three readings per position


@pytest.mark.slow
def test_a_session_for_the_block_parameters_reaches_their_targets(tmp_path, capsys):
    """next --mount: the targets bound the block's parameters of (28)-(29) of 000 in the mounting the readings
    are in; each 'at least' of positions still needed is a true lower bound (never more than the session then
    took)."""
    header, rows = _readings(tmp_path, "two-axis")
    session = tmp_path / "s.csv"
    session.write_text(header + "\n")
    lower = []
    for _ in range(len(rows) + 1):
        res = garant.next_position("two-axis", str(session), SIGMA, mount="+x+y+z")
        if res.done:
            break
        assert "Gamma12" not in res.names and "theta_k3" in res.names    # zero by the split: no target
        lower.append(res.still_needed)
        session.write_text(session.read_text() + _row_at(header, rows, res.next) + "\n")
    assert res.done and res.consistent and lower
    assert all(lb <= len(lower) - k for k, lb in enumerate(lower))
    assert main(["next", "--model", "two-axis", str(session), "--sigma", str(SIGMA), "--mount", "+y+z+q"]) == 2
    assert "--mount needs" in capsys.readouterr().err


@pytest.mark.slow
def test_done_means_estimate_prints_every_bound_at_its_target(tmp_path):
    # next said "done" on 10 positions where estimate on the same readings printed a q9 bound 1.22x the
    # target (next planned with the nominal H; estimate linearises where the unit is and adds the remainder). A
    # MEMS-size unit at a vertex of its bounds, noise at +-sigma with the signs of the estimator whose
    # bound the unit moves most on the plan next led to before (there estimate printed 1.036x its target): a
    # session led by next to "done", and estimate on that file prints every bound at or below next's target.
    from conftest import write_csv
    from garant.verify import power
    from garant.verify.workflows import next as nx
    mod = models.load("two-axis")
    p = power.mems_truth(mod, np.random.default_rng(5), vertex=True)
    P = np.array([(a, b) for a in range(0, 360, 90) for b in range(0, 360, 90)], float)
    f = power.mems_readings(mod, P, None, p, np.zeros((len(P), 3)))
    plan = []                                   # where next at the nominal H alone says done
    while not (r := nx.next_position(mod, "two-axis", P[plan], np.zeros(len(plan), int), SIGMA)).done:
        plan.append(int(np.flatnonzero(np.all(np.abs(P - np.array(r.position[:2])) < 1e-9, axis=1))[0]))
    clean = garant.estimate("two-axis", str(write_csv(tmp_path / "c.csv", P[plan], f[plan])), SIGMA, g=power.G)
    nu = int(np.argmax([clean.a_priori["guaranteed_error"][n] / t for n, t in zip(mod.Q_NAMES, r.target)]))
    f[plan] += power.G * SIGMA * np.sign(power.estimator_weights(mod, P[plan], None, f[plan], nu)).reshape(-1, 3)
    taken = []
    for _ in range(len(P) + 1):
        res = garant.next_position("two-axis", str(write_csv(tmp_path / "s.csv", P[taken], f[taken])), SIGMA, g=power.G)
        if res.done:
            break
        taken.append(int(np.flatnonzero(np.all(np.abs(P - np.array(res.next[:2])) < 1e-9, axis=1))[0]))
    assert res.done and res.consistent and "estimate" in res.bounds_from
    est = garant.estimate("two-axis", str(tmp_path / "s.csv"), SIGMA, g=power.G)
    printed = np.array([est.guaranteed_error[n] for n in mod.Q_NAMES])
    assert np.all(printed <= np.array(res.target) * (1 + 1e-7)), printed / np.array(res.target)
