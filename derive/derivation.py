"""One derivation of a model: residual (1), Jacobian, combinations (4), H (3), plan estimators."""
from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from . import combinations, estimators, model as model_mod
from .description import check_observable


@dataclass(frozen=True)
class Derivation:
    """One stand model derived: exact readings per mounting, the Jacobian, H, q and the estimators."""

    model: model_mod.Model
    up_nominal: tuple            # per mounting: u(angles) in block axes
    force_over_g: tuple          # per mounting: exact readings over g, (1) of 000
    J: sp.Matrix                 # dz/dp at p = 0
    ident: combinations.Identification
    estimators: tuple            # per q_nu: {(position index, component): Rational}

    @property
    def angles(self):
        """The symbols of the stand's read angles."""
        return self.model.angle_symbols

    @property
    def names(self):
        """The physical parameters' names, in the model's order."""
        return tuple(p.name for p in self.model.parameters)


@lru_cache(maxsize=None)
def derive(model):
    """Run the whole symbolic pipeline for a model description (cached per model)."""
    J = model_mod.jacobian(model)
    check_observable(model, J)
    names = [p.name for p in model.parameters]
    ident = combinations.identify(J, names, model.preferred, model.angle_symbols, model.variables)
    reach = reachable_positions(model, J)
    if reach is not None:                      # detents: what the stand can reach decides, if it sees less
        finite = combinations.identify(J, names, model.preferred, model.angle_symbols, positions=reach)
        if finite.R.rows < ident.R.rows:
            ident = finite
    est = (estimators.optimal_estimators(ident.H, model.angle_symbols, model.plan_deg)
           if model.plan_deg else ())
    Qs = model_mod.mount_matrices(model)
    return Derivation(model=model, up_nominal=tuple(model_mod.up_nominal(model, Q) for Q in Qs),
                      force_over_g=tuple(model_mod.specific_force_over_g(model, Q) for Q in Qs), J=J,
                      ident=ident, estimators=tuple(est))


def reachable_positions(model, J):
    """The positions at which the detents can hide a combination (exact angles of the angles with too
    few detents; the others stay free), or None when none can.

    An angle whose readings are trigonometric polynomials of degree d in it, with at least 2d + 1
    distinct detents, sees exactly what its whole circle sees: a nonzero trigonometric polynomial of
    degree d has at most 2d zeros in a turn, and on a product of such sets the evaluation of a product
    basis is one-to-one as each factor's is (Kronecker). Only the other angles need their detents."""
    from itertools import product
    angles = model.stand.angles
    if model.variables or not all(a.detents_deg for a in angles):
        return None
    few = [(s, a) for s, a in zip(model.angle_symbols, angles)
           if len(a.detents_deg) <= 2 * combinations.harmonic_degree(J, s, model.angle_symbols)]
    if not few:
        return None
    values = [[sp.pi * sp.Rational(str(d)) / 180 for d in a.detents_deg] for _, a in few]
    return [dict(zip([s for s, _ in few], combo)) for combo in product(*values)]


@lru_cache(maxsize=None)
def numeric_H(model):
    """H of a (possibly extended) model as a numpy function of (*angles, *variables): (3, m, ...)."""
    return _numeric_H(derive(model))


def _numeric_H(d):
    args = [*d.model.angle_symbols, *d.model.variables]
    rows, cols = d.ident.H.shape
    f = sp.lambdify(args, list(d.ident.H), "numpy")

    def H(*values):
        import numpy as np
        values = np.broadcast_arrays(*[np.asarray(v, float) for v in values])
        out = [np.broadcast_to(np.asarray(v, float), values[0].shape) for v in f(*values)]
        return np.array(out).reshape((rows, cols) + values[0].shape)
    return H
