"""`garant simulate`: readings from the exact nonlinear model, with hidden effects, for testing."""
import re
import types

import numpy as np

from .data import DataError
from .plans import QUARTER_DEG

ROW_SECONDS = 60.0        # one position a minute


def plan_positions(mod, plan):
    """Positions (degrees) of a named plan: optimal10, quarter16, or grid:AxB (alpha, beta steps)."""
    if plan == "optimal10":
        return np.asarray(mod.PLAN_DEG, float)
    if plan == "quarter16":
        return np.asarray(QUARTER_DEG, float)
    m = re.fullmatch(r"grid:(\d+(?:\.\d+)?)x(\d+(?:\.\d+)?)", plan)
    if m:
        da, db = float(m.group(1)), float(m.group(2))
        if da <= 0 or db <= 0 or 360 % da or 360 % db:
            raise DataError(f"grid steps must divide 360 degrees, got {plan}")
        return np.array([(a, b) for a in np.arange(0, 360, da) for b in np.arange(0, 360, db)])
    raise DataError(f"unknown plan {plan!r}: use optimal10, quarter16 or grid:AxB (degrees)")


def parse_effect(text, catalogue):
    """'NAME=v1,v2,...' -> (name, values); one value per parameter of the effect, in its units."""
    name, _, vals = text.partition("=")
    if name not in catalogue:
        raise DataError(f"unknown effect {name!r}; the catalogue: {', '.join(catalogue)}")
    try:
        values = [float(v) for v in vals.split(",")] if vals else []
    except ValueError:
        raise DataError(f"--effect {text}: values must be numbers") from None
    n = len(catalogue[name].params)
    if len(values) != n:
        names = ", ".join(p.name for p in catalogue[name].params)
        raise DataError(f"--effect {name} takes {n} values ({names}), got {len(values)}")
    return name, values


def exact_module(model):
    """The rendered module of a (possibly extended) model, executed in memory."""
    from derive import codegen
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


def simulate(base_model, mod, plan, effects, sigma, seed, g=9.81, size=1e-4):
    """Readings at a plan with random small errors, the given effects and noise bounded by sigma."""
    from derive import effects as catalogue
    rng = np.random.default_rng(seed)
    ext = catalogue.extend(base_model, [n for n, _ in effects])
    exact = exact_module(ext)
    P = plan_positions(mod, plan)
    values = {p.name: rng.uniform(-size, size) for p in base_model.parameters}
    for name, vals in effects:
        values.update(zip((p.name for p in catalogue.CATALOGUE[name].params), vals))
    physical = [values[n] for n in exact.PARAMETER_NAMES]
    t, T = rows_time_temp(len(P))
    kw = {v: x for v, x in (("time_s", t), ("temp_c", T)) if v in exact.readings.__code__.co_varnames}
    f = exact.readings(*np.deg2rad(P).T, physical, g, **kw).T
    f = f + g * rng.uniform(-sigma, sigma, f.shape)
    return P, f, t, T, values


def write(path, P, f, t, T):
    with open(path, "w") as fh:
        fh.write("alpha_deg,beta_deg,f1,f2,f3,time_s,temp_c\n")
        for (a, b), row, ti, Ti in zip(P, f, t, T):
            fh.write(f"{a:g},{b:g},{float(row[0])!r},{float(row[1])!r},{float(row[2])!r},{ti:g},{Ti:.4f}\n")
