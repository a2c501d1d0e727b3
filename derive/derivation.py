"""One derivation of a model: residual (1), Jacobian, combinations (4), H (3), plan estimators."""
from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from . import estimators, identify, model as model_mod


@dataclass(frozen=True)
class Derivation:
    model: model_mod.Model
    up_nominal: sp.Matrix        # u(alpha, beta), instrument axes
    force_over_g: sp.Matrix      # exact readings over g, (1) of 000
    J: sp.Matrix                 # dz/dp at p = 0
    ident: identify.Identification
    estimators: tuple            # per q_nu: {(position index, component): Rational}

    @property
    def angles(self):
        return self.model.angle_symbols

    @property
    def names(self):
        return tuple(p.name for p in self.model.parameters)


@lru_cache(maxsize=None)
def derive(model):
    """Run the whole symbolic pipeline for a model description (cached per model)."""
    J = model_mod.jacobian(model)
    names = [p.name for p in model.parameters]
    ident = identify.identify(J, names, model.preferred, model.angle_symbols)
    est = (estimators.optimal_estimators(ident.H, model.angle_symbols, model.plan_deg)
           if model.plan_deg else ())
    return Derivation(model=model, up_nominal=model_mod.up_nominal(model),
                      force_over_g=model_mod.specific_force_over_g(model), J=J, ident=ident,
                      estimators=tuple(est))
