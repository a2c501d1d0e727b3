"""`garant simulate`: readings from the exact nonlinear model, with hidden effects, for testing."""
import math
import re
import types

import numpy as np

from ..errors import DataError
from ..io.positions import read_plan
from ..models import layout, reachable_grid, unreachable
from ..io.report import write_text

ROW_SECONDS = 60.0        # one position a minute


def plan_positions(mod, plan):
    """Positions (degrees, (N, n_angles)) and mountings ((N,) or None) of a named plan: optimal10 (the
    model's own plan), quarter16 / quarter (every quarter turn), grid:AxB (a step per angle) or grid:A
    (one step for every angle); with several mountings, every position in each of them."""
    n = len(mod.ANGLES)
    ranges = getattr(mod, "ANGLE_RANGES_DEG", ((0, 360),) * n)
    detents = getattr(mod, "ANGLE_DETENTS_DEG", ((),) * n)
    if str(plan).endswith(".csv"):                          # a plan file, as `garant plan --csv` writes it
        names, mount_names = layout(mod)
        P, mounts = read_plan(plan, names, mount_names if len(mount_names) > 1 else None)
        _check_reachable(mod, ranges, detents, P, plan)
        return P, mounts
    if plan == "optimal10":
        if not len(getattr(mod, "PLAN_DEG", ())):
            raise DataError("this model has no optimal plan of its own; write one with `garant plan STAND --csv "
                            "PLAN.csv` and pass --plan PLAN.csv, or use quarter or grid:STEP")
        P = np.asarray(mod.PLAN_DEG, float)
        _check_reachable(mod, ranges, detents, P, "the model's plan")
    elif plan in ("quarter16", "quarter"):
        P = reachable_grid(ranges, detents, 90.0)
    else:
        m = re.fullmatch(r"grid:(\d+(?:\.\d+)?(?:x\d+(?:\.\d+)?)*)", plan)
        if not m:
            raise DataError(f"unknown plan {plan!r}: use optimal10, quarter, grid:AxB or grid:A (degrees)")
        steps = [float(v) for v in m.group(1).split("x")]
        steps = steps * n if len(steps) == 1 else steps
        if len(steps) != n or any(s <= 0 or 360 % s for s in steps):
            raise DataError(f"{plan}: give {n} step(s) that divide 360 degrees")
        P = reachable_grid(ranges, detents, steps, what=f"--plan {plan}")
    mounts = getattr(mod, "MOUNTINGS", None)
    if mounts is None:
        return P, None
    return np.tile(P, (len(mounts), 1)), np.repeat(np.arange(len(mounts)), len(P))


def _check_reachable(mod, ranges, detents, P, where):
    bad = unreachable(ranges, detents, P)
    if bad:
        k, i, v = bad
        can = (f"its detents are {', '.join(f'{d:g}' for d in detents[i])}" if len(detents[i])
               else f"its range is [{ranges[i][0]:g}, {ranges[i][1]:g}]")
        raise DataError(f"{where}: position {k + 1}: {mod.ANGLES[i]} = {v:g} deg is not reachable ({can})")


def parse_effect(text, catalogue, base_angles=None):
    """'NAME=v1,v2,...' -> (name, values); one value per parameter of the effect, in its units."""
    name, _, vals = text.partition("=")
    if name not in catalogue:
        raise DataError(f"unknown effect {name!r}; the catalogue: {', '.join(catalogue)}")
    try:
        values = [float(v) for v in vals.split(",")] if vals else []
    except ValueError:
        raise DataError(f"--effect {text}: values must be numbers") from None
    if not all(math.isfinite(v) for v in values):
        raise DataError(f"--effect {text}: values must be finite numbers (not inf or nan)")
    n = len(catalogue[name].params)
    if catalogue[name].angle is not None and base_angles is not None and catalogue[name].angle not in base_angles:
        raise DataError(f"--effect {name} is an error of the encoder of angle {catalogue[name].angle!r}; this stand's "
                        f"angles are {', '.join(base_angles)}")
    if len(values) != n:
        names = ", ".join(p.name for p in catalogue[name].params)
        raise DataError(f"--effect {name} takes {n} values ({names}), got {len(values)}")
    return name, values


def exact_module(model):
    """The rendered module of a (possibly extended) model, executed in memory."""
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


def simulate(base_model, mod, plan, effects, sigma, seed, g=9.81, size=1e-4):
    """Readings at a plan with random small errors, the given effects and noise bounded by sigma."""
    from garant.derive import effects as catalogue
    rng = np.random.default_rng(seed)
    ext = catalogue.extend(base_model, [n for n, _ in effects])
    exact = exact_module(ext)
    P, mounts = plan_positions(mod, plan)
    values = {p.name: rng.uniform(-size, size) for p in base_model.parameters}
    for name, vals in effects:
        values.update(zip((p.name for p in catalogue.CATALOGUE[name].params), vals))
    physical = [values[n] for n in exact.PARAMETER_NAMES]
    t, T = rows_time_temp(len(P))
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
