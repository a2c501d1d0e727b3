"""garant plan --route: the order of a plan's positions of least total stand time, exact by
Held-Karp (checked against every order by brute force), the trapezoidal move times, the schedule printed
and carried by plan -o."""
import itertools
import re

import numpy as np
import pytest

from garant.derive.builtin import STANDS_DIR
from garant.verify.cli import main
from garant.verify.solve import route as rt


def _brute(C, bottleneck=False):
    return min(rt._value(C, list(p), bottleneck) for p in itertools.permutations(range(len(C))))


@pytest.mark.parametrize("bottleneck", [False, True])
def test_held_karp_is_the_best_of_every_order(bottleneck):
    rng = np.random.default_rng(5)
    for n in (1, 2, 5, 7):
        C = rng.integers(1, 20, (n, n)).astype(float)           # asymmetric, with ties
        np.fill_diagonal(C, 0)
        order = rt.held_karp(C, bottleneck)
        assert sorted(order) == list(range(n))
        assert rt._value(C, order, bottleneck) == _brute(C, bottleneck)


def test_move_times_of_the_trapezoid_and_the_triangle():
    # 90 deg at 20 deg/s, 10 deg/s^2: 40 deg to reach the speed and stop, so 90/20 + 20/10 = 6.5 s;
    # 10 deg never reaches it: 2 sqrt(10/10) = 2 s; without acceleration, 90/20 = 4.5 s.
    assert rt.move_time(90.0, 20.0, 10.0) == pytest.approx(6.5)
    assert rt.move_time(10.0, 20.0, 10.0) == pytest.approx(2.0)
    assert rt.move_time(90.0, 20.0, None) == pytest.approx(4.5)
    # the short way round on a full turn, straight inside a limited range
    D = rt.travel([[0.0, 0.0], [270.0, 270.0]], [(0, 360), (0, 359)])
    assert D[0, 1].tolist() == [90.0, 270.0]


def _stand_with_speeds(tmp_path):
    text = (STANDS_DIR / "two_axis.toml").read_text()
    assert text.count("[[angle]]\n") == 2
    text = text.replace("[[angle]]\n", "[[angle]]\nspeed_deg_s = 20\nacceleration_deg_s2 = 10\n", 1)
    text = text.replace("\n[[angle]]\nname", "\n[[angle]]\nspeed_deg_s = 45\nacceleration_deg_s2 = 10\nname", 1)
    text = text.replace("[stand]\n", "[stand]\nsettle_s = 5\n", 1)
    path = tmp_path / "two_speed.toml"
    path.write_text(text)
    return path


@pytest.mark.slow
def test_the_route_of_the_two_axis_plan_is_the_fastest_order(tmp_path, capsys):
    import json
    path = _stand_with_speeds(tmp_path)
    assert main(["plan", "--model", str(path), "--route", "--json", str(tmp_path / "p.json"), "-o",
                 str(tmp_path / "r.csv")]) == 0
    out = capsys.readouterr().out
    d = json.loads((tmp_path / "p.json").read_text())
    r = d["route"]
    assert sorted(map(tuple, r["positions"])) == sorted(map(tuple, d["plan"]))
    assert r["method"].startswith("exact") and r["objective"] == "total stand time, s"
    total = float(re.search(r"total stand time: ([\d.]+) s", out).group(1))
    assert total == pytest.approx(r["total"], rel=1e-3)
    # every order of the first 8 positions of that plan, by brute force, against the exact route of them
    P = np.array(d["plan"], float)[:8]
    motion = rt.Motion((20.0, 45.0), (10.0, 10.0), 5.0)
    C = rt.costs(P, np.zeros(len(P), int), [(0, 360), (0, 360)], motion)
    assert rt._value(C, rt.held_karp(C), False) == pytest.approx(_brute(C))
    # and the route's own total is the sum of its moves' trapezoid times: no move is cheaper than its slowest angle
    C10 = rt.costs(np.array(r["positions"], float), np.zeros(10, int), [(0, 360), (0, 360)], motion)
    assert sum(C10[k, k + 1] for k in range(9)) == pytest.approx(r["total"])
    rows = (tmp_path / "r.csv").read_text().splitlines()
    assert rows[0] == "alpha_deg,beta_deg,order,move_s,arrive_s" and len(rows) == 11
    assert float(rows[-1].split(",")[-1]) == pytest.approx(r["total"], rel=1e-5)


def test_above_twelve_positions_the_heuristic_states_its_gap_to_a_lower_bound():
    P = np.array([[a, b] for a in (0, 90, 180, 270) for b in (0, 90, 180, 270)], float)
    C = rt.costs(P, np.zeros(16, int), [(0, 360), (0, 360)], rt.Motion((20.0, 45.0), (10.0, 10.0), 5.0))
    order, method, bound = rt.order(C)
    assert "2-opt" in method and sorted(order) == list(range(16))
    assert bound <= rt._value(C, order, False) <= rt._value(C, list(range(16)), False)


@pytest.mark.parametrize("bad", ["speed_deg_s = -1", 'speed_deg_s = "fast"', "speed_deg_s = 1e300"])
def test_a_motion_figure_that_is_not_a_positive_number_is_one_line(tmp_path, capsys, bad):
    text = (STANDS_DIR / "two_axis.toml").read_text().replace("[[angle]]\n", f"[[angle]]\n{bad}\n", 1)
    (tmp_path / "s.toml").write_text(text)
    assert main(["plan", "--model", str(tmp_path / "s.toml"), "--route"]) == 2
    err = capsys.readouterr().err
    assert "angle[1].speed_deg_s" in err and err.count("\n") == 1
