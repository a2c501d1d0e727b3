"""Names of the built-in generated models, as the command line spells them."""
import importlib

from .data import DataError

MODELS = {"two-axis": "generated.two_axis", "norm": "generated.norm"}
STANDS = ["two-axis"]            # models with stand angles (plan, estimate)


def load(name):
    """The generated module of a built-in model."""
    if name not in MODELS:
        raise DataError(f"unknown model {name!r}; built-in models: {', '.join(MODELS)}")
    return importlib.import_module(MODELS[name])


def load_remount(name):
    """The generated remount module (25)-(29) of a built-in model."""
    load(name)
    return importlib.import_module(MODELS[name] + "_remount")
