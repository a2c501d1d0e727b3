"""Names of the built-in generated models, as the command line spells them."""
import importlib

from .data import DataError

MODELS = {"two-axis": "generated.two_axis"}


def load(name):
    """The generated module of a built-in model."""
    if name not in MODELS:
        raise DataError(f"unknown model {name!r}; built-in models: {', '.join(MODELS)}")
    return importlib.import_module(MODELS[name])
