"""garant: guaranteed (minimax) calibration of accelerometer blocks on test stands.

    garant.derive     SymPy: stand descriptions -> residual (1), H (3), combinations q (4), remount, norm (2.2)
    garant.generated  numpy only: the rendered estimator modules
    garant.verify     numpy, cvxpy: LPs, proofs, workflows on data, the checks against the papers

The names below are the notebook API (docs/api.md); each is imported on first use, so
`import garant` is light.
"""
from importlib import import_module as _import_module

__version__ = "0.1.0"

_API = {
    "plan": ("garant.verify.api", "plan"),
    "estimate": ("garant.verify.api", "estimate"),
    "calibrate_norm": ("garant.verify.api", "calibrate_norm"),
    "calibrate_many": ("garant.verify.api", "calibrate_many"),
    "diagnose": ("garant.verify.api", "diagnose"),
    "next_position": ("garant.verify.api", "next_position"),
    "apply": ("garant.verify.api", "apply"),
    "budget": ("garant.verify.api", "budget"),
    "load_model": ("garant.verify.models", "load"),
    "DataError": ("garant.verify.errors", "DataError"),
}
__all__ = list(_API)


def __dir__():
    """The API beside the module's own names: what `dir(garant)` and tab completion show."""
    return sorted(set(globals()) | set(_API))


def __getattr__(name):
    if name not in _API:
        raise AttributeError(f"module 'garant' has no attribute {name!r}")
    module, attr = _API[name]
    return getattr(_import_module(module), attr)
