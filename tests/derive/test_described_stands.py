"""The target: five stands that are not built in run derive -> plan -> simulate -> estimate
-> diagnose. The readings are made here by an exact rotation chain written independently of garant
(numpy, passive rotations C_n(x) = cos x E + (1 - cos x) n n^T - sin x [n x]); each q must lie within
its guaranteed bound of the truth, and every plan certificate must pass `garant check-certificate`."""
import json

import numpy as np
import pytest

from garant.verify import models
from garant.verify.cli import main
from conftest import C, STANDS

G = 9.81
SIGMA = 1e-5
X, Y, Z = np.eye(3)



def mounting(name):
    """v_block = Q v_table: block axis i along the table axis the name gives (e.g. +z+x+y)."""
    axes = {"x": X, "y": Y, "z": Z}
    return np.array([(1 if name[2 * i] == "+" else -1) * axes[name[2 * i + 1]] for i in range(3)])


#: Each stand's chain, base side last (the product applied to e3), from its description file.
CHAINS = {
    "wedge45": lambda a, e: (C(Z, a["phi"] - e["dphi"]) @ C(Y, e["kappa2"]) @ C(X, e["kappa1"])
                             @ C(X, np.pi / 4 + e["w"])),
    "wedge90": lambda a, e: (C(Z, a["phi"] - e["dphi"]) @ C(Z, e["kappa2"]) @ C(X, e["kappa1"])
                             @ C(X, np.pi / 2 + e["w"])),
    "tilted_inner": lambda a, e: C([0, 1, 1], a["b"] - e["db"]) @ C(X, a["a"] - e["da"]) @ C(Y, e["kappa"]),
    "table120": lambda a, e: C(X, a["phi"] - e["dphi"]) @ C(Y, e["kappa"]),
    "cradle180": lambda a, e: C(Z, a["b"] - e["db"]) @ C(X, a["a"] - e["da"]) @ C(Y, e["kappa"]),
}


def readings(stand, mod, angles_deg, mounts, e):
    """f (m/s^2) = g [(E + Gamma)(1 - dg) Q Theta chain e3 + bias]."""
    Gamma = np.array([[e[f"Gamma{i}{j}"] for j in (1, 2, 3)] for i in (1, 2, 3)])
    bias = np.array([e[f"bias{i}"] for i in (1, 2, 3)])
    th = [e[n] for n in ("theta1", "theta2", "theta3")]
    Theta = C(Z, th[2]) @ C(Y, th[1]) @ C(X, th[0])
    out = []
    for deg, m in zip(angles_deg, mounts):
        a = dict(zip(mod.ANGLES, np.deg2rad(deg)))
        u = CHAINS[stand](a, e) @ Z
        out.append(G * ((np.eye(3) + Gamma) @ ((1 - e["dg"]) * mounting(m) @ Theta @ u) + bias))
    return np.array(out)


@pytest.mark.slow
@pytest.mark.parametrize("stand", sorted(CHAINS))
def test_derive_plan_simulate_estimate_diagnose(stand, tmp_path, capsys):
    toml = str(STANDS / f"{stand}.toml")
    assert main(["derive", toml, "--out", str(tmp_path / "gen")]) == 0
    plan, certs = tmp_path / "plan.csv", tmp_path / "certs"
    assert main(["plan", "--model", toml, "-o", str(plan), "--certificates", str(certs), "--count-nodes", "5"]) == 0
    mod = models.load(toml)
    files = sorted(certs.glob("*.json"))
    assert len(files) == len(mod.Q_NAMES)                  # every q's optimality on the plan's candidates
    for f in files:
        assert main(["check-certificate", str(f)]) == 0, f.name
    capsys.readouterr()

    # simulate reads the plan file `plan` wrote, honours the stand, and saves the truth beside the data
    assert main(["simulate", "--model", toml, "--plan", str(plan), "--sigma", str(SIGMA), "-o",
                 str(tmp_path / "sim.csv")]) == 0
    assert (tmp_path / "sim.truth.json").is_file()

    # the independent chain: data at the plan's positions, every error nonzero
    rng = np.random.default_rng(7)
    e = {n: float(v) for n, v in zip(mod.PARAMETER_NAMES, rng.uniform(-3e-4, 3e-4, len(mod.PARAMETER_NAMES)))}
    head = plan.read_text().splitlines()
    cols = head[0].split(",")
    rows = [r.split(",") for r in head[1:]]
    angles = np.array([[float(r[cols.index(f"{a}_deg")]) for a in mod.ANGLES] for r in rows])
    mounts = [r[cols.index("mount")] for r in rows] if "mount" in cols else ["+x+y+z"] * len(rows)
    f = readings(stand, mod, angles, mounts, e) + G * rng.uniform(-SIGMA / 2, SIGMA / 2, (len(rows), 3))
    data = tmp_path / "data.csv"
    lines = [",".join(cols + ["f1", "f2", "f3"])]
    lines += [",".join(r + [repr(float(v)) for v in fk]) for r, fk in zip(rows, f)]
    data.write_text("\n".join(lines) + "\n")
    out = tmp_path / "est.json"
    assert main(["estimate", "--model", toml, str(data), "--sigma", str(SIGMA), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    truth = models.q_of(mod, [e[n] for n in mod.PARAMETER_NAMES])
    for k, q in enumerate(mod.Q_NAMES):
        assert abs(res["q"][q] - truth[k]) <= res["guaranteed_error"][q], q
    capsys.readouterr()
    assert main(["diagnose", "--model", toml, str(data), "--sigma", str(SIGMA)]) == 0
    assert "consistent" in capsys.readouterr().out


def test_a_plan_certificate_is_tied_to_its_description(tmp_path, capsys):
    """Change the description after the certificate was made, or forge its dual: rejected."""
    toml = tmp_path / "wedge45.toml"
    toml.write_text((STANDS / "wedge45.toml").read_text())
    certs = tmp_path / "certs"
    assert main(["plan", "--model", str(toml), "--certificates", str(certs)]) == 0
    cert = certs / "wedge45_plan_q1.json"
    assert main(["check-certificate", str(cert)]) == 0
    forged = json.loads(cert.read_text())
    forged["dual"] = ["1" if i == 0 else "0" for i in range(len(forged["dual"]))]   # the value then differs
    (tmp_path / "forged.json").write_text(json.dumps(forged))
    assert main(["check-certificate", str(tmp_path / "forged.json")]) == 1
    toml.write_text(toml.read_text().replace("angle_deg = 45", "angle_deg = 30"))
    capsys.readouterr()
    assert main(["check-certificate", str(cert)]) == 1
    assert "SHA-256 differs" in capsys.readouterr().out


@pytest.mark.slow
def test_two_axis_plans_on_finer_grids_are_the_quarter_turn_plans(capsys):
    """The number of optimal 10-position plans on the 30-degree grid, exactly confirmed: the
    same 64 as on quarter turns (Table 2 of 000), every one on quarter turns."""
    assert main(["plan", "--model", "two-axis", "--grid", "30", "--count-nodes", "5000"]) == 0
    out = capsys.readouterr().out
    assert "optimal plans of 10 positions on that grid: 64;" in out and "every one on quarter turns" in out
    assert "confirmed exactly" in out
