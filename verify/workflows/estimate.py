"""Estimate q, with guaranteed error bounds, from readings at any set of positions ((6)-(8) of 000)."""
import numpy as np

from ..defaults import SIGMA_WIDER
from ..errors import DataError, opt
from ..io.positions import Positions
from ..solve import lp, taylor
from . import block, guarantee, mounting, nearby, remainder
from .premises import NEAR_EDGE, premises as make_premises

EXACT_DEG = 1e-6   # positions closer than this to the plan count as on it


def describe(mod, nus):
    """'q_nu = definition' of the q's at indices nus, for a message."""
    return ", ".join(f"{mod.Q_NAMES[nu]} = {mod.Q_DEFINITIONS[nu]}" for nu in nus)


def residuals_table_axes(mod, positions, g, Q):
    """z of (1) in block axes, turned to table axes by Q^-1 ((26) of 000): shape (N, 3).

    For a stand with several mountings, z stays in block axes (H already includes each Q)."""
    if positions.mounts is not None:
        return mod.residual(*positions.radians, positions.f.T, g, mount=positions.mounts).T
    z_block = positions.f.T / g - Q @ mod.up_nominal(*positions.radians)
    return (Q.T @ z_block).T


def variable_columns(mod, positions):
    """{name: values (N,)} of the columns the model's VARIABLES need (an extended model's time_s in s or
    temp_c in degrees C), as numbers; DataError naming a column that is missing or not a number."""
    out = {}
    for v in map(str, mod.VARIABLES):
        if v not in positions.extra:
            raise DataError(f"{positions.path}: the model needs the column {v} "
                            f"({'s' if v == 'time_s' else 'degrees C'}) "
                            "on every row", param="data")
        try:
            out[v] = np.asarray(positions.extra[v], float)
        except ValueError:
            raise DataError(f"{positions.path}: column {v} must hold a number on every row", param="data") from None
        if not np.all(np.isfinite(out[v])):
            raise DataError(f"{positions.path}: column {v} must hold a finite number on every row", param="data")
    return out


def distinct_positions(positions, decimals=6, variables=None):
    """Rows at the same position (angles equal to 1e-6 degree, same mounting) joined into one, the spread
    (largest less smallest reading, m/s^2, per component) of the rows joined, and how far the true reading
    can move between them (units of g: 2 g per radian of each angle's own spread in the group, 0 where the
    rows' angles agree exactly): (positions, spread, moved).

    Readings each within +-sigma of one truth hold it in the intersection of their intervals, [max -
    sigma, min + sigma]: the midrange (max + min) / 2, within sigma - spread / 2 (`sharper` says how much
    below sigma); the joined reading is that midrange, so the information set is the rows' own, and the LP
    and the remainder are solved once per distinct position (worst case; no independence of the noise is
    assumed). Joining is sound only for readings that agree: `repeated_disagree` checks the spread first.
    The angles are averaged. The model's `variables` ({name: values}, see `variable_columns`) are part of a
    position (rows at other times are other positions) and kept; other columns are dropped."""
    variables = variables or {}
    key = np.round(positions.angles_deg, decimals)
    if positions.mounts is not None:
        key = np.column_stack([key, positions.mounts])
    if variables:
        key = np.column_stack([key, *variables.values()])
    order = np.lexsort(key.T[::-1])                       # rows sorted by position: groups are runs
    new = np.r_[True, np.any(key[order[1:]] != key[order[:-1]], axis=1)]
    if new.all():
        return Positions(positions.path, positions.angles_deg, positions.f, positions.mounts,
                         dict(variables)), np.zeros((len(key), 3)), np.zeros(len(key))
    starts = np.flatnonzero(new)
    counts = np.diff(np.r_[starts, len(key)])
    inverse = np.empty(len(key), int)
    inverse[order] = np.cumsum(new) - 1
    angles = np.column_stack([np.bincount(inverse, weights=positions.angles_deg[:, i])
                              for i in range(positions.angles_deg.shape[1])]) / counts[:, None]
    spread, f = np.empty((len(starts), 3)), np.empty((len(starts), 3))
    for i in range(3):
        column = positions.f[order, i]
        top, bottom = np.maximum.reduceat(column, starts), np.minimum.reduceat(column, starts)
        # the spread as computed, less its rounding: never more than the readings' true spread
        spread[:, i] = np.maximum(top - bottom - 4 * np.finfo(float).eps * (np.abs(top) + np.abs(bottom)), 0.0)
        f[:, i] = 0.5 * top + 0.5 * bottom
    moved = np.zeros(len(starts))
    for i in range(positions.angles_deg.shape[1]):
        column = positions.angles_deg[order, i]
        moved += 2 * np.deg2rad(np.maximum.reduceat(column, starts) - np.minimum.reduceat(column, starts))
    n = positions.angles_deg.shape[1]
    mounts = None if positions.mounts is None else key[order[starts], n].astype(int)
    kept = {v: np.asarray(x)[order[starts]] for v, x in variables.items()}
    return Positions(positions.path, angles, f, mounts, kept), spread, moved * (1 + 1e-9)


def repeated_disagree(positions, spread, sigma, g, decimals=6):
    """Indices (position, component) where readings repeated at one position differ by more than 2 sigma
    (each is within sigma of the same true value) plus what the 1e-6 degree the rows may differ by can
    move a reading (at most 2 g per radian of each angle): such readings refute sigma themselves."""
    slack = 2 * np.deg2rad(0.5 * 10.0 ** -decimals) * positions.angles_deg.shape[1]
    return np.argwhere(spread / g > 2 * sigma * (1 + 1e-9) + slack)


def _sharper(spread, moved, g, Q, positions):
    """`sharper` in the axes of z: the table axes turn the components by Q^-1, a signed permutation for every
    mounting of (26) of 000 (any other turn: 0, sigma as stated)."""
    r = sharper(spread, moved, g).reshape(-1, 3)
    if np.array_equal(Q, np.eye(3)) or positions.mounts is not None:
        return r.reshape(-1)
    if not np.all(np.isin(np.abs(Q), (0.0, 1.0))):
        return np.zeros(r.size)
    return (np.abs(Q.T) @ r.T).T.reshape(-1)


def sharper(spread, moved, g):
    """Per residual component (3N,), units of g: how much below sigma the joined reading of repeated rows is
    known, spread / 2 less how far the truth moves between the rows (the true reading at their average angles
    is within sigma + moved of each row); 0 for a position read once, and where the rows agree exactly."""
    return np.where(spread > 0, spread / g / 2 - moved[:, None], 0.0).reshape(-1)


def check_residual_size(z, path, limit=0.5):
    """Readings must be near the model: a residual beyond half of g is a unit or column mistake, not
    a small error the linear model (2) can describe."""
    worst = np.abs(z).max(axis=1)
    if worst.max() > limit:
        k = int(np.argmax(worst))
        raise DataError(f"{path}: position {k + 1} differs from the model by {worst[k]:.3g} g; readings must be "
                        f"specific force in m/s^2 (check {opt('g')}, the units and the column order)")


def choose_estimator(mod, positions, A):
    """Weights (m x 3N) and the method: (23) of 000 near the optimal plan, else the LP (7)-(8)."""
    plan = mod.PLAN_DEG
    match = (nearby.match_plan(positions.alpha_deg, positions.beta_deg, plan)
             if len(plan) and positions.angles_deg.shape[1] == 2 and positions.mounts is None else None)
    if match is not None and match[1] > EXACT_DEG:
        order, miss = match
        cols = np.array([3 * order[s] + p for s in range(len(order)) for p in range(3)])
        Psi = nearby.estimator_23(nearby.plan_estimators(mod), A[:, cols])
        W = np.zeros_like(A)
        W[:, cols] = Psi
        return W, (f"positions within {miss:.3g} deg of the optimal plan but not on it: "
                   "estimator (23) of 000, q* = (D H^T)^-1 D Z")
    Phi, _ = lp.primal(A)
    return Phi.T, "optimal guaranteed estimator on these positions (LP (7)-(8) of 000)"


PROGRESS_ABOVE = 100_000   # distinct positions: from here on each stage is announced (it takes seconds)


def estimate(mod, positions, sigma, g, remount=None, mount=None, gamma="lower", premises=None, progress=None,
             thermal=None):
    """The verdict (are the data consistent with sigma?), then q with guaranteed errors that include
    the proven linearisation remainder (workflows/guarantee.py), and the block's physical errors.

    The model is linearised at its exact fit to these data; `premises` (premises.py; default: the
    description's bounds and the defaults, g as given) are what the bounds assume, and the result
    states them. When the data refute sigma, `consistent` is False and no bound is given.
    `progress(text)`, when given, hears of each stage of a large problem. `thermal` (degree, T0): the model
    is a thermal extension (models.thermal), and the result holds each q's polynomial in T with one bound
    over the whole range (workflows/thermal.py).
    """
    if not (sigma > 0 and np.isfinite(sigma)):
        raise DataError(f"sigma must be a finite number > 0 (got {sigma:g})", param="sigma")
    if not (g > 0 and np.isfinite(g)):
        raise DataError(f"g must be a finite number > 0 m/s^2 (got {g:g})", param="g")
    premises = premises or make_premises(mod, sigma, g)
    Q = remount.MOUNTS[mount] if mount else np.eye(3)
    rows, all_rows = len(positions.f), positions
    positions, spread, moved = distinct_positions(positions, variables=variable_columns(mod, positions))
    distinct = len(positions.f)
    bad = repeated_disagree(positions, spread, sigma, g)
    if len(bad):
        return refuted_by_repeats(mod, positions, spread, bad, sigma, g, premises, rows)
    z = residuals_table_axes(mod, positions, g, Q)
    A = lp.measurement_matrix(mod, np.column_stack(positions.radians), positions.mounts,
                              list(positions.extra.values()))
    missing = lp.unidentifiable(A)
    if missing:
        raise DataError(f"{positions.path}: the {distinct} distinct positions cannot identify "
                        f"{describe(mod, missing)}; add positions (see `garant plan`)", param="data")
    check_residual_size(residuals_table_axes(mod, all_rows, g, Q), positions.path)
    say = progress if progress is not None and distinct >= PROGRESS_ABOVE else (lambda text: None)
    say(f"{rows} rows, {distinct} distinct positions: the exact-model fit and the linearisation there")
    lin = guarantee.linearise(mod, positions, z.reshape(-1), A, premises)
    del A                                      # H at zero errors: what follows uses lin.A, H at the fit
    say("the optimal estimators (LP (7)-(8)) at the linearisation")
    W, method = choose_estimator(mod, positions, lin.A)
    say("the verdict and the proven remainder")
    v = guarantee.verdict(lin, z.reshape(-1), sigma, W, sharper=_sharper(spread, moved, g, Q, positions),
                          progress=progress)
    out = {                                    # arrays stay arrays until a JSON file is written
        "model": mod.__name__.rsplit(".", 1)[-1], "g": g, "sigma": sigma,
        "premises": unrefutable_premises(lin, premises.to_dict()),
        "positions": rows, "distinct_positions": distinct, "consistent": v.consistent,
        "sigma_min_supported": v.sigma_min_supported, "sigma_min_tolerance": guarantee.SIGMA_TOLERANCE,
        "remainder_left_bound": float(v.remainder.max()),
        "minimax_residual": v.minimax_exact, "minimax_residual_linear": v.minimax_linear,
        "linearised_at": dict(zip(mod.Q_NAMES, lin.q0.tolist())),
        "definitions": dict(zip(mod.Q_NAMES, mod.Q_DEFINITIONS)), "units": dict(zip(mod.Q_NAMES, mod.Q_UNITS)),
        "positions_deg": positions.angles_deg,
        "residual_minimax": v.residual.reshape(-1, 3),
    }
    if not v.consistent:
        names = list(mod.ANGLES)
        out["disagreements"] = [
            {"position": int(k // 3) + 1, **{f"{a}_deg": float(positions.angles_deg[k // 3, i])
                                             for i, a in enumerate(names)}, "component": int(k % 3) + 1}
            for k in v.disagree]
        if v.split_refuted:
            out["split_refuted"] = True
        return out
    y = z.reshape(-1) - lin.z0
    q_apriori, e_apriori = lin.q0 + W @ y, v.guaranteed_error
    q, e = _midpoint(*v.interval, q_apriori, e_apriori)
    q_wider, e_wider = _midpoint(*v.interval_wider, q_apriori, SIGMA_WIDER * e_apriori)
    out.update({
        "method": method,
        "q": dict(zip(mod.Q_NAMES, q.tolist())),
        "guaranteed_error": dict(zip(mod.Q_NAMES, e.tolist())),
        "a_priori": {"q": dict(zip(mod.Q_NAMES, q_apriori.tolist())),
                     "guaranteed_error": dict(zip(mod.Q_NAMES, e_apriori.tolist()))},
        "guaranteed_error_linear": dict(zip(mod.Q_NAMES, v.error_linear.tolist())),
        "guaranteed_error_remainder": dict(zip(mod.Q_NAMES, v.error_remainder.tolist())),
        "sigma_wider": SIGMA_WIDER * sigma,
        "guaranteed_error_sigma_wider": dict(zip(mod.Q_NAMES, e_wider.tolist())),
        "sigma_fit": max(float(v.minimax_less_remainder), 0.0),
        "remainder_parts": {k: dict(zip(mod.Q_NAMES, x.tolist())) for k, x in v.parts.items()},
        "residual": (y - lin.A.T @ (q - lin.q0)).reshape(-1, 3),
        "warnings": near_prior(lin, q, e) + unrefutable(lin.A, W, mod),
        "premises_refuted": beyond_prior(lin, q, e),
    })
    if thermal is not None:
        from . import thermal as th
        out["thermal"] = th.summary(mod, v.info, q, e, np.asarray(positions.extra["temp_c"], float), *thermal)
    if not out["premises_refuted"]:                # else no block split: it rests on the refuted bounds
        out.update(block_errors(mod, v, g, premises, remount, mount, gamma))
        if thermal is not None:
            out.update(_thermal_file(mod, v, q, positions, thermal, g, premises, remount, out))
        elif out.get("gamma") == "lower" and "physical" in out:      # the file's set (workflows/thermal_file.py)
            from . import thermal_file
            out["_set"] = thermal_file.lower_set(mod, remount, out["mount"], v.info, q, v.interval,
                                                 _own(premises).get("Delta_g", 0.0), g, out["physical"]["Gamma"],
                                                 out["physical"]["bias"])
        elif out.get("gamma") == "symmetric" and "physical" in out:
            from . import thermal_file
            out["_set"] = thermal_file.symmetric_set(remount, out["mount"], v.info, q,
                                                     _own(premises).get("Delta_g", 0.0), g, out["physical"]["Gamma"],
                                                     out["physical"]["bias"], out["physical_bound_premises"])
    return out


def _own(premises):
    """{parameter: its own a-priori bound}."""
    return dict(zip(premises.names, premises.physical()))


def _thermal_file(mod, v, q, positions, thermal, g, premises, remount, out):
    """{"thermal_file": the temperature part of the calibration (workflows/thermal_file.py)}, or why there is
    none ("block_not_separated")."""
    from . import thermal_file
    T = np.asarray(positions.extra["temp_c"], float)
    degree, t0 = thermal
    if "physical" in out:
        if out["gamma"] != "lower":
            return {"block_not_separated": "a calibration over temperature is written in the frame the data define "
                                           "(--gamma lower); with --gamma symmetric none is written"}
        return {"thermal_file": thermal_file.lower_section(
            mod, remount, out["mount"], v.info, q, v.interval, T, t0, degree, _own(premises).get("Delta_g", 0.0), g,
            out["physical"]["Gamma"], out["physical"]["bias"])}
    if "block" in out:
        from ..io.calibration import g_uncertainty
        try:
            return {"thermal_file": thermal_file.block_section(mod, v.info, q, T, t0, degree, g, out["block"],
                                                               g_uncertainty(out))}
        except DataError as err:
            return {"block_not_separated": str(err)}
    return {}


def unrefutable_premises(lin, stated):
    """The premises dictionary with `unrefutable`: the parameters no plan separates (t of the linearisation)
    whose a-priori bound the bounds use, since they move the readings with q held (a parameter that enters
    only with another, as Delta_alpha with alpha_star, moves nothing and is not named); the statement names
    them, for no data can check them."""
    names = [lin.premises.names[k] for j, (k, b) in enumerate(zip(lin.T, lin.t_bound)) if b > 0 and _moves(lin, j)]
    out = dict(stated, unrefutable=names)
    if names:
        out["statement"] += (f"; no data can check the bounds of {', '.join(names)} (they move the readings beyond "
                             f"what "
                             "q absorbs, and no plan separates them): these bounds rest on them")
    return out


def _moves(lin, j, size=1e-2, count=24):
    """Whether t_j moves the readings with q held, anywhere: readings of units with errors of `size` at `count`
    positions of the data, t_j at its bound and at 0 (an exact invariance, such as a sum, moves nothing)."""
    mod, pos = lin.mod, lin.positions
    rng = np.random.default_rng(0)
    rows = rng.choice(len(pos.f), min(count, len(pos.f)), replace=False)
    sub = pos.at(rows)
    p = rng.uniform(-size, size, lin.L.shape[0])
    step = lin.L[:, lin.A.shape[0] + j] * lin.t_bound[j]
    return bool(np.abs(guarantee._z_exact(mod, sub, p + step, lin.premises.g)
                       - guarantee._z_exact(mod, sub, p, lin.premises.g)).max() > 1e-12)


def _midpoint(lo, hi, q, e):
    """(midpoint, half-width) of intervals, the half-width rounded up so that mid +- half holds [lo, hi];
    the a-priori q +- e where that is no wider (the printed bound never exceeds it)."""
    mid, half = taylor.midrad(lo, hi)
    wider = half >= e
    return np.where(wider, q, mid), np.where(wider, e, half)


def block_errors(mod, v, g, premises, remount=None, mount=None, gamma="lower"):
    """The block's errors over the information set of the verdict v: its physical errors in `mount` by
    the remount formulas (28)-(29) of 000 when the model has them, else the block's calibration (Gamma,
    biases) where the stand separates it, else why not."""
    if remount is not None:
        gap = 0.0
        if premises.absorbed:                    # the split into Gamma and theta_k is linear in the literal q
            gap = mounting.literal_gap(mod, premises, _gamma_prime_bound(mod, premises, remount, v))
        own = dict(zip(premises.names, premises.physical()))
        phys, bound, note, premised = mounting.recover(remount, mount or "+x+y+z", gamma, v.info, g, gap,
                                                       {n: own[n] for n in ("Delta_g", "Delta_beta") if n in own},
                                                       v.interval)
        if premises.absorbed:
            note += "; the split of Gamma and theta_k assumes " + ", ".join(
                f"|{n}| <= {b:g} ({src})" for n, (b, src) in premises.split.items())
        return dict(mount=mount or "+x+y+z", gamma=gamma, physical=phys, physical_bound=bound, physical_note=note,
                    physical_bound_premises=premised)
    if not all(n in mod.PARAMETER_NAMES for n in block.BLOCK):
        return {}
    try:
        return {"block": block.calibration(mod, v.info, premises)}
    except DataError as err:                     # the estimate stands; only a calibration of the block cannot
        return {"block_not_separated": str(err)}


def _gamma_prime_bound(mod, premises, remount, v):
    """Entrywise bound of the equivalent unit's Gamma' (3 x 3): where each q of G(q) ((29) of 000) is its Gamma'
    entry plus absorbed parameters only (0 in the equivalent unit), |q| over the printed interval; else the
    block's calibration over the information set."""
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    names = list(mod.PARAMETER_NAMES)
    idx = np.asarray(remount.G_INDEX)
    lo, hi = v.interval
    pure = all(set(np.flatnonzero(R[idx[i, j]])) <= {names.index(f"Gamma{i + 1}{j + 1}")}
               | {names.index(n) for n in premises.absorbed} and R[idx[i, j], names.index(f"Gamma{i + 1}{j + 1}")] == 1
               for i in range(3) for j in range(3))
    if pure:
        return np.maximum(np.abs(lo), np.abs(hi))[idx] * (1 + 1e-15)
    cal = block.calibration(mod, v.info, premises)
    return np.abs(cal["Gamma"]) + cal["Gamma_bound"]


def refuted_by_repeats(mod, positions, spread, bad, sigma, g, premises, rows):
    """The result when readings repeated at a position disagree by more than 2 sigma: no bound, the
    positions and spreads named, and the smallest sigma they allow (half the largest spread)."""
    names = list(mod.ANGLES)
    worst = bad[np.argsort(-spread[bad[:, 0], bad[:, 1]])]
    return {
        "model": mod.__name__.rsplit(".", 1)[-1], "g": g, "sigma": sigma, "premises": premises.to_dict(),
        "positions": rows, "distinct_positions": len(positions.f), "consistent": False,
        "sigma_min_supported": float(spread.max() / g / 2), "sigma_min_tolerance": 0.0,
        "definitions": dict(zip(mod.Q_NAMES, mod.Q_DEFINITIONS)), "units": dict(zip(mod.Q_NAMES, mod.Q_UNITS)),
        "positions_deg": positions.angles_deg,
        "repeated_disagree": [
            {"position": int(k) + 1, **{f"{a}_deg": float(positions.angles_deg[k, i]) for i, a in enumerate(names)},
             "component": int(c) + 1, "spread": float(spread[k, c] / g)} for k, c in worst]}


def beyond_prior(lin, q, e):
    """Every q whose whole interval q +- e lies beyond what the a-priori bounds allow: the data refute a
    premise (a stand error or the mounting past its stated bound), so no printed bound is guaranteed.
    Each: the q, its definition, estimate and bound, what the premises allow and the parameters (name,
    bound, source) whose bounds to widen (--bound NAME=VALUE)."""
    mod, prem = lin.mod, lin.premises
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    biases = R[:, remainder.linear_parameters(mod)].any(axis=1)
    stated = lin.stated_bounds
    source = [prem.split[n][1] if n in prem.split else s for n, s in zip(prem.names, prem.sources)]
    out = []
    for nu in np.flatnonzero((np.abs(q) - e > lin.q_prior * (1 + 1e-9)) & ~biases):
        out.append({"q": mod.Q_NAMES[nu], "definition": mod.Q_DEFINITIONS[nu], "estimate": float(q[nu]),
                    "guaranteed_error": float(e[nu]), "allowed": float(lin.q_prior[nu]),
                    "parameters": [{"name": prem.names[k], "bound": float(stated[k]), "source": source[k]}
                                   for k in np.flatnonzero(R[nu]) if 0 < stated[k] < np.inf]})
    return out


def near_prior(lin, q, e):
    """Lines for every q whose estimate plus its bound comes within NEAR_EDGE of what the a-priori
    bounds allow (and not wholly beyond: `beyond_prior`): the premise may not hold; say which parameters
    and what to raise."""
    mod, prem = lin.mod, lin.premises
    allowed = lin.q_prior
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    out = []
    biases = np.asarray(mod.PHYSICAL_TO_Q, float)[:, remainder.linear_parameters(mod)].any(axis=1)
    for nu in np.flatnonzero((np.abs(q) + e > NEAR_EDGE * allowed) & (np.abs(q) - e <= allowed * (1 + 1e-9))
                             & ~biases):
        names = [prem.names[k] for k in np.flatnonzero(R[nu]) if 0 < lin.stated_bounds[k] < np.inf]
        if np.abs(q[nu]) + e[nu] >= allowed[nu] * (1 - 1e-9):
            out.append(f"{mod.Q_NAMES[nu]} = {q[nu]:+.3e} +- {e[nu]:.1e}: its interval is cut by what the a-priori "
                       f"bounds allow ({allowed[nu]:.2e}, from {', '.join(names)}), so this bound rests on them; if "
                       "the unit may be larger, raise them (--bound NAME=VALUE, the description's `bound`, --prior, "
                       "or --g-uncertainty for Delta_g)")
            continue
        out.append(f"{mod.Q_NAMES[nu]} = {q[nu]:+.3e} +- {e[nu]:.1e} is beyond {NEAR_EDGE:g} of what the a-priori "
                   f"bounds allow ({allowed[nu]:.2e}, from {', '.join(names)}): if the unit may be larger, raise "
                   "their bounds (--bound NAME=VALUE, the description's `bound`, --prior, or --g-uncertainty for "
                   "Delta_g)")
    return out


def unrefutable(A, W, mod, fraction=0.999):
    """Lines for every q whose estimator's weights lie (almost) wholly in the span of the model's own
    columns: noise shaped like those weights is fitted, not seen, so no verdict can refute an
    understated sigma along it (a minimal plan: offsets of 10 sigma so shaped move that q by 10 sigma
    and leave the fit exact); the bound then rests on sigma alone."""
    # |W_nu projected on the span of A's rows|^2 = (W A^T (A A^T)^+ A W^T)_nu,nu: from m x m products, no
    # orthonormal basis of every reading (a QR of A^T copies it and makes a basis of its size)
    d, V = np.linalg.eigh(A @ A.T)
    live = d > d.max() * 1e-12
    X = V[:, live].T @ (A @ W.T)
    inside = (X ** 2 / d[live, None]).sum(axis=0) / np.maximum(np.einsum("ij,ij->i", W, W), 1e-300)
    names = [mod.Q_NAMES[nu] for nu in np.flatnonzero(inside >= fraction)]
    if not names:
        return []
    return [f"noise shaped like the estimators of {', '.join(names)} is fitted, not seen: these readings have no "
            "redundancy along them, so they cannot refute an understated sigma there (a minimal plan); those bounds "
            "rest on sigma being right"]
