"""A still warm-up (PX4's and ArduPilot's thermal calibration: the board in one orientation while it heats):
`calibrate-norm LOG --thermal-degree D` on a log that holds one orientation.

Each axis's raw reading is a polynomial of degree D in T about t0, the middle of the range, its coefficients over
the information set (every polynomial that meets each still piece's mean within its noise rule: LPs proven by
duality, solve/hull.py). One orientation cannot separate a bias drift from a drift of the scale factors and
misalignments times the gravity they act on: the reading's drift is their sum. The flight stacks' files hold the
bias's drift alone (offset polynomials); garant writes them under a stated premise, an a-priori bound S on the
drift of each entry of Gamma (|Gamma_ij(T) - Gamma_ij(t0)| <= S |T - t0|, the sensor's datasheet figure: `--bound
scale_drift=S`), the offset polynomial's bound widened by it: |g (beta_i(T) - beta_i(t0)) - d_i(T)| <= |d_i(T) -
d^_i(T)| + S |T - t0| sum_j |w_j|, d_i the reading's drift and w the gravity in the raw axes. The accelerometer
calibration at t0 (offsets, scales) is left as the vehicle has it: a still log does not give it.
"""
import numpy as np

from ..errors import DataError

#: The scale and misalignment drift assumed where none is stated (per C): 100 ppm/C, a MEMS accelerometer's typical
#: datasheet figure. A premise, printed with every bound that rests on it.
SCALE_DRIFT_DEFAULT = 1e-4


def _box(tau, r, e, D):
    """A box every polynomial of the set lies in (its coefficients): any D + 1 pieces at distinct temperatures
    interpolate it, so |c| <= |V^-1| (|r| + e) on them (V their Vandermonde matrix in tau)."""
    pick = np.argsort(tau)[np.round(np.linspace(0, len(tau) - 1, D + 1)).astype(int)]     # spread over the range
    V = np.vander(tau[pick], D + 1, increasing=True)
    if np.ptp(tau[pick]) == 0 or len(np.unique(tau[pick])) < D + 1:
        raise DataError(f"the still pieces hold fewer than {D + 1} distinct temperatures: no polynomial of degree {D}",
                        param="log")
    return (np.abs(np.linalg.inv(V)) @ (np.abs(r[pick]) + e[pick])) * (1 + 1e-6) + 1e-12


def fit(data, stills, note, g, quantum, degree=1, scale_drift=None):
    """The still warm-up's result: per axis the raw reading's polynomial about t0 with its coefficients' bounds
    over the information set, the drift over the range, what one orientation cannot separate, and (consistent) the
    offset polynomials the flight stacks load, under the scale-drift premise (`thermal`, offsets_only)."""
    from ..io import recordings
    from ..solve import hull
    from .norm_noise import noise_axes, noise_rule_name
    from .norm_thermal import SPLIT_C
    e, rule = noise_axes(stills, quantum), noise_rule_name(stills, quantum)
    temps = np.array([float(np.mean(data.temp[(data.t >= st.start) & (data.t <= st.stop)])) for st in stills])
    if len(stills) < degree + 1 or temps.max() - temps.min() < 2 * SPLIT_C:
        raise DataError(f"{data.path}: one orientation over {temps.min():.1f}-{temps.max():.1f} C in {len(stills)} "
                        f"still piece(s): a drift of degree {degree} in T needs {degree + 1} pieces or more and the "
                        f"temperature to move by {2 * SPLIT_C:g} C or more while the unit is still", param="log")
    t_lo, t_hi = float(temps.min()), float(temps.max())
    t0 = round(0.5 * (t_lo + t_hi), 1)
    tau, R = temps - t0, max(t_hi - t0, t0 - t_lo)
    r = np.array([st.mean for st in stills])
    B = np.vander(tau, degree + 1, increasing=True)
    span = np.array([[(t_hi - t0) ** k - (t_lo - t0) ** k for k in range(degree + 1)]])
    ctl = _control_rows(degree, t_lo - t0, t_hi - t0)
    C = np.vstack([np.eye(degree + 1), span, ctl])       # the coefficients, the drift over the range, its controls
    drift, coeffs, consistent = {}, {}, True
    for i in range(3):
        box = _box(tau, r[:, i], e[:, i], degree)
        try:
            lo, hi = hull.ranges(B, r[:, i] - e[:, i], r[:, i] + e[:, i], -box, box, C)
        except hull.Empty:
            consistent = False
            break
        n = degree + 2                                   # the coefficients and the drift over the range; controls after
        mid, half = 0.5 * (lo[:n] + hi[:n]), 0.5 * (hi[:n] - lo[:n]) * (1 + 1e-9)
        v = ctl @ mid[:-1]                               # the written polynomial's control points
        worst = np.maximum(hi[n:] - v, v - lo[n:]).max() + 1e-12 * (np.abs(ctl) @ np.abs(mid[:-1])).max()
        coeffs["xyz"[i]] = (mid[:-1], half[:-1], float(worst) * (1 + 1e-9))
        drift["xyz"[i]] = {"at_t0": float(mid[0]), "at_t0_bound": float(half[0]),
                           "slope": float(mid[1]), "slope_bound": float(half[1]),
                           "over_range": float(mid[-1]), "over_range_bound": float(half[-1])}
        if degree > 1:
            drift["xyz"[i]].update(coefficients=mid[:-1].tolist(), coefficient_bounds=half[:-1].tolist())
    unit = recordings.raw_unit(r, g)
    w = r.mean(axis=0)
    share = w / np.linalg.norm(w)
    S, stated = (SCALE_DRIFT_DEFAULT, False) if scale_drift is None else (float(scale_drift), True)
    premise = (f"the bounds hold if each axis of each still piece's raw mean is within its noise rule of the truth "
               f"({rule}) and each axis's reading is a polynomial of degree {degree} in the temperature over the range")
    out = {"log": data.path, "still_only": True, "consistent": consistent, "intervals": len(stills),
           "still_note": note, "samples": len(data.t), "duration_s": float(data.t[-1]), "raw_unit": unit,
           "t0_c": t0, "range_c": [t_lo, t_hi], "degree": degree, "drift": drift if consistent else None,
           "direction": share.tolist(),
           "not_separated": (f"one orientation (gravity along {', '.join(f'{v:+.3f}' for v in share)} in the raw "
                             "axes) cannot separate a bias drift from a scale-factor drift times that axis's share "
                             "of g, nor give the scale factors and biases themselves: each drift is their sum, right "
                             "in this orientation only; the flight stacks' offset polynomials are written under a "
                             "stated bound of the scale and misalignment drift (--bound scale_drift=S, per C), or "
                             "turn the unit through orientations while it warms to separate them"),
           "premises": {"statement": premise, "g": g}}
    if consistent and unit == "m/s^2":
        out["thermal"] = offsets(coeffs, t0, (t_lo, t_hi), degree, S, stated, np.abs(w).sum(), R, g, premise)
        out.update(g=g, definitions=out["thermal"]["definitions"], scale_drift={"bound_per_c": S, "stated": stated})
    return out


def _control_rows(degree, a, b):
    """The Bernstein control points, on each of norm_thermal.PIECES pieces of [a, b], of the drift relative to t0,
    psi(tau) = sum_{k >= 1} c_k tau^k, as rows over the coefficients c: psi on a piece is their convex combination,
    so the largest |psi - psi^| over the set is the largest over them (each an LP pair, workflows/thermal.py)."""
    from .norm_thermal import PIECES
    from .thermal import bernstein
    xs = [np.zeros(degree + 1)] + [np.eye(degree + 1)[k] for k in range(1, degree + 1)]
    cuts = np.linspace(a, b, PIECES + 1)
    return np.unique(np.vstack([bernstein(xs, lo, hi) for lo, hi in zip(cuts[:-1], cuts[1:])]), axis=0)


def offsets(coeffs, t0, t_range, degree, S, stated, w_sum, R, g, premise):
    """The thermal block the exports write (io/tcal.py, offsets_only): each axis's offset polynomial relative to t0
    (over g, no constant: the stacks' offset is relative, X0 = 0 at TREF), and its one bound over the range: the
    largest error of the drift over the information set (its Bernstein control points, `_control_rows`) plus the
    premise's S R sum_j |w_j|."""
    q, bound = {}, {}
    for i, a in enumerate("xyz"):
        mid, _, worst = coeffs[a]
        q[f"bias{i + 1}"] = [0.0] + (mid[1:] / g).tolist()
        bound[f"bias{i + 1}"] = float((worst + S * R * w_sum) / g * (1 + 1e-9))
    source = ("--bound scale_drift" if stated else
              "assumed: a typical MEMS datasheet figure; state the sensor's with --bound scale_drift=S")
    said = (f"each entry of Gamma (scale factors and misalignments) drifts by at most {S:g} per C from its value at "
            f"t0 = {t0:g} C ({source})")
    units = ["1 (over g)"] + [f"1/degC{'' if k == 1 else f'^{k}'} (over g)" for k in range(1, degree + 1)]
    return {"degree": degree, "t0_c": t0, "range_c": list(t_range), "q": q, "bound": bound, "offsets_only": True,
            "units": {f"bias{i + 1}": units for i in range(3)},
            "definitions": {f"bias{i + 1}": f"bias{i + 1}" for i in range(3)},
            "premise": premise + "; " + said, "command": "calibrate-norm"}
