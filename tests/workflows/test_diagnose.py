"""The model-discrepancy workflow: hidden effects are named, clean data raises no alarm."""
import json

import numpy as np
import pytest

from garant.generated import two_axis as mod
from garant.derive.builtin import TWO_AXIS_MODEL as base
from garant.derive.effects import CATALOGUE
from garant.verify.workflows import diagnose, simulate
from garant.verify.cli import main
from garant.verify.io.positions import read_positions
from garant.verify.workflows.premises import premises

S = 1e-5
# Parameter scale that makes a value of k mean "k sigma" of effect on z (time up to ~96 min,
# temperature within about +-4.5 C of 20 C in simulated rows).
SCALE = {"bias_drift": 1 / 5760, "bias_temperature": 1 / 4.0, "scale_temperature": 1 / 4.0}


def run(tmp_path, plan, effects, seed):
    P, f, t, T, _, _ = simulate.simulate(base, mod, plan, effects, S, seed)
    path = tmp_path / "d.csv"
    simulate.write(path, P, f, t, T)
    res = diagnose.diagnose(base, mod, read_positions(str(path)), S, premises(mod, S, 9.81))
    res.pop("_study")
    return res


def values(name, k):
    n, s = len(CATALOGUE[name].params), SCALE.get(name, 1.0)
    return [k * S * s] + [0.0] * (n - 2) + ([-0.6 * k * S * s] if n > 1 else [])


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CATALOGUE))
@pytest.mark.parametrize("k, seed", [(3, 0), (10, 1), (20, 2)])
def test_hidden_effect_is_named(tmp_path, name, k, seed):
    res = run(tmp_path, "grid:30x45", [(name, values(name, k))], seed)
    assert not res["consistent_before"] and res["consistent_after"]
    assert res["effects"] == [name]
    first = CATALOGUE[name].params[0].name
    est = res["estimates"][first]
    assert abs(est["value"] - values(name, k)[0]) <= est["bound"] + 1e-7 * SCALE.get(name, 1)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(3))
def test_no_effect_no_alarm(tmp_path, seed):
    res = run(tmp_path, "grid:30x45", [], seed)
    assert res["consistent_before"] and res["effects"] == [] and res["consistent_after"]


@pytest.mark.slow
def test_two_hidden_effects_both_named(tmp_path):
    res = run(tmp_path, "grid:30x45", [("scale_quadratic", [8 * S, 0, 0]),
                                       ("bias_drift", [10 * S / 5760, 0, -5 * S / 5760])], 3)
    assert sorted(res["effects"]) == ["bias_drift", "scale_quadratic"] and res["consistent_after"]


@pytest.mark.slow
def test_invisible_effect_is_blind_not_guessed(tmp_path):
    # u_i u_j = 0 at every quarter-turn position: cross-coupling cannot show on quarter16.
    res = run(tmp_path, "quarter16", [("cross_coupling", [10 * S] * 6)], 0)
    assert "cross_coupling" in res["blind_to"] and res["effects"] == [] and res["consistent_before"]


@pytest.mark.slow
def test_indistinguishable_on_quarter_turns(tmp_path):
    # |u_i| = u_i^2 on quarter turns: asymmetry and quadratic scale explain the data equally.
    res = run(tmp_path, "quarter16", [("scale_asymmetry", [10 * S, 0, 0])], 0)
    assert sorted(res["indistinguishable"][0]) == ["scale_asymmetry", "scale_quadratic"]
    sep = res["separating_positions"][0]["positions"]
    assert all((p["alpha_deg"] % 90, p["beta_deg"] % 90) != (0, 0) for p in sep)


@pytest.mark.slow
def test_cli_simulate_and_diagnose(tmp_path, capsys):
    data, out = tmp_path / "d.csv", tmp_path / "r.json"
    assert main(["simulate", "--model", "two-axis", "--plan", "grid:30x45", "--effect",
                 "beta_encoder_harmonic=8e-5,-4e-5", "--sigma", str(S), "--seed", "4", "-o", str(data)]) == 0
    assert main(["diagnose", "--model", "two-axis", str(data), "--sigma", str(S), "--prior", "2e-4",
                 "--json", str(out), "--plot", str(tmp_path / "p.png"), "--report", str(tmp_path / "rep")]) == 0
    res = json.loads(out.read_text())
    for key in ("consistent_before", "max_residual_before", "effects", "indistinguishable", "consistent_after",
                "max_residual_after", "estimates", "blind_to"):
        assert key in res
    assert res["effects"] == ["beta_encoder_harmonic"]
    assert (tmp_path / "rep" / "two_axis_beta_encoder_harmonic.py").exists()
    assert (tmp_path / "p.png").stat().st_size > 10000


@pytest.mark.parametrize("argv, message", [
    (["simulate", "--model", "two-axis", "--plan", "grid:7x45", "--sigma", "1e-5", "-o", "x.csv"], "divide 360"),
    (["simulate", "--model", "two-axis", "--plan", "optimal10", "--effect", "warp=1", "--sigma", "1e-5", "-o", "x.csv"],
     "unknown effect 'warp'"),
    (["simulate", "--model", "two-axis", "--plan", "optimal10", "--effect", "bias_drift=1", "--sigma", "1e-5",
      "-o", "x.csv"], "takes 3 values"),
])
def test_bad_arguments(capsys, argv, message):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("stand, plan, effect, values", [
    ("single-axis", "grid:30", "scale_quadratic", [0, 1e-4, 0]),
    ("three-axis", "grid:90x45x90", "bias_drift", [1e-4 / 5000, 0, 0]),
])
def test_diagnose_described_stands(tmp_path, capsys, stand, plan, effect, values):
    # garant simulate and garant diagnose on the example stands of derive/stands/.
    data, out = tmp_path / "d.csv", tmp_path / "r.json"
    assert main(["simulate", "--model", stand, "--plan", plan, "--effect", f"{effect}=" + ",".join(map(str, values)),
                 "--sigma", str(S), "--seed", "1", "-o", str(data)]) == 0
    assert main(["diagnose", "--model", stand, str(data), "--sigma", str(S), "--prior", "2e-4",
                 "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    assert not res["consistent_before"] and res["effects"] == [effect] and res["consistent_after"]


@pytest.mark.slow
@pytest.mark.parametrize("pair, seed", [(("scale_quadratic", "bias_drift"), 0), (("cross_coupling",
                                                                                  "bias_temperature"), 1),
                                        (("beta_encoder_harmonic", "scale_asymmetry"), 2)])
def test_two_effects_at_two_sigma_both_named(tmp_path, pair, seed):
    # Two effects at once, each with a signature of 2 sigma (the largest change of a reading
    # it makes), default prior 1e-3: both are named.
    scaled = []
    for name in pair:
        unit = [1.0] + [0.0] * (len(CATALOGUE[name].params) - 1)
        _, f1, *_ = simulate.simulate(base, mod, "grid:30x45", [(name, unit)], S, seed)
        _, f0, *_ = simulate.simulate(base, mod, "grid:30x45", [(name, [0.0] * len(unit))], S, seed)
        scaled.append((name, [2.0 / (np.abs(f1 - f0).max() / 9.81 / S) * v for v in unit]))
    P, f, t, T, _, _ = simulate.simulate(base, mod, "grid:30x45", scaled, S, seed)
    simulate.write(tmp_path / "d.csv", P, f, t, T)
    res = diagnose.diagnose(base, mod, read_positions(str(tmp_path / "d.csv")), S, premises(mod, S, 9.81))
    named = set(res["effects"]) | {e for g in res["indistinguishable"] for e in g}
    assert set(pair) <= named and res["consistent_after"]


# At the noise floor for MEMS-size units, the fewest effects, random directions. The sets are
# those of python -m verify.power: a unit with random errors, the positions in a random order, each effect
# in a random direction of its parameters scaled to a signature (largest change of a reading) of a x sigma.
def _lab():
    from garant.verify import power
    return power, power.Lab("two-axis")


def test_the_net_signature_of_power_is_what_the_model_cannot_absorb():
    # python -m verify.power --net scales an effect by the part of its change no q absorbs (the minimax
    # residual after the best q). A change the model makes itself (H^T q) has none, whatever its size; a
    # single reading's bump keeps at most its own size. A raw signature in place of the net turns it red.
    from garant.verify.solve import lp
    from garant.verify.workflows import simulate
    power, lab = _lab()
    P, mounts = simulate.plan_positions(lab.mod, "grid:90x60")
    A = lp.measurement_matrix(lab.mod, np.deg2rad(P), mounts)
    absorbed = (A.T @ np.random.default_rng(0).normal(0, 1e-4, A.shape[0])).reshape(-1, 3)
    assert lab.signature(absorbed, P, mounts, net=False) > 10
    assert lab.signature(absorbed, P, mounts, net=True) < 1e-6
    bump = np.zeros((len(P), 3))
    bump[5, 1] = 3 * power.SIGMA
    assert 0.1 < lab.signature(bump, P, mounts, net=True) <= 3 * (1 + 1e-9)
    assert lab.signature(bump, P, mounts, net=False) == pytest.approx(3)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_an_encoder_harmonic_near_the_floor_is_named_for_a_mems_size_unit(seed):
    # Red when, with scale errors of 1e-2 and biases of 5e-2 g, the allowance for the nonlinearity around
    # zero errors swamps a harmonic at 1.8 sigma on 96 positions and nothing is named.
    power, lab = _lab()
    pos = power.make_set(lab, "grid:30x45", "MEMS", {"alpha_encoder_harmonic": 1.8}, "uniform", seed)
    named, tied, consistent, _ = power.diagnosis(lab, pos)
    assert not consistent and "alpha_encoder_harmonic" in named | tied
    assert named <= {"alpha_encoder_harmonic"} | tied


@pytest.mark.slow
@pytest.mark.parametrize("size, noise, seed", [("MEMS", "uniform", 0), ("MEMS", "clipped", 1), ("small", "clipped", 2)])
def test_clean_sets_raise_no_alarm_whatever_the_unit(size, noise, seed):
    power, lab = _lab()
    named, _, consistent, _ = power.diagnosis(lab, power.make_set(lab, "grid:30x45", size, {}, noise, seed))
    assert consistent and not named


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_effects_at_two_sigma_are_named_and_no_third(seed):
    # Red when a temperature coefficient and quadratic scale factor at 2 sigma each bring scale_asymmetry in
    # as a third effect (forward selection not asking whether a named effect is still needed).
    power, lab = _lab()
    hidden = {"bias_temperature": 2.0, "scale_quadratic": 2.0}
    pos = power.make_set(lab, "grid:30x45", "small", hidden, "uniform", seed)
    found, spurious, refuted = power.outcome(lab, pos, set(hidden))
    assert refuted and found and not spurious


class _Columns:
    """A study stand-in for select(): a constant base row and an effect's row per name (the measurement
    matrix of the fit), residuals z_fit."""

    def __init__(self, cols, z):
        self.cols, self.z_fit = cols, np.asarray(z, float)

    def A_fit(self, names):
        return np.vstack([np.ones(len(self.z_fit))] + [self.cols[n] for n in names])


def test_an_effect_forward_selection_took_is_dropped_when_the_others_do_without_it():
    # Found by a random search over small problems: forward selection takes a, b, d, e, c (each step the
    # largest drop of the minimax residual) and is consistent only with all five; without b the other four
    # are consistent too, so b is not named.
    cols = {"a": [-1.169, 0.371, -1.842, -0.157, 1.332, 0.503, -0.850],
            "b": [0.679, -0.133, -0.624, 1.125, 0.380, -1.960, -0.641],
            "c": [1.543, -0.115, 1.980, 0.754, 0.949, -1.665, -0.477],
            "d": [1.508, 1.373, 0.196, -0.664, -0.898, -0.272, -0.107],
            "e": [-0.981, -0.974, 0.567, 1.267, 0.415, 0.117, 1.366]}
    study = _Columns({k: np.array(v) for k, v in cols.items()}, [-1, 2, -3, 0, 2, -1, -1])
    rb, sigma = np.zeros(7), 0.05
    t0 = diagnose.chebyshev_fit(study.A_fit([]), study.z_fit, rb)[1]
    chosen, history, _ = diagnose.select(study, list(cols), rb, sigma, t0)
    forward = [min(h["scores"], key=h["scores"].get) for h in history]
    assert forward == ["a", "b", "d", "e", "c"]
    assert sorted(chosen) == ["a", "c", "d", "e"]
    assert diagnose.chebyshev_fit(study.A_fit(chosen), study.z_fit, rb)[1] <= sigma
