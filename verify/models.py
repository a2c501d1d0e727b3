"""The models the command line knows: built-in generated modules, or a stand description file."""
import importlib
import types
from pathlib import Path

import numpy as np

from .errors import DataError

MODELS = {"two-axis": "garant.generated.two_axis", "single-axis": "garant.generated.single_axis",
          "three-axis": "garant.generated.three_axis", "norm": "garant.generated.norm"}
STANDS = ["two-axis", "single-axis", "three-axis"]       # models with stand angles (plan, estimate)


def load(name):
    """The generated module of a built-in model, or of a description file (derived in memory)."""
    if str(name).endswith(".toml"):
        return from_description(name)
    if name not in MODELS:
        raise DataError(f"unknown model {name!r}; built-in models: {', '.join(MODELS)}, or a STAND.toml")
    return importlib.import_module(MODELS[name])


def from_description(path):
    """Derive a stand description and execute the rendered module (no file is written)."""
    from garant.derive import codegen, description
    try:
        model = description.load(path)
        files = codegen.model_files(model)
    except description.DescriptionError as e:
        raise DataError(str(e)) from None
    key = f"generated/{model.stand.name}.py"
    mod = types.ModuleType(model.stand.name)
    mod.__file__ = str(Path(path).resolve())
    exec(compile(files[key], key, "exec"), mod.__dict__)
    return mod


def stand_model(name):
    """The symbolic Model (derive/) of a built-in stand or of a description file."""
    from garant.derive import description
    from garant.derive.builtin import MODELS as BUILTIN
    if str(name).endswith(".toml"):
        try:
            return description.load(name)
        except description.DescriptionError as e:
            raise DataError(str(e)) from None
    key = name.replace("-", "_")
    if key not in BUILTIN:
        raise DataError(f"unknown stand {name!r}; use {', '.join(STANDS)} or a STAND.toml")
    return BUILTIN[key]


def symbolic_H(mod):
    """The symbolic H (rows: 3 per mounting) and the angle symbols of a stand module, re-derived from
    its description (built-in or the TOML file it was loaded from)."""
    from garant.derive.derivation import derive
    source = getattr(mod, "__file__", "") or ""
    name = source if source.endswith(".toml") else mod.__name__.rsplit(".", 1)[-1].replace("_", "-")
    d = derive(stand_model(name))
    return d.ident.H, d.model.angle_symbols


def load_remount(name):
    """The generated remount module (25)-(29) of a built-in model, or None."""
    load(name)
    try:
        return importlib.import_module(MODELS[name] + "_remount")
    except (KeyError, ModuleNotFoundError):
        return None


def reachable_grid(ranges, detents, step):
    """Positions (degrees, (S, n)) a stand can take on a grid: each angle at its detents when it has
    them, else at the multiples of `step` (one per angle, or one for all) inside its range."""
    steps = list(step) if np.ndim(step) else [step] * len(ranges)
    values = []
    for (lo, hi), det, st in zip(ranges, detents, steps):
        values.append(np.asarray(det, float) if len(det) else
                      np.arange(np.ceil(lo / st) * st, min(hi, lo + 360 - 1e-9) + 1e-9, st))
    return np.array(np.meshgrid(*values, indexing="ij")).reshape(len(values), -1).T


def unreachable(ranges, detents, P):
    """The first (position index, angle index, value) a stand cannot take, or None."""
    P = np.atleast_2d(np.asarray(P, float))
    for i, ((lo, hi), det) in enumerate(zip(ranges, detents)):
        v = P[:, i]
        if len(det):
            bad = ~np.isclose(((v[:, None] - np.asarray(det, float)[None]) + 180) % 360 - 180, 0, atol=1e-6).any(axis=1)
        else:
            w = lo + (v - lo) % 360
            bad = (w > hi + 1e-9) & ~np.isclose(v, hi)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            return k, i, float(v[k])
    return None


def layout(mod):
    """Angle names and mounting names of a stand module (one mounting: ('+x+y+z',))."""
    return list(mod.ANGLES), list(getattr(mod, "MOUNTINGS", ("+x+y+z",)))


def H_at(mod, angles_rad, mounts=None):
    """H at positions: angles (S, n_angles) in radians, mounts (S,) indices -> (3, m, S)."""
    angles_rad = np.atleast_2d(np.asarray(angles_rad, float))
    cols = [angles_rad[:, i] for i in range(angles_rad.shape[1])]
    if hasattr(mod, "MOUNTINGS"):
        return mod.H(*cols, mount=np.zeros(len(angles_rad), int) if mounts is None else np.asarray(mounts))
    return mod.H(*cols)
