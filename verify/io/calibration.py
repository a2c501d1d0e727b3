"""Calibration files: garant's own JSON (versioned, read back by `garant apply`) and imu_tk's text form.

garant-calibration-1 (every number in SI units unless the field says otherwise):

    format        "garant-calibration-1"
    kind          "norm" (a static log through (2.2) of 001) or "stand" (an estimate on a stand, 000)
    model         "a = M (raw - b)": corrected specific force a in m/s^2 from the raw reading
    raw_unit      what `raw` is measured in ("m/s^2", or "count" for a raw-count log)
    M             3 x 3, m/s^2 per raw unit, lower-triangular (garant's convention)
    b             3, raw units
    bound_matrix  3 x 3 B >= 0, dimensionless: |A| <= B for the residual errors A of a corrected sample,
                  a = (E + A) a_true + eps (norm: lower-triangular, [[lambda1, 0, 0], [alpha, lambda2, 0],
                  [beta, gamma, lambda3]]; stand: `through_M`)
    bound_bias    3, m/s^2: |eps| <= bound_bias, the worst-case residual biases
    bound_delta   3, dimensionless (x g): the worst-case nonlinearity of the 12-parameter model, or zeros
    delta         3, dimensionless (x g), optional: the estimated nonlinearity of the 12-parameter model,
                  taken out of each sample by apply (zeros, or absent, for 9 parameters and a stand)
    pendulosity_axes  the axes (i, j, k) of the nonlinearity terms delta_l n_axis(l) n_l
    g             m/s^2, the gravity the calibration used
    source        the log it was made from; note: how the bound of a sample follows (below)

A corrected sample a is within (I - B)^-1 (B |a| + bound_bias + g bound_delta_l |n_axis(l) n_l|) of the
true specific force, component-wise (n = a / |a|): with the residual errors A (|A| <= B) the truth is
(E + A)^-1 (a - eps), and |(E + A)^-1 v| <= sum_k B^k |v| = (I - B)^-1 |v| for B >= 0 whose rows sum
below 1 (the reader checks it).

imu_tk (CalibratedTriad::save/load): 9 numbers of T (row-major), 9 of K, 3 of B, for
X' = T K (X - B). garant writes T = M diag(M)^-1 (unit diagonal, the general form of imu_tk's T),
K = diag(M), B = b, so X' = M (X - b) exactly.
"""
import json

import numpy as np

from ..errors import DataError, opt
from . import files, recordings, schemas
from .report import json_value, write_json, write_text

FORMAT = "garant-calibration-1"
MAX_BYTES = 1_000_000
#: The largest condition number of M a calibration may have (an accelerometer's M is near a scaled rotation).
MAX_CONDITION = 1e3


def from_norm(res, axes):
    """The calibration dictionary of a consistent `calibrate-norm` result (catalogue effects, --effect, add their
    entry: workflows/norm_effects.py `file_entry`)."""
    e = res["guaranteed_error_q"]                 # bounds of the correction (I + A) of the calibrated block
    B = np.array([[e["lambda1"], 0.0, 0.0], [e["alpha"], e["lambda2"], 0.0], [e["beta"], e["gamma"], e["lambda3"]]])
    eps = res["g"] * np.array([e[f"eps{i}/g"] for i in (1, 2, 3)])
    delta = [e.get(f"delta{i}*g", 0.0) for i in (1, 2, 3)]
    # The file's M is (E + A_mid)^-1 M_fit (the information set's midpoint folded into the fit), the truth's
    # (E + A)^-1 M_fit: a sample's residual errors are (E + A_mid)^-1 (A - A_mid) and (E + A_mid)^-1 g dq_eps,
    # so the bounds of the correction reach it through |(E + A_mid)^-1| = |M M_fit^-1|.
    K = np.abs(np.asarray(res["matrix"]) @ np.linalg.inv(np.asarray(res["matrix_fit"]))) if "matrix_fit" in res \
        else np.eye(3)
    B, eps = (K @ B) * (1 + 1e-12), (K @ eps) * (1 + 1e-12)
    # M holds g = res["g"]; a true g_t moves a corrected sample by the factor g / g_t, within 1 +- u
    # (u, the bound of |Delta_g/g|): E + A becomes (1 + d)(E + A), so |A| <= B + u (E + B), |eps| scales alike
    u = res.get("g_uncertainty", 0.0)
    B, eps = (B + u * (np.eye(3) + B)) * (1 + 1e-12), eps * (1 + u) * (1 + 1e-12)
    out = {"format": FORMAT, "kind": "norm", "model": "a = M (raw - b)", "raw_unit": res["raw_unit"],
           "M": res["matrix"], "b": res["bias"], "bound_matrix": B.tolist(),
           "bound_bias": eps.tolist(), "bound_delta": delta,
           "delta": list(res.get("nonlinearity_delta_g") or [0.0, 0.0, 0.0]),
           "pendulosity_axes": list(axes), "g": res["g"], "source": res["log"],
           "note": "per-sample bound: (I - B)^-1 (B |a| + bound_bias + g bound_delta_l |n_axis(l) n_l|), n = a/|a|",
           "premises": res["premises"]["statement"]}
    st = res.get("_information_set")
    if st is not None:
        out["information_set"] = dict(st, g_uncertainty=float(u))
        out["note"] += SET_NOTE
    return out


#: What a file with its information set adds to its note.
SET_NOTE = ("; or, where smaller, the error's largest value over information_set (its unknowns linear in the "
            "error; workflows/sample_set.py)")


def through_M(G, B, bias_bound, g_uncertainty=0.0):
    """(M, bound_matrix, bound_bias) of a stand calibration from the block's Gamma estimate G (3 x 3, or a stack
    (N, 3, 3) with B and bias_bound broadcast: one per sample of a calibration over temperature), the
    entrywise bound B of Gamma - G and the bound of the biases (m/s^2). With f = (E + Gamma) a + bias
    and the file's M = (E + G)^-1 (as rounded), a corrected sample is M (f - b) = (E + A) a + eps with
        A = M (E + G) - E + M (Gamma - G),   eps = M (bias - b),
    so |A| <= |M (E + G) - E| + |M| B and |eps| <= |M| bias_bound: the factor M (about 1 / (1 + Gamma_ii))
    is in the bound, not left out.

    Where Gamma is relative to the g given (the block absorbs Delta_g, `g_uncertainty` u its bound on
    |Delta_g/g|), the data fix E + Gamma = c (E + Gamma_t) with c = g_t / g in [1 - u, 1 + u] and Gamma_t the
    block's own errors: a corrected sample is M (E + Gamma) a / c + eps, so
        |A| <= (|M (E + G) - E| + |M| B) / (1 - u) + u / (1 - u) E,
    the error of g itself not scaled by M (it is g_t - g in the sample, whatever the block's scale)."""
    G, B = np.asarray(G, float), np.asarray(B, float)
    M = np.linalg.inv(np.eye(3) + G)
    absM = np.abs(M)
    left = np.abs(M @ (np.eye(3) + G) - np.eye(3)) + 8 * np.finfo(float).eps * (absM @ (1 + np.abs(G)))
    u = float(g_uncertainty)
    bound = ((left + absM @ B) / (1 - u) + u / (1 - u) * np.eye(3)) * (1 + 1e-12)
    return M, bound, (absM @ np.asarray(bias_bound, float)[..., None])[..., 0] * (1 + 1e-12)


def from_stand(res, st=None):
    """The calibration dictionary of a consistent stand estimate with the block's physical errors
    ((28)-(29) of 000): a = (E + Gamma)^-1 (f - bias) for readings f in m/s^2. The bounds of Gamma hold
    Delta_g/g on its diagonal (a premise: the stand cannot separate it from the scale factors); they reach
    the sample through M (`through_M`); the premises travel with the file."""
    G, eG = np.array(res["physical"]["Gamma"]), np.array(res["physical_bound"]["Gamma"])
    M, B, eb = through_M(G, np.abs(eG), res["physical_bound"]["bias"])
    out = {"format": FORMAT, "kind": "stand", "model": "a = M (raw - b)", "raw_unit": "m/s^2",
           "M": M.tolist(), "b": list(res["physical"]["bias"]), "bound_matrix": B.tolist(),
           "bound_bias": eb.tolist(), "bound_delta": [0.0, 0.0, 0.0],
           "pendulosity_axes": [2, 3, 1], "g": res["g"], "source": f"{res['model']} estimate, mounting {res['mount']}",
           "note": "per-sample bound: (I - B)^-1 (B |a| + bound_bias); B = |M (E + Gamma) - E| + |M| (the bounds of "
                   "Gamma, Delta_g/g on its diagonal), bound_bias = |M| (the bounds of the biases)",
           "premises": res["premises"]["statement"]}
    return out if st is None else with_set(out, st, st["g_uncertainty"])


def from_block(res, st=None):
    """The calibration dictionary of a consistent estimate on any stand: the block's Gamma and biases over
    the information set (workflows/block.py); a = (E + Gamma)^-1 (f - bias) for readings f in m/s^2.
    Each bound already holds the a-priori bounds of what the parameter is confounded with (Delta_g on the
    diagonal); where the block absorbs Delta_g (its Gamma is relative to the g given) the uncertainty of g
    enters the per-sample bound as the relative error of g it is, after M (`through_M`), so the bound is one
    in m/s^2 of the true specific force. `st`: the block's information set (workflows/block.py), which the file
    carries for apply (workflows/sample_set.py)."""
    blk, prem = res["block"], res["premises"]
    G, g = np.asarray(blk["Gamma"]), res["g"]
    u = g_uncertainty(res)
    M, B, eb = through_M(G, blk["Gamma_bound"], g * np.asarray(blk["bias_bound"]), u)
    out = {"format": FORMAT, "kind": "stand", "model": "a = M (raw - b)", "raw_unit": "m/s^2",
            "M": M.tolist(), "b": (g * np.asarray(blk["bias"])).tolist(),
            "bound_matrix": B.tolist(), "bound_bias": eb.tolist(), "bound_delta": [0.0, 0.0, 0.0],
            "pendulosity_axes": [2, 3, 1], "g": g, "source": f"{res['model']} estimate",
            "note": "per-sample bound: (I - B)^-1 (B |a| + bound_bias); B = " + (
                        "(" if u else "") + "|M (E + Gamma) - E| + |M| (the bounds of Gamma, each with the a-priori "
                    "bounds of what it is confounded with)" + (
                        f") / (1 - u) + u / (1 - u) E, u = {u:g} the bound of |Delta_g/g| (Gamma is relative to g = "
                        f"{g:g} m/s^2)" if u else "") + ", bound_bias = |M| (the bounds of the biases)",
            "premises": " ".join(filter(None, (prem["statement"] + ".", prem.get("meaning"))))}
    return out if st is None else with_set(out, st, u)


def with_set(cal, st, u):
    """The calibration dictionary `cal` carrying the information set `st` (workflows/sample_set.py) with u, the
    bound of |Delta_g/g| its per-sample bound holds, and its note saying so."""
    cal["information_set"] = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in st.items()}
    cal["information_set"]["g_uncertainty"] = float(u)
    cal["note"] += SET_NOTE
    return cal


BLOCK_NAMES = tuple(f"Gamma{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)) + ("bias1", "bias2", "bias3")


def g_uncertainty(res):
    """The bound of |Delta_g/g| where the block absorbs Delta_g (its Gamma is relative to the g given), else 0."""
    prem = res["premises"]
    gravity = any(prem["a_priori"][n]["kind"] == "gravity" for n in prem.get("absorbed", ()))
    return float(prem["g_uncertainty"]) if gravity else 0.0


def write(path, cal):
    """Write a calibration as a garant-calibration-1 JSON file."""
    write_json(path, cal)


def read(path):
    """A garant calibration file: checked against its published schema (docs/schemas/calibration.schema.json)
    and then for what a schema cannot state (M non-singular and well-conditioned, bound rows below 1);
    DataError naming the file and the field on any problem."""
    files.regular(path, "the calibration file", MAX_BYTES, param="calibration")
    try:
        with open(path, "rb") as fh:
            data = files.json_text(fh.read(MAX_BYTES).decode("utf-8"), parse_int=_int)
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="calibration") from None
    except (UnicodeDecodeError, ValueError, RecursionError) as e:
        raise DataError(f"{path}: not a JSON calibration file ({_short(e)})", param="calibration") from None
    return checked(data, path)


def checked(data, path="calibration"):
    """A calibration dictionary (read from a file, or the one `calibrate_norm` returns) checked against the
    schema and for what it cannot state; numbers as numpy arrays. `path` names it in errors."""
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise DataError(f"{path}: not a {FORMAT} file (its \"format\" must be \"{FORMAT}\")", param="calibration")
    if isinstance(data.get("information_set"), dict):           # a set read before carries the LPs solved on it
        data = dict(data, information_set={k: v for k, v in data["information_set"].items() if k != "_solved"})
    data = json.loads(json.dumps(data, default=json_value))      # numpy arrays and numbers as JSON has them
    where = _nan(data)
    if where is not None:                                       # NaN passes every minimum and maximum
        raise DataError(f"{path}: {where}: NaN is not a number a calibration may hold", param="calibration")
    schemas.validate(data, "calibration", path)
    out = dict(data)
    for key in ("M", "b", "bound_matrix", "bound_bias", "bound_delta", "pendulosity_axes"):
        out[key] = np.array(data[key], dtype=float)
    out["delta"] = np.array(data.get("delta", [0.0, 0.0, 0.0]), dtype=float)
    cond = np.linalg.cond(out["M"])
    if not np.isfinite(cond) or cond > MAX_CONDITION:
        raise DataError(f"{path}: M is singular or ill-conditioned (condition number {cond:.3g}, at most "
                        f"{MAX_CONDITION:g}); a calibration's M is close to a scaled rotation", param="calibration")
    if out["bound_matrix"].sum(axis=1).max() >= 1:
        raise DataError(f"{path}: each row of bound_matrix must sum below 1 (the bound (I - B)^-1 needs it)",
                        param="calibration")
    if "effects" in data and (data.get("thermal") or np.any(out["delta"]) or data["kind"] != "norm"):
        raise DataError(f"{path}: effects belong to a 9-parameter norm calibration (no delta, no thermal)",
                        param="calibration")
    if "information_set" in data:
        out["information_set"] = _information_set(data, path)
    if "thermal" in data:
        th = data["thermal"]
        lo, hi = th["range_c"]
        cuts = th["pieces_c"]
        if not (lo <= th["t0_c"] <= hi) or len(th["Gamma"]) != th["degree"] or len(th["bias"]) != th["degree"]:
            raise DataError(f"{path}: thermal: t0_c must lie in range_c and Gamma and bias hold one term per degree",
                            param="calibration")
        if (cuts[0] != lo or cuts[-1] != hi or any(x >= y for x, y in zip(cuts, cuts[1:]))
                or len(th["bound_Gamma"]) != len(cuts) - 1 or len(th["bound_bias"]) != len(cuts) - 1):
            raise DataError(f"{path}: thermal: pieces_c must rise from range_c's first to its last temperature and "
                            "bound_Gamma and bound_bias hold one bound per piece", param="calibration")
        out["thermal"] = {k: (np.array(v, float) if isinstance(v, list) else v) for k, v in th.items()}
    _lower_rows(out, path)
    return out


def _lower_rows(cal, path):
    """A two-axis stand's set reads the error through its rows (`Gamma_rows`, `bias_rows`, `rest_Gamma`,
    `rest_bias`: workflows/sample_set.py `lower_bound`): they come together, in the frame the data define, one term
    per power 0..degree (0 alone without thermal) and one rest per piece; a thermal file's set holds them;
    DataError naming what does not fit."""
    st, th = cal.get("information_set"), cal.get("thermal")
    if st is None or (th is None and "Gamma_rows" not in st):
        return
    if th is not None and th["frame"] == "block":               # the block's set, each power's columns beside
        if "block_powers" not in st or "Gamma_rows" in st:
            raise DataError(f"{path}: information_set: a calibration over temperature in the block's axes reads its "
                            "set through block_columns and block_powers", param="calibration")
        return
    P = len(st["estimate"])
    D1, pieces = (th["degree"] + 1, len(th["pieces_c"]) - 1) if th is not None else (1, 1)
    parts = [k in st for k in ("Gamma_rows", "bias_rows", "rest_Gamma", "rest_bias")]
    problem = (
        "Gamma_rows, bias_rows, rest_Gamma and rest_bias come together" if any(parts) and not all(parts) else
        "a calibration over temperature reads its set through Gamma_rows" if not any(parts) else
        "Gamma_rows and block_columns do not go together" if "block_columns" in st else
        "Gamma_rows belong to the frame the data define (thermal.frame lower)" if th is not None
        and th["frame"] != "lower" else
        f"Gamma_rows must be {D1} x 3 x 3 x {P} and bias_rows {D1} x 3 x {P} (a term per power of T - t0, a column "
        "per entry of estimate)" if st["Gamma_rows"].shape != (D1, 3, 3, P) or st["bias_rows"].shape != (D1, 3, P) else
        f"rest_Gamma must hold one 3 x 3 bound per piece ({pieces})" if st["rest_Gamma"].shape != (pieces, 3, 3)
        else None)
    if problem:
        raise DataError(f"{path}: information_set: {problem}", param="calibration")


def _information_set(data, path):
    """The file's information_set as numpy arrays, each part one entry per row or column of the set (rows K x P,
    P = 9 and the effects' parameters); DataError naming what does not fit."""
    raw = data["information_set"]
    P = len(raw["estimate"])
    effects = data.get("effects") or {}
    from ...generated import norm as norm_model          # the effects' parameters, by name
    session = sum(len(norm_model.EFFECTS.get(x, ())) for x in effects.get("not_applied") or {})
    problem = (
        f"{P} columns, but 9, the effects' {len(effects['theta'])} parameters and the {session} of those not "
        "applied make the set's"
        if effects.get("theta") is not None and P != 9 + len(effects["theta"]) + session else
        f"{P} columns, but a norm calibration without effects has 9, or 12 with its nonlinearity delta"
        if data["kind"] == "norm" and "effects" not in data and P not in (9, 12) else
        f"every row must hold one number per entry of estimate ({P})" if any(len(r) != P for r in raw["rows"]) else
        "centre and bound must hold one number per row" if len(raw["centre"]) != len(raw["rows"])
        or len(raw["bound"]) != len(raw["rows"]) else
        "box_lo, box_hi and shift must hold one number per entry of estimate"
        if any(len(raw[k]) != P for k in ("box_lo", "box_hi", "shift")) else
        "box_lo must not exceed box_hi" if any(x > y for x, y in zip(raw["box_lo"], raw["box_hi"])) else
        "block_columns must name 12 different columns of the set" if "block_columns" in raw
        and (len(set(raw["block_columns"])) != 12 or max(raw["block_columns"]) >= P) else
        "block_powers need block_columns and the calibration's thermal degree, each power 12 columns of the set apart "
        "from the others" if "block_powers" in raw and (
            "block_columns" not in raw or len(raw["block_powers"]) != (data.get("thermal") or {}).get("degree")
            or len({c for cols in [raw["block_columns"], *raw["block_powers"]] for c in cols})
            != 12 * (1 + len(raw["block_powers"])) or max(map(max, raw["block_powers"])) >= P) else None)
    if problem:
        raise DataError(f"{path}: information_set: {problem}", param="calibration")
    try:
        return {k: np.array(v, int if k in ("block_columns", "block_powers") else float) for k, v in raw.items()}
    except ValueError:
        raise DataError(f"{path}: information_set: every row of an array must hold as many numbers as the others",
                        param="calibration") from None


def thermal_at(cal, T):
    """Per sample at temperatures T (C): (M (N, 3, 3), b (N, 3), bound_matrix (N, 3, 3), bound_bias (N, 3)) of a
    calibration with a temperature polynomial, through `through_M` with the bounds of the piece of the range that
    holds T (each over the estimate's information set and the whole piece, workflows/thermal_file.py; a T at a
    cut lies in both pieces, and either bound holds there)."""
    th = cal["thermal"]
    G, b, piece = thermal_gamma(cal, T)
    M, B, eb = through_M(G, th["bound_Gamma"][piece], th["bound_bias"][piece], th.get("g_uncertainty", 0.0))
    return M, b, B, eb


def thermal_gamma(cal, T):
    """Per sample at temperatures T (C): the file's Gamma(T) = Gamma(t0) + sum_k Gamma_k (T - t0)^k (N, 3, 3),
    Gamma(t0) = M^-1 - E, its b(T) likewise (N, 3), and the index of the piece of the range that holds T."""
    th = cal["thermal"]
    T = np.asarray(T, float)
    tau = T - th["t0_c"]
    powers = np.stack([tau ** k for k in range(1, th["degree"] + 1)], axis=1)          # (N, D)
    G = (np.linalg.inv(cal["M"]) - np.eye(3))[None] + np.einsum("nk,kij->nij", powers, th["Gamma"])
    b = cal["b"][None] + powers @ th["bias"]
    cuts = th["pieces_c"]
    return G, b, np.clip(np.searchsorted(cuts, T, side="right") - 1, 0, len(cuts) - 2)


def _nan(value, where=""):
    """The place of the first NaN in a JSON value (e.g. "bound_bias[0]"), or None."""
    if isinstance(value, float) and value != value:
        return where or "the value"
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for k, v in items:
        found = _nan(v, f"{where}.{k}" if isinstance(k, str) and where else k if isinstance(k,
                                                                                            str) else f"{where}[{k}]")
        if found is not None:
            return found
    return None


def _int(text):
    """JSON integers: exact up to 18 digits, else a float (inf beyond 1e308; the schema refuses both)."""
    return int(text) if len(text.lstrip("-")) <= 18 else float(text)


def _short(e):
    return str(e).splitlines()[0][:120]


def check_units(cal, log_path, raw, cal_path):
    """Refuse a log whose scale does not match the calibration's raw unit (a raw-count log corrected by a
    calibration made in m/s^2, or the reverse): the median norm of the readings is within 20 % of g for a
    log in m/s^2 (as calibrate-norm decides it)."""
    looks = recordings.raw_unit(raw, cal["g"])
    if looks != cal["raw_unit"]:
        norm = float(recordings.median(np.linalg.norm(raw, axis=1)))
        say = {"m/s^2": "m/s^2", "count": "raw counts"}
        raise DataError(f"{log_path}: its readings (median norm {norm:.4g}) look like {say[looks]}, but {cal_path} was "
                        f"made from a log in {say[cal['raw_unit']]}; correct a log of the same unit, or pass "
                        f"{opt('trust_units')} if the scale is right")


#: The frames `apply` can correct into: garant's (M as calibrated) or that of the imu_tk export.
FRAMES = ("garant", "imu_tk")


def apply_thermal(cal, raw, T, path="the log"):
    """Corrected specific force (N, 3), m/s^2, and its worst-case error per sample (N, 3) of a calibration with
    a temperature polynomial, each sample at its own temperature T (C); DataError when a sample lies outside
    the calibrated range (the polynomial and its bound hold there only)."""
    lo, hi = cal["thermal"]["range_c"]
    T = np.asarray(T, float)
    out = np.flatnonzero((T < lo) | (T > hi) | ~np.isfinite(T))
    if out.size:
        raise DataError(f"{path}: {out.size} sample(s) at temperatures outside the calibrated range [{lo:g}, {hi:g}] "
                        f"C (the first, sample {out[0] + 1}, at {T[out[0]]:g} C): the calibration holds nothing there",
                        param="log")
    M, b, B, eb = thermal_at(cal, T)
    if B.sum(axis=2).max() >= 1:
        raise DataError(f"{path}: the calibration's bounds at these temperatures do not keep each row of the bound "
                        "matrix below 1", param="log")
    a = np.einsum("nij,nj->ni", M, np.asarray(raw, float) - b)
    bound = np.linalg.solve(np.eye(3)[None] - B, (np.einsum("nij,nj->ni", B, np.abs(a)) + eb)[..., None])[..., 0]
    return a, bound * (1 + 1e-9)


def apply(cal, raw, frame="garant"):
    """Corrected specific force (N, 3) in m/s^2 and its worst-case error per sample (N, 3), in garant's
    frame or, with frame "imu_tk", in the frame of the imu_tk export (`imu_tk_form`: turned by R, the
    bound carried through |R|). Computed
    axis by axis ((3, N), each axis contiguous): |n_i n_j| = |a_i a_j| / |a|^2. The nonlinearity the file
    states (`delta`, of the 12-parameter model) is taken out as calibrate-norm fitted it, g delta_l n_axis(l)
    n_l with n the direction of M (raw - b); its bound `bound_delta` stays in the bound, and so does what the
    error of n moves the estimated term by: |n_i n_j - m_i m_j| <= 2 |n - m| <= 4 |a - a_true| / |a|. A file with
    catalogue effects (calibrate-norm --effect) is applied by workflows/norm_effects.py `apply`."""
    a = cal["M"] @ (np.asarray(raw, float) - cal["b"]).T
    inv2 = 1.0 / np.maximum((a * a).sum(axis=0), 1e-300)
    axes = cal["pendulosity_axes"].astype(int) - 1
    nn = np.abs(a[axes] * a) * inv2
    delta = np.asarray(cal.get("delta", np.zeros(3)), float)
    if np.any(delta):
        a = a - (cal["g"] * delta)[:, None] * (a[axes] * a) * inv2
    inverse = np.linalg.inv(np.eye(3) - cal["bound_matrix"])
    v = cal["bound_matrix"] @ np.abs(a) + cal["bound_bias"][:, None] + (cal["g"] * cal["bound_delta"])[:, None] * nn
    bound = inverse @ v
    if np.any(delta):
        moved = 4 * np.sqrt((bound * bound).sum(axis=0) * inv2)          # bounds |n - m| twice over
        bound = bound + inverse @ ((cal["g"] * np.abs(delta))[:, None] * moved)
    if frame == "imu_tk":
        R = imu_tk_form(cal)[2]
        a, bound = R @ a, (np.abs(R) @ bound) * (1 + 1e-12)
    return a.T, (bound * (1 + 1e-12)).T


def imu_tk_form(cal):
    """(T, K, R): the imu_tk file's T (unit diagonal) and K with T K = R M, R the turn from garant's frame
    into the file's. A norm calibration's frame is free (the norm relation sees |a| only): it is turned,
    M -> Q^T M by the QR decomposition M = Q U, into imu_tk's own convention for accelerometers, T upper
    triangular, with the same |a| for every reading. A stand calibration's frame is the stand's (R = I)."""
    M = np.asarray(cal["M"], float)
    R = np.eye(3)
    if cal.get("kind") == "norm":
        Q, U = np.linalg.qr(M)
        S = np.diag(np.sign(np.diag(U)))          # positive scale factors: U -> S U, Q -> Q S
        R, M = (Q @ S).T, np.triu(S @ U)
    K = np.diag(np.diag(M))
    T = M @ np.linalg.inv(K)
    np.fill_diagonal(T, 1.0)
    return T, K, R


def frame_turn_deg(R):
    """The angle (degrees) of the turn R between two frames."""
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))))


def imu_tk_text(cal):
    """The calibration in imu_tk's CalibratedTriad file form (T, K, B), X' = T K (X - B), its unit
    diagonal written as exactly 1, in the frame `imu_tk_form` says."""
    T, K, _ = imu_tk_form(cal)
    b = np.asarray(cal["b"], float)

    def block(X):
        return "\n".join(" ".join(f"{v:.17g}" for v in row) for row in X)
    return f"{block(T)}\n\n{block(K)}\n\n" + "\n".join(f"{v:.17g}" for v in b) + "\n"


def write_imu_tk(path, cal):
    """Write a calibration in imu_tk's text form (T, K, B)."""
    write_text(path, imu_tk_text(cal))


def read_imu_tk(path):
    """(M, b) from an imu_tk calibration file: M = T K."""
    files.regular(path, "the imu_tk calibration file", MAX_BYTES, param="calibration")
    try:
        with open(path) as fh:
            vals = np.array(fh.read(MAX_BYTES).split(), dtype=float)
    except (OSError, ValueError) as e:
        raise DataError(f"{path}: not an imu_tk calibration file ({e})", param="calibration") from None
    if vals.size != 21:
        raise DataError(f"{path}: an imu_tk calibration file has 21 numbers (T, K, B), found {vals.size}",
                        param="calibration")
    T, K, B = vals[:9].reshape(3, 3), vals[9:18].reshape(3, 3), vals[18:]
    return T @ K, B


def yaml_float(x):
    """x as a YAML 1.1 float (PyYAML's safe_load, Kalibr's reader, takes 2e-05 for text): six significant digits,
    a dot in the mantissa and a signed exponent (2.0e-05, 100.0)."""
    s = f"{float(x):.6g}"
    mant, e, exp = s.partition("e")
    return (mant if "." in mant else mant + ".0") + (e + exp if e else "")


def kalibr_text(noise_density, rate_hz, random_walk=None, gyro=None, topic="/imu0", why_no_walk=""):
    """The IMU file Kalibr's reader takes (its ImuParameters: flat keys rostopic,
    update_rate, accelerometer_noise_density (m/s^2/sqrt(Hz)), accelerometer_random_walk (m/s^3/sqrt(Hz)),
    gyroscope_noise_density (rad/s/sqrt(Hz)), gyroscope_random_walk (rad/s^2/sqrt(Hz))). What a static
    accelerometer log does not measure is never invented: the random walk when no still interval is long
    enough (`why_no_walk` says why) and the gyroscope's figures unless given (`gyro` = (noise density,
    random walk)) are written as comments, and Kalibr's reader then names the missing key."""
    lines = ["# Written by garant calibrate-norm --export-kalibr: Kalibr's IMU configuration (imu.yaml), the",
             "# statistics Kalibr's reader takes. Scale, misalignment and bias are no fields of it: see the garant",
             "# JSON (--save) or the imu_tk file (--export-imu-tk).",
             f"rostopic: {topic}",
             f"update_rate: {yaml_float(rate_hz)}   # [ Hz ]",
             f"accelerometer_noise_density: {yaml_float(noise_density)}   # [ m / s^2 / sqrt(Hz) ], from the still "
             "intervals"]
    lines.append(f"accelerometer_random_walk: {yaml_float(random_walk)}   # [ m / s^3 / sqrt(Hz) ], from the longest "
                 "still interval (Allan deviation; statistical, not a bound)" if random_walk is not None else
                 f"# accelerometer_random_walk: not measured ({why_no_walk}); Kalibr needs it")
    if gyro is not None:
        lines += [f"gyroscope_noise_density: {yaml_float(gyro[0])}   # [ rad / s / sqrt(Hz) ], as given "
                  "(--kalibr-gyro)",
                  f"gyroscope_random_walk: {yaml_float(gyro[1])}   # [ rad / s^2 / sqrt(Hz) ], as given "
                  "(--kalibr-gyro)"]
    else:
        lines += ["# gyroscope_noise_density: not measured by an accelerometer log (give --kalibr-gyro ND,RW); "
                  "Kalibr needs it",
                  "# gyroscope_random_walk: not measured by an accelerometer log (give --kalibr-gyro ND,RW); "
                  "Kalibr needs it"]
    return "\n".join(lines) + "\n"


#: The keys Kalibr's IMU reader (ImuParameters) requires.
KALIBR_KEYS = ("rostopic", "update_rate", "accelerometer_noise_density", "accelerometer_random_walk",
               "gyroscope_noise_density", "gyroscope_random_walk")
