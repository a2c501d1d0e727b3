"""`garant simulate --model norm`: the log of a unit turned by hand, as calibrate-norm reads it.

Still intervals at random, face or 001-optimal orientations (shuffled, or in the plan's own order: a person turning
a board face by face while it heats), joined by moves, at the sample rate given; a temperature profile (a warm-up
towards an end temperature, or a heat-cool cycle); any catalogue effect of the norm relation in the convention
calibrate-norm computes and prints it in (workflows/norm_effects.py CONVENTION: the term in the reading calibrated
by the truth's M); noise uniform within +-sigma g on each axis of each sample. The truth (the block's errors of
(1.3) of 001, its M and b, the effects' parameters, and where every effect is affine in the specific force the raw
bias and Gamma at 60 temperatures across the still intervals' range) is written beside the log.
"""
import re

import numpy as np

from ..errors import DataError

#: Seconds of a still interval and of a move between two, and samples per second, unless given.
STILL_S, MOVE_S, RATE_HZ = 8.0, 2.0, 100.0


def orientations(plan, rng):
    """Unit directions (K, 3) of a plan for a unit turned by hand: random:N (N random directions), faces (the six
    faces, each twice), optimal (the 18 directions of section 4 of 001)."""
    from .. import models
    m = re.fullmatch(r"random:(\d+)", str(plan))
    if m:
        K = int(m.group(1))
        if not 1 <= K <= 100_000:
            raise DataError(f"--plan {plan}: give 1 to 100000 orientations", param="plan")
        d = rng.normal(size=(K, 3))
        return d / np.linalg.norm(d, axis=1)[:, None]
    if plan == "faces":
        return np.repeat(np.vstack([np.eye(3), -np.eye(3)]), 2, axis=0)
    if plan == "optimal":
        return np.array(models.load("norm").PLAN[:18], float)
    raise DataError(f"--plan {str(plan)[:40]!r}: a unit turned by hand takes random:N, faces or optimal",
                    param="plan")


def temperature(profile, t):
    """Each sample's temperature (C) at times t (s) of a profile: none (None), warmup:T0,T1,TAU (from T0 towards
    T1 with the time constant TAU, s) or cycle:T0,T1,PERIOD (T0 to T1 and back, a sine of that period, s)."""
    if profile in (None, "none"):
        return None
    m = re.fullmatch(r"(warmup|cycle):([-+0-9.eE]+),([-+0-9.eE]+),([-+0-9.eE]+)", str(profile))
    if not m:
        raise DataError(f"--temperature-profile {str(profile)[:40]!r}: give warmup:T0,T1,TAU or cycle:T0,T1,PERIOD "
                        "(C, C, s)",
                        param="temperature_profile")
    kind, a, b, tau = m.group(1), *(float(x) for x in m.group(2, 3, 4))
    if not (np.isfinite([a, b, tau]).all() and tau > 0 and -60 <= a <= 150 and -60 <= b <= 150):
        raise DataError(f"--temperature-profile {profile}: temperatures within -60..150 C and a time above 0 s",
                        param="temperature_profile")
    if kind == "warmup":
        return b - (b - a) * np.exp(-t / tau)
    return a + (b - a) * 0.5 * (1 - np.cos(2 * np.pi * t / tau))


def parse_effects(items, mod):
    """{effect: its parameters (over g, the units of EFFECT_UNITS)} of --effect NAME=v1,v2,... (repeatable)."""
    out = {}
    for item in items:
        name, _, values = str(item).partition("=")
        if name not in mod.EFFECTS:
            raise DataError(f"--effect {name[:40]!r}: a unit turned by hand takes {', '.join(mod.EFFECTS)}",
                            param="effect")
        try:
            v = [float(x) for x in values.split(",")]
        except ValueError:
            raise DataError(f"--effect {item[:60]}: give {len(mod.EFFECTS[name])} numbers after the =",
                            param="effect") from None
        if len(v) != len(mod.EFFECTS[name]) or not np.all(np.isfinite(v)) or np.abs(v).max() > 1:
            raise DataError(f"--effect {name}: give {len(mod.EFFECTS[name])} finite numbers of at most 1 in size "
                            f"({', '.join(mod.EFFECTS[name])})", param="effect")
        if name in out:
            raise DataError(f"--effect {name} is given twice", param="effect")
        out[name] = np.array(v)
    return out


def simulate(plan, effects, sigma, seed=0, g=9.81, size=1e-3, profile=None, ordered=False, still_s=STILL_S,
             move_s=MOVE_S, rate=RATE_HZ, revisit=0):
    """(t (N,), readings (N, 3) m/s^2, temperature (N,) or None, truth dict) of a unit turned by hand; `revisit`:
    the first orientations visited again at the end (hot, on a warm-up)."""
    from .. import models
    from .norm_effects import CONVENTION
    mod = models.load("norm")
    rng = np.random.default_rng(seed)
    dirs = orientations(plan, rng)
    if ordered:          # the way a person turns a unit: face up first, face down last (z from +1 to -1)
        dirs = dirs[np.argsort(-dirs[:, 2], kind="stable")]
    else:
        dirs = dirs[rng.permutation(len(dirs))]
    if not 0 <= revisit <= len(dirs):
        raise DataError(f"--revisit {revisit}: at most the {len(dirs)} orientations of the plan", param="revisit")
    dirs = np.vstack([dirs, dirs[:revisit][::-1]])           # back the way it came
    errors = rng.uniform(-size, size, 9)                  # lambda, alpha, beta, gamma, eps/g of (1.3) of 001
    P = np.eye(3) + np.array([[errors[0], 0, 0], [errors[3], errors[1], 0], [errors[4], errors[5], errors[2]]])
    per = int(round(still_s * rate)), int(round(move_s * rate))
    n = len(dirs) * sum(per)
    if n > 50_000_000:
        raise DataError(f"{n} samples: at most 50 million (fewer orientations, shorter stills or a lower rate)",
                        param="plan")
    t = np.arange(n) / rate
    T = temperature(profile, t)
    need = {v for x in effects for v in mod.EFFECT_VARIABLES[x]}
    if need & {"temp_c", "temp_rate_c_s"} and T is None:
        raise DataError("--effect " + ", ".join(x for x in effects if {"temp_c", "temp_rate_c_s"}
                                                & set(mod.EFFECT_VARIABLES[x]))
                        + " needs a temperature profile (--temperature-profile warmup:T0,T1,TAU)",
                        param="temperature_profile")
    still = np.zeros(n, bool)
    m = np.empty((n, 3))
    for k, d in enumerate(dirs):
        a = k * sum(per)
        still[a:a + per[0]] = True
        m[a:a + per[0]] = d
        turn = rng.normal(size=(per[1], 3))                   # a move: another direction each sample
        m[a + per[0]:a + sum(per)] = turn / np.linalg.norm(turn, axis=1)[:, None]
    mids = np.array([(k * sum(per) + (per[0] - 1) / 2) / rate for k in range(len(dirs))])
    t_ref = float((mids.min() + mids.max()) / 2)              # as calibrate-norm counts time (norm_effects.Extension)
    rate_T = np.zeros(n) if T is None else np.gradient(T, t)
    term = np.zeros((3, n))
    for name, theta in effects.items():
        basis = mod.effect_basis(name, m.T, t - t_ref, 20.0 if T is None else T, rate_T)
        term += np.einsum("j,jik->ik", theta, basis)
    f = g * (m.T + term)                                      # the reading calibrated by the truth's M
    raw = (P @ f).T + g * errors[6:9] + g * rng.uniform(-sigma, sigma, (n, 3))
    truth = {"parameters": dict(zip(("lambda1", "lambda2", "lambda3", "alpha", "beta", "gamma", "eps1/g", "eps2/g",
                                     "eps3/g"), errors.tolist())),
             "matrix": np.linalg.inv(P).tolist(), "bias": (g * errors[6:9]).tolist(),
             "effects": {x: dict(zip(mod.EFFECTS[x], v.tolist())) for x, v in effects.items()},
             "convention": CONVENTION, "time_ref_s": t_ref, "temp_ref_c": 20.0,
             "orientations": len(dirs), "ordered": bool(ordered), "revisited": int(revisit), "still_s": still_s,
             "move_s": move_s,
             "rate_hz": rate, "sigma": sigma, "g": g, "seed": seed, "plan": plan, "temperature_profile": profile}
    if T is not None:
        lo, hi = float(T[still].min()), float(T[still].max())
        truth["temperature_range_c"] = [lo, hi]
        if set(effects) <= THERMAL:
            truth["thermal"] = thermal_truth(mod, effects, P, errors[6:9], np.linspace(lo, hi, 60))
    return t, raw, T, truth


#: The effects affine in the specific force and functions of the temperature alone: a raw bias and a Gamma over T.
THERMAL = {"bias_temperature", "bias_temperature_2", "bias_temperature_3", "scale_temperature", "scale_temperature_2",
           "scale_temperature_3", "misalignment_temperature", "misalignment_temperature_2",
           "misalignment_temperature_3"}


def thermal_truth(mod, effects, P, eps, temps):
    """The raw bias over g and Gamma (raw = (E + Gamma(T)) w + g beta(T)) at each temperature: with the term c(T) +
    K(T) m in the calibrated reading, beta = eps + P c and Gamma = P (E + K) - E."""
    K = len(temps)
    zero, rate = np.zeros((3, K)), np.zeros(K)
    c = sum(np.einsum("j,jik->ik", th, mod.effect_basis(x, zero, 0.0, temps, rate)) for x, th in effects.items())
    cols = []
    for j in range(3):
        e = np.zeros((3, K))
        e[j] = 1.0
        cols.append(sum(np.einsum("j,jik->ik", th, mod.effect_basis(x, e, 0.0, temps, rate))
                        for x, th in effects.items()) - c)
    Kmat = np.stack(cols, axis=1)                         # (3, 3, K): K[:, j] the term's column j
    beta = eps[:, None] + P @ c
    gamma = np.einsum("il,ljk->ijk", P, np.eye(3)[:, :, None] + Kmat) - np.eye(3)[:, :, None]
    return {"temp_c": temps.tolist(), "bias_over_g": beta.T.tolist(), "gamma": np.moveaxis(gamma, 2, 0).tolist()}


def write(path, t, raw, T):
    """The log as a csv calibrate-norm reads: time_s, ax, ay, az (m/s^2) and temp_c (C) where there is one."""
    from ..io.report import write_chunks
    from ..io.text import csv_bytes
    cols = [t, *raw.T] + ([] if T is None else [T])
    header = "time_s,ax,ay,az" + ("" if T is None else ",temp_c")

    def pieces(step=1_000_000):
        yield (header + "\n").encode()
        for i in range(0, len(t), step):
            yield csv_bytes([c[i:i + step] for c in cols], digits=12)
    write_chunks(path, pieces())
