"""`garant simulate`: readings from the exact nonlinear model, with hidden effects, for testing."""
import functools
import math
import re
import types

import numpy as np

from ..errors import DataError, opt
from ..io.positions import read_plan
from ..models import layout, reachable_grid, unreachable
from ..io.report import write_text

ROW_SECONDS = 60.0        # one position a minute


def plan_positions(mod, plan):
    """Positions (degrees, (N, n_angles)) and mountings ((N,) or None) of a named plan: optimal10 (the
    model's own plan), quarter16 / quarter (every quarter turn), grid:AxB (a step per angle) or grid:A
    (one step for every angle); with several mountings, every position in each of them."""
    n = len(mod.ANGLES)
    ranges = mod.ANGLE_RANGES_DEG
    detents = mod.ANGLE_DETENTS_DEG
    if str(plan).endswith(".csv"):                          # a plan file, as `garant plan -o` writes it
        names, mount_names = layout(mod)
        P, mounts = read_plan(plan, names, mount_names if len(mount_names) > 1 else None)
        _check_reachable(mod, ranges, detents, P, plan)
        return P, mounts
    if plan == "optimal10":
        if not len(mod.PLAN_DEG):
            raise DataError(f"this model has no optimal plan of its own; write one with `garant plan --model STAND "
                            f"-o PLAN.csv` and pass {opt('plan')} PLAN.csv, or use quarter or grid:STEP")
        P = np.asarray(mod.PLAN_DEG, float)
        _check_reachable(mod, ranges, detents, P, "the model's plan")
    elif plan in ("quarter16", "quarter"):
        P = reachable_grid(ranges, detents, 90.0)
    else:
        m = re.fullmatch(r"grid:(\d+(?:\.\d+)?(?:x\d+(?:\.\d+)?)*)", plan)
        if not m:
            raise DataError(f"unknown plan {plan!r}: use optimal10, quarter, grid:AxB or grid:A (degrees)",
                            param="plan")
        steps = [float(v) for v in m.group(1).split("x")]
        steps = steps * n if len(steps) == 1 else steps
        if len(steps) != n or any(s <= 0 or 360 % s for s in steps):
            raise DataError(f"{plan}: give {n} step(s) that divide 360 degrees", param="plan")
        P = reachable_grid(ranges, detents, steps, what=f"--plan {plan}")
    mounts = mod.MOUNTINGS
    if len(mounts) == 1:
        return P, None
    return np.tile(P, (len(mounts), 1)), np.repeat(np.arange(len(mounts)), len(P))


def _check_reachable(mod, ranges, detents, P, where):
    bad = unreachable(ranges, detents, P)
    if bad:
        k, i, v = bad
        can = (f"its detents are {', '.join(f'{d:g}' for d in detents[i])}" if len(detents[i])
               else f"its range is [{ranges[i][0]:g}, {ranges[i][1]:g}]")
        raise DataError(f"{where}: position {k + 1}: {mod.ANGLES[i]} = {v:g} deg is not reachable ({can})",
                        param="plan")


def parse_effect(text, catalogue, base_angles=None):
    """'NAME=v1,v2,...' -> (name, values); one value per parameter of the effect, in its units."""
    name, _, vals = text.partition("=")
    if name not in catalogue:
        raise DataError(f"unknown effect {name!r}; the catalogue: {', '.join(catalogue)}", param="effect")
    try:
        values = [float(v) for v in vals.split(",")] if vals else []
    except ValueError:
        raise DataError(f"{opt('effect')} {text}: values must be numbers") from None
    if not all(math.isfinite(v) for v in values):
        raise DataError(f"{opt('effect')} {text}: values must be finite numbers (not inf or nan)")
    n = len(catalogue[name].params)
    if catalogue[name].angle is not None and base_angles is not None and catalogue[name].angle not in base_angles:
        raise DataError(f"{opt('effect')} {name} is an error of the encoder of angle {catalogue[name].angle!r}; this "
                        f"stand's "
                        f"angles are {', '.join(base_angles)}")
    if len(values) != n:
        names = ", ".join(p.name for p in catalogue[name].params)
        raise DataError(f"{opt('effect')} {name} takes {n} values ({names}), got {len(values)}")
    return name, values


@functools.lru_cache(maxsize=64)
def exact_module(model):
    """The rendered module of a (possibly extended) model, executed in memory (kept per model: a model is
    frozen, and its module is only read)."""
    from garant.derive import codegen
    files = codegen.model_files(model, "mem", "mem")
    key = f"mem/{model.stand.name}.py"
    mod = types.ModuleType(model.stand.name)
    exec(compile(files[key], key, "exec"), mod.__dict__)
    return mod


def rows_time_temp(n):
    """time_s (s) and temp_c (C) of each row: a minute per position, temperature neither constant
    nor proportional to time (so drift and temperature can be told apart)."""
    k = np.arange(n)
    return k * ROW_SECONDS, 20 + 4 * np.sin(2 * np.pi * k / max(n, 2) * 1.5) + 0.02 * k


#: The kinds of a stand's parameters a --size can name (the generated module's PARAMETER_KINDS).
KINDS = ("stand", "mounting", "gravity", "block", "bias")


def parse_sizes(text):
    """--size: one bound for every parameter ('1e-4'), or one per kind ('stand=1e-4,mounting=3e-3,block=1e-2,
    bias=0.05'; a kind not named is drawn as 0): {kind: bound}, each a finite number >= 0 and < 1
    (dimensionless or rad; a bias over g)."""
    def number(v, what):
        try:
            x = float(v)
        except ValueError:
            raise DataError(f"{opt('size')}: {what} {v[:40]!r} is not a number") from None
        if not (math.isfinite(x) and 0 <= x < 1):
            raise DataError(f"{opt('size')}: {what} {v[:40]!r} must be a number >= 0 and < 1 (the bound of a small "
                            f"error)")
        return x
    if "=" not in text:
        return dict.fromkeys(KINDS, number(text, "the bound"))
    out = dict.fromkeys(KINDS, 0.0)
    for part in text.split(","):
        kind, _, v = part.partition("=")
        if kind.strip() not in KINDS:
            raise DataError(f"{opt('size')}: unknown kind {kind.strip()[:40]!r}; name one of {', '.join(KINDS)}")
        out[kind.strip()] = number(v.strip(), kind.strip())
    return out


def thermal_degree(name):
    """k of a thermal coefficient's name (Gamma11_T2 -> 2, bias3_T1 -> 1; derive/effects.py `thermal`), else 0."""
    from garant.derive.effects import BLOCK_PARAMETERS
    base, _, k = name.rpartition("_T")
    return int(k) if base in BLOCK_PARAMETERS and k in ("1", "2", "3") else 0


def read_truth(path, mod, thermal=False):
    """--truth FILE.json: {"parameter name": value, ...} for parameters of the stand (the others 0), each a
    finite number with |value| < 1 (rad, dimensionless, a bias over g); with `thermal` also the coefficients
    p_Tk of (T - T0)^k of a block parameter p (per C^k)."""
    from ..io import files
    data = files.read_json(path, "a JSON object of parameter values", param="truth")
    if not isinstance(data, dict):
        raise DataError(f'{path}: expected a JSON object such as {{"kappa": 5e-5, "bias1": 0.05}}', param="truth")
    for name, v in data.items():
        if thermal and thermal_degree(name):
            pass
        elif name not in mod.PARAMETER_NAMES:
            raise DataError(f"{path}: {name[:40]!r} is not a parameter of this stand; its parameters: "
                            + ", ".join(mod.PARAMETER_NAMES), param="truth")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and abs(v) < 1):
            raise DataError(f"{path}: {name}: {str(v)[:40]} must be a number with |value| < 1 (rad, dimensionless, "
                            "or a bias over g)", param="truth")
    return {k: float(v) for k, v in data.items()}


def simulate(base_model, mod, plan, effects, sigma, seed, g=9.81, size=1e-4, truth=None, temperatures=None):
    """Readings at a plan with the given effects and noise bounded by sigma, the stand's own errors drawn at
    random within `size` (a number, or {kind: bound} as parse_sizes gives), or set by `truth` ({name:
    value}, the others 0). `temperatures` (C): the plan at each of these chamber temperatures, the truth's
    thermal coefficients (p_Tk) about the middle of their range."""
    from garant.derive import effects as catalogue
    rng = np.random.default_rng(seed)
    names = [n for n, _ in effects]
    thermal = {}
    if temperatures is not None:
        thermal = {n: v for n, v in (truth or {}).items() if thermal_degree(n)}
        degree = max(map(thermal_degree, thermal), default=0)
        if degree:
            names.append(catalogue.thermal_name(degree, int(round(0.5 * (min(temperatures) + max(temperatures))))))
    ext = catalogue.extend(base_model, names)
    exact = exact_module(ext)
    P, mounts = plan_positions(mod, plan)
    if temperatures is not None:
        n = len(P)
        P = np.vstack([P] * len(temperatures))
        mounts = None if mounts is None else np.concatenate([mounts] * len(temperatures))
    sizes = size if isinstance(size, dict) else dict.fromkeys(KINDS, size)
    kinds = dict(zip(mod.PARAMETER_NAMES, mod.PARAMETER_KINDS))
    values = {p.name: rng.uniform(-1, 1) * sizes.get(kinds.get(p.name, "block"), 0.0) for p in base_model.parameters}
    if truth is not None:
        values = {p.name: truth.get(p.name, 0.0) for p in base_model.parameters}
    for name, vals in effects:
        values.update(zip((p.name for p in catalogue.CATALOGUE[name].params), vals))
    values.update(thermal)
    physical = [values.get(n, 0.0) for n in exact.PARAMETER_NAMES]
    t, T = rows_time_temp(len(P))
    if temperatures is not None:
        T = np.repeat(np.asarray(temperatures, float), n)
    kw = {v: x for v, x in (("time_s", t), ("temp_c", T)) if v in exact.readings.__code__.co_varnames}
    if mounts is not None:
        f = np.column_stack([exact.readings(*np.deg2rad(P[k]), physical, g, mount=int(mounts[k]),
                                            **{v: x[k] for v, x in kw.items()}) for k in range(len(P))]).T
    else:
        f = exact.readings(*np.deg2rad(P).T, physical, g, **kw).T
    f = f + g * rng.uniform(-sigma, sigma, f.shape)
    return P, f, t, T, values, mounts


def write(path, P, f, t, T, names=("alpha", "beta"), mounts=None, mount_names=None):
    """CSV with a column <angle>_deg per angle, f1..f3 (m/s^2), mount (if any), time_s, temp_c."""
    lines = [",".join([f"{a}_deg" for a in names] + ["f1", "f2", "f3"] + (["mount"] if mounts is not None else [])
                      + ["time_s", "temp_c"])]
    for k, (pos, row, ti, Ti) in enumerate(zip(P, f, t, T)):
        cells = [f"{a:g}" for a in pos] + [repr(float(v)) for v in row]
        cells += [mount_names[mounts[k]]] if mounts is not None else []
        lines.append(",".join(cells + [f"{ti:g}", f"{Ti:.4f}"]))
    write_text(path, "\n".join(lines) + "\n")
