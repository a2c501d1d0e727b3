"""Catalogue effects in the norm relation (2.2) of 001: `garant calibrate-norm LOG --effect NAME[,NAME...]`.

The fit takes the effect's term (derive/effects.py, derived into the generated norm module: `effect_basis`) out of
each reading, g sum_j theta_j phi_j(p, t, T), at the direction p of the reading with the term taken out (a fixed
point, `fixed_point`), the interval's time t (s, from the middle of the log's still intervals) and temperature T
(C). The truth is the reading of the fit, f = M_fit (raw - b_fit) / g = (E + A) m + eps/g + sum_j theta_j phi_j(m,
t, T) + u with |m| = 1, m the true direction: the effect at the truth's direction. Its first order in the
correction theta' = theta - theta_fit is a column of (2.2) beside H; the rest, v = Phi(p) theta' + (Phi(m) -
Phi(p)) theta, enters each interval's remainder (norm_information.remainder_per_interval) with
|(Phi(m) - Phi(p)) theta| <= ||sum_j |theta_j| b_j||_2 |m - p|, b_j the bound of the effect's Jacobian over the
unit ball (generated `effect_jacobian_bound`, from the effect's derived term table). The parameters, the base ones
and the effects', are bounded over the information set of that extended relation. A calibration file takes the term
out at p = M (raw - b) / |M (raw - b)| (io/calibration.py `_with_effects` bounds what that direction's error moves it
by).
"""
import numpy as np

from ..errors import DataError, opt

#: Iterations of the direction the term is evaluated at, p <- direction of (f - Phi(p) theta): a contraction by
#: about L |theta| (1e-2 for effects of 1e-3); what is left, |n - p|, enters the remainder as computed.
FIXED_POINT = 30

#: |x/|x| - m| <= K_DIR |x - m| for a unit m and |x - m| <= 0.1: the angle's sine is at most |x - m| and the
#: chord 2 sin(a/2) = sin a / cos(a/2), cos(a/2) >= sqrt((1 + sqrt(1 - 0.01)) / 2).
K_DIR = 1.0 / np.sqrt((1 + np.sqrt(1 - 0.01)) / 2) * (1 + 1e-12)


def lipschitz(jac, size):
    """||sum_j size_j b_j||_2 per interval, jac = b (P, 3, 3, K): the effect's Lipschitz bound in w for parameters
    within `size` (rounded up)."""
    B = np.einsum("j,jilk->kil", size, jac)
    return np.linalg.norm(B, 2, axis=(1, 2)) * (1 + 1e-12)


#: Effects a file's `apply` does not carry to another log, and why.
SESSION_ONLY = {
    "bias_drift": "a drift in time belongs to its calibration session: the bias b is the one at t = {t_ref:g} s of "
                  "{log}",
    "temperature_lag": "applying it needs each sample's temperature rate, which a log's neighbouring samples give only "
                       "noisily: the file's biases and temperature coefficients are those of the sensor's own "
                       "temperature, the lag taken out"}


def parse(text, mod):
    """The effect names of --effect NAME[,NAME...] (or a list of names): each one the norm relation can carry,
    none twice."""
    if isinstance(text, (list, tuple)) and all(isinstance(x, str) for x in text):
        text = ",".join(text)
    if not isinstance(text, str):
        raise DataError(f"effects: give names as text or a list of text, e.g. 'bias_drift,cross_coupling', not "
                        f"{type(text).__name__}", param="effects")
    names = [x.strip() for x in text.split(",") if x.strip()]
    if not names:
        raise DataError(f"{opt('effects')}: give one or more effect names, e.g. {opt('effects')} "
                        f"bias_drift,cross_coupling",
                        param="effects")
    for x in names:
        if x in mod.STAND_EFFECTS:
            raise DataError(f"{opt('effects')} {x}: it needs a stand's angles; calibrate-norm can add "
                            f"{', '.join(mod.EFFECTS)}", param="effects")
        if x not in mod.EFFECTS:
            raise DataError(f"{opt('effects')} {x[:40]!r}: not an effect of the catalogue; calibrate-norm can add "
                            f"{', '.join(mod.EFFECTS)}", param="effects")
    if len(set(names)) < len(names):
        raise DataError(f"{opt('effects')}: an effect is named twice", param="effects")
    return tuple(sorted(names, key=list(mod.EFFECTS).index))


#: The convention every norm effect's parameters are computed, printed, documented and saved in: the term is in the
#: reading calibrated by M (after M, in the calibrated axes), not added to the raw reading; the two differ by the
#: scale and misalignment acting on the term (|M P - E| of it, a few percent of it for a MEMS unit).
CONVENTION = ("each effect's term is in the reading calibrated by M, f = M (raw - b), after M and in the calibrated "
              "axes (w = g p, p the direction of f; the calibration takes it out: a = f - g sum_j theta_j phi_j(p, t, "
              "T)); it is not an addition to the raw reading, which differs by the scale and misalignment acting on it")


def physics(mod, name):
    """An effect's definition in the convention of CONVENTION: the catalogue's `f_i += ...` with f the reading
    calibrated by M."""
    import re
    return re.sub(r"\bf_([i1-3]) \+=", r"[M (raw - b)]_\1 +=", mod.EFFECT_PHYSICS[name])


def catalogue_markdown(mod):
    """The table of the effects calibrate-norm can add, each with its definition in the norm convention and its
    parameters with their units: docs/diagnose.md and docs/norm_001.md hold it (a test compares them)."""
    rows = ["| effect | its term in the reading calibrated by M, [M (raw - b)]_i (w = g p) | parameters (unit) |",
            "|---|---|---|"]
    for name in mod.EFFECTS:
        pars = ", ".join(f"{p} ({u})" for p, u in zip(mod.EFFECTS[name], mod.EFFECT_UNITS[name]))
        rows.append(f"| `{name}` | {physics(mod, name).replace('|', chr(92) + '|')} | {pars} |")
    return "\n".join(rows) + "\n"


def fixed_point(ext, f):
    """(F, p) for readings f (K, 3) over g: F = f - Phi(p) theta with p the direction of F, iterated FIXED_POINT
    times or until p stops moving."""
    p = f.T / np.linalg.norm(f, axis=1)
    for _ in range(FIXED_POINT):
        F = f - ext.term(p).T
        q = F.T / np.linalg.norm(F, axis=1)
        done = np.abs(q - p).max() < 1e-16
        p = q
        if done:
            break
    return f - ext.term(p).T, p


class Extension:
    """The effects added to the norm relation on a log's still intervals: their parameters theta (over g, the
    units of EFFECT_UNITS), their basis at the fit's directions and what the remainder needs of them."""

    def __init__(self, mod, names, stills, temps, path, rates=None, temp_ref=20.0, option=None, thermal_range=None):
        self.mod, self.names, self.path = mod, tuple(names), path
        t_mid = np.array([(st.start + st.stop) / 2 for st in stills])
        self.t_ref = float((t_mid.min() + t_mid.max()) / 2)
        self.t = t_mid - self.t_ref
        need = {v for x in names for v in mod.EFFECT_VARIABLES[x]}
        if need & {"temp_c", "temp_rate_c_s"} and temps is None:
            raise DataError(f"{path}: {opt('effects')} "
                            + ", ".join(x for x in names if {"temp_c", "temp_rate_c_s"} & set(mod.EFFECT_VARIABLES[x]))
                            + " needs each sample's temperature: the log has no temperature column (temp_c, C)",
                            param="effects")
        # the effects' temperature counted from temp_ref (C): the generated basis reads T - 20, so T is shifted
        self.temp_ref = float(temp_ref)
        self.temp = np.full(len(stills), 20.0) if temps is None else np.asarray(temps, float) - self.temp_ref + 20.0
        self.rate = np.zeros(len(stills)) if rates is None else np.asarray(rates, float)     # C/s
        self.labels = [p for x in names for p in mod.EFFECTS[x]]
        self.units = [u for x in names for u in mod.EFFECT_UNITS[x]]
        self.theta = np.zeros(len(self.labels))
        self.phi = self.jac = self.p = self.n = None
        self.thermal_range = thermal_range     # (lowest, highest) C of the still intervals, with --thermal-degree
        self.option = option or f"--effect {','.join(self.names)}"          # how the user asked for it, in messages

    def basis(self, p):
        """phi_j at directions p (3, K), shape (P, 3, K)."""
        return np.concatenate([self.mod.effect_basis(x, p, self.t, self.temp, self.rate) for x in self.names])

    def term(self, p):
        """The effect's term at theta, directions p (3, K): shape (3, K), over g."""
        return np.einsum("j,jik->ik", self.theta, self.basis(p))

    def at(self, p, n):
        """Fix the directions: p of M (raw - b), where the term is evaluated, and n of the reading with the term
        taken out (the direction of (2.2))."""
        self.p, self.n = p, n
        self.phi = self.basis(p)
        self.jac = np.concatenate([self.mod.effect_jacobian_bound(x, self.t, self.temp, self.rate) for x in self.names])

    def columns(self, n):
        """The first-order columns n . phi_j(p) of (2.2), shape (P, K)."""
        return np.einsum("jik,ik->jk", self.phi, n)

    def extra(self, th_box, A_box, e_box, nu, v_set=None):
        """(v, rho) per interval for a box of the correction theta' (|theta'| <= th_box) and of the base's (A_box,
        e_box): |v| <= |Phi(p)| th_box + r, r >= |(Phi(m) - Phi(p)) theta| <= L |m - p| with L = ||sum_j
        (|theta_j| + th_box_j) b_j||_2 (`lipschitz`). With F - m = A m + d, |d| <= |eps/g| + nu + |v|, the angle
        between F and m has sine at most delta = |F - m|, so |n - m| <= K_DIR delta (delta <= 0.1); |m - p| <=
        |m - n| + |n - p| =: D; so r <= L (K_DIR (a + e + nu + v_lin + r) + |n - p|), solved for r. rho bounds
        the part along n, |n^T (Phi(m) - Phi(p)) theta|, which enters (2.2) at first order: the smaller of r and
        D sum_k sum_j (|theta_j| + th_box_j) sum_i |n_i| s_j[i, k], s_j the Jacobian's bound within D of p
        (generated `effect_slope_bound`: at p itself, not the ball's worst). `v_set` (3, K): a bound of |Phi(p)
        theta'| componentwise over a set that holds the truth (norm_information.effect_reach), where smaller."""
        a, e = float(np.linalg.norm(A_box)), float(np.linalg.norm(e_box))
        v_box = np.einsum("jik,j->ik", np.abs(self.phi), th_box)
        v_lin = np.linalg.norm(v_box if v_set is None else np.minimum(v_box, v_set), axis=0)
        size = np.abs(self.theta) + th_box
        L = lipschitz(self.jac, size)
        dp = np.linalg.norm(self.n - self.p, axis=0)
        room = 1.0 - K_DIR * L
        r = np.where(room > 0, L * (K_DIR * (a + e + nu + v_lin) + dp) / np.where(room > 0, room, 1.0), np.inf)
        r = np.where(a + e + nu + v_lin + r <= 0.1, r, np.inf)
        if not np.all(np.isfinite(r)):
            return np.full(r.shape, np.inf), np.full(r.shape, np.inf)
        D = (K_DIR * (a + e + nu + v_lin + r) + dp) * (1 + 1e-12)
        Dc = np.minimum(D, self._components(A_box, e_box, nu + v_lin + r, D) + dp)
        slope = np.concatenate([self.mod.effect_slope_bound(x, self.p, D, self.t, self.temp, self.rate)
                                for x in self.names])
        along = np.einsum("j,jick,ik,ck->k", size, slope, np.abs(self.n), Dc) * (1 + 1e-12)
        return (v_lin + r) * (1 + 1e-12), np.minimum(r, along) * (1 + 1e-12)

    def _components(self, A_box, e_box, w, D):
        """A bound of |n - m| per coordinate (3, K), with Delta = F - m = A m + e + x, |x| <= w (noise and the
        effect's part), |Delta| <= delta: n - m = (P_m Delta - m ((1 - |F|) m^T Delta + |Delta|^2) / (|F| + 1)) / |F|
        exactly (|F|^2 = 1 + 2 m^T Delta + |Delta|^2), so |(n - m)_c| <= (|(P_n Delta)_c| + 2 |n - m| delta +
        |m_c| 2 delta^2 / (2 - delta)) / (1 - delta), and |(P_n Delta)_c| <= (|P_n| (|A| (|n| + D) + |e|))_c + w
        (a row of a projection has norm at most 1); D >= |n - m|, |m| <= |n| + D."""
        n = self.n
        delta = np.linalg.norm(A_box) * (1 + D) + np.linalg.norm(e_box) + w
        Pn = np.abs(np.eye(3)[:, :, None] - n[:, None, :] * n[None, :, :])        # (3, 3, K)
        inner = np.abs(A_box) @ (np.abs(n) + D) + np.abs(e_box)[:, None]           # (3, K)
        Pd = np.einsum("cdk,dk->ck", Pn, inner) + w
        if np.any(delta >= 0.5):
            return np.full(n.shape, np.inf)
        out = (Pd + 2 * D * delta + (np.abs(n) + D) * 2 * delta ** 2 / (2 - delta)) / (1 - delta)
        return out * (1 + 1e-12)

    def fixed_point(self, f):
        """`fixed_point` with this extension's theta."""
        return fixed_point(self, f)

    def verdict(self, res, noise, nu):
        """`verdict` of this extension on a fit."""
        return verdict(self.mod, res, noise, nu, self)

    def effects_out(self, lo, hi, a_priori):
        """`effects_out` of this extension: the effects' parameters with their bounds."""
        return effects_out(self, lo, hi, a_priori)[0]

    def identifiable(self, base):
        """The effect parameters these intervals cannot identify beside the base model's columns `base` (an exact
        rank test, as diagnose_norm decides equivalence): their labels."""
        from . import diagnose_norm
        cols = self.columns(self.n)
        r = diagnose_norm.rank(np.vstack([base, cols]))
        if r == base.shape[0] + cols.shape[0]:
            return []
        return [lab for j, lab in enumerate(self.labels)
                if diagnose_norm.rank(np.vstack([base, np.delete(cols, j, axis=0)])) == r]


def verdict(mod, res, noise, nu, ext):
    """Whether the data are consistent with the extended relation, and its design: (the weighted minimax residual in
    units of each interval's bound, within 1 when consistent; A (9 + P, K) of
    the information set (bias and effect columns over |F|), each interval's bound base + left, the a-priori errors
    of the LP estimator (noise only)). The remainder is bounded on the box of the LP estimator's errors (as the base
    model's verdict bounds (2.3) on it); consistent when some correction meets every interval's bound (a weighted
    minimax fit within 1)."""
    from ..solve import lp
    from ..solve import highs
    from .norm_information import design, lower, remainder_per_interval
    s, n = res["sigma"], res["n"]
    A, f = design(mod, res, ext)
    base = noise / f
    _, err = lp.primal(A / base)
    box = lower(err)
    left, _ = remainder_per_interval((n * f).T, box, err[6:9], nu, ext.extra(err[9:], box, err[6:9], nu))
    if not np.all(np.isfinite(left)):
        raise DataError(f"{ext.path}: with {ext.option} the fit's effects are too "
                        f"large ({', '.join(f'{x}={v:+.2g}' for x, v in zip(ext.labels, ext.theta))}) for the "
                        "remainder of (2.2) to be bounded on the box the orientations guarantee: no verdict; "
                        "--diagnose names what the data need", param="effects")
    t = highs.chebyshev_fit(A, s, weights=base + left)[1]
    return float(t), A, base + left, err


def effects_out(ext, lo, hi, a_priori):
    """The effects' parameters: estimate (the fit's theta plus the midpoint of the set's correction) and guaranteed
    error over the information set, per effect, with units and the reference of time and temperature."""
    from ..solve import taylor
    mid, half = taylor.midrad(lo, hi)
    theta = ext.theta + mid
    out, j = {}, 0
    for x in ext.names:
        names = ext.mod.EFFECTS[x]
        out[x] = {"physics": physics(ext.mod, x), "parameters": {
            p: {"estimate": float(theta[j + i]), "guaranteed_error": float(half[j + i]),
                "guaranteed_error_a_priori": float(a_priori[j + i]), "unit": ext.mod.EFFECT_UNITS[x][i]}
            for i, p in enumerate(names)}}
        j += len(names)
    return out, theta, half


def file_entry(res, ext_names, temps_range):
    """The calibration file's `effects` (and its model and note): what `apply` takes out of each sample and how its
    bound grows; `temps_range` (C), the lowest and highest temperature of the samples in the still intervals, or
    None."""
    eff = res["effects"]
    applied = [x for x in ext_names if x not in SESSION_ONLY]
    frame = np.abs(np.asarray(res["matrix"]) @ np.linalg.inv(np.asarray(res["matrix_fit"])) - np.eye(3))
    return {"model": MODEL, "note": res["calibration"]["note"] + NOTE, "effects": {
            "frame": frame.tolist(), "names": applied, "time_ref_s": res["effect_reference"]["time_s"],
            "temp_ref_c": res["effect_reference"]["temp_c"],
            "temp_range_c": temps_range,
            "theta": [eff[x]["parameters"][p]["estimate"] for x in applied for p in eff[x]["parameters"]],
            "bound": [eff[x]["parameters"][p]["guaranteed_error"] for x in applied for p in eff[x]["parameters"]],
            "not_applied": {x: SESSION_ONLY[x].format(t_ref=res["effect_reference"]["time_s"], log=res["log"])
                            for x in ext_names if x in SESSION_ONLY}}}


MODEL = "a = M (raw - b) - g sum_j theta_j phi_j(p, T), p = M (raw - b) / |M (raw - b)|"
NOTE = ("; with effects, inside the brackets also g |Phi(p)| bound + |frame| g (|Phi(p) theta| + |Phi(p)| bound) + g L "
        "(|theta| + bound) |m - p| (L the effects' Lipschitz bound, |m - p| bounded from the sample's own bound)")


def needs_temperature(cal):
    """The calibration file's effects need each sample's temperature (and hold within its calibrated range)."""
    from .. import models
    eff = cal.get("effects") or {}
    mod = models.load("norm")
    return any("temp_c" in mod.EFFECT_VARIABLES.get(x, ()) for x in eff.get("names", ()))


def apply_term(cal, a0, temp, g, path):
    """The effects of a calibration file at corrected samples a0 = M (raw - b) (3, N), m/s^2: the term g Phi(p)
    theta (3, N) to take out (p = a0 / |a0|), g |Phi(p)| h (3, N) (h the bound of theta), c = g L (|theta| + h)
    (N), the bound's growth per unit |m - p| (`apply` composes them), and Phi(p) (J, 3, N) itself."""
    from .. import models
    mod = models.load("norm")
    eff = cal["effects"]
    names = eff["names"]
    count = sum(len(mod.EFFECTS[x]) for x in names)
    if len(eff["theta"]) != count or len(eff["bound"]) != count:
        raise DataError(f"{path}: effects: theta and bound must hold one number per parameter of "
                        f"{', '.join(names) or 'no effect'} ({count}), not {len(eff['theta'])} and {len(eff['bound'])}",
                        param="calibration")
    N = a0.shape[1]
    T = np.full(N, 20.0)
    if any("temp_c" in mod.EFFECT_VARIABLES[x] for x in names):
        if temp is None:
            raise DataError(f"{path}: the calibration holds {', '.join(names)}: the log needs each sample's "
                            "temperature (a temp_c column, C)", param="log")
        T = np.asarray(temp, float)
        lo, hi = eff["temp_range_c"]
        shift = 20.0 - float(eff.get("temp_ref_c", 20.0))      # the basis reads T - 20: counted from temp_ref_c
        out = np.flatnonzero((T < lo) | (T > hi) | ~np.isfinite(T))
        if out.size:
            raise DataError(f"{path}: {out.size} sample(s) at temperatures outside the calibrated range [{lo:g}, "
                            f"{hi:g}] C (the first, sample {out[0] + 1}, at {T[out[0]]:g} C): the effects' bound "
                            "holds there only", param="log")
        T = T + shift
    p = a0 / np.maximum(np.linalg.norm(a0, axis=0), 1e-300)
    phi = np.concatenate([mod.effect_basis(x, p, 0.0, T) for x in names])
    jac = np.concatenate([mod.effect_jacobian_bound(x, 0.0, T) for x in names])
    theta, h = np.asarray(eff["theta"], float), np.asarray(eff["bound"], float)
    return (g * np.einsum("j,jik->ik", theta, phi), g * np.einsum("j,jik->ik", h, np.abs(phi)),
            g * lipschitz(jac, np.abs(theta) + h), phi)


def apply(cal, raw, frame="garant", temp=None, path="the log"):
    """io/calibration.py `apply` for a calibration with catalogue effects (9 parameters: no nonlinearity), each
    sample at its temperature `temp` (C) where an effect needs it. With a = a0 - g Phi(p) theta
    (p = a0 / |a0|) the truth a_t = g m meets a / g = (E + A') m + eps' / g + x, where A', eps' are bounded by
    bound_matrix and bound_bias as without effects and x = Phi(p) (theta_t - theta) + (Phi(m) - Phi(p)) theta_t +
    (K - E) Phi(m) theta_t (K - E the frame of the set's midpoint, bounded by `frame`): componentwise
        |x| <= |Phi(p)| h + |frame| (|Phi(p) theta| + |Phi(p)| h) + (1 + |frame| 1) L (|theta| + h) |m - p|,
    and |m - p| <= 2 |a0 / g - m| <= 2 (|a - a_t| + |g Phi(p) theta|) / g closes the bound on itself."""
    from ..io.calibration import imu_tk_form
    g = cal["g"]
    a0 = cal["M"] @ (np.asarray(raw, float) - cal["b"]).T
    term, lin, c, phi = apply_term(cal, a0, temp, g, path)
    a = a0 - term
    F = np.abs(np.asarray(cal["effects"]["frame"], float))
    inverse = np.linalg.inv(np.eye(3) - cal["bound_matrix"])
    v = cal["bound_matrix"] @ np.abs(a) + cal["bound_bias"][:, None] + lin
    if "information_set" in cal:      # the linear part over the set (workflows/sample_set.py), not over its box
        from . import sample_set
        st = cal["information_set"]
        u = float(st["g_uncertainty"])
        v = np.minimum(v, (1 + u) * sample_set.linear_sup(st, a, g, phi) + u * np.abs(a))
    bound0 = inverse @ (v + F @ (np.abs(term) + lin))
    grow = inverse @ (1.0 + F.sum(axis=1))                     # the bound's growth per unit of c |m - p|
    room = g - 2.0 * c * float(np.linalg.norm(grow))
    if np.any(room <= 0):
        raise DataError(f"{path}: the calibration's effects are too large for their bound to close (|theta| L >= 1/2)",
                        param="calibration")
    moved = 2.0 * (np.linalg.norm(bound0, axis=0) + np.linalg.norm(term, axis=0)) / room
    bound = bound0 + grow[:, None] * (c * moved)
    if frame == "imu_tk":
        R = imu_tk_form(cal)[2]
        a, bound = R @ a, (np.abs(R) @ bound) * (1 + 1e-12)
    return a.T, (bound * (1 + 1e-12)).T
