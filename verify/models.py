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


def load_remount(name):
    """The generated remount module (25)-(29) of a built-in model, or None."""
    load(name)
    try:
        return importlib.import_module(MODELS[name] + "_remount")
    except (KeyError, ModuleNotFoundError):
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
