"""The effect catalogue: named physical additions to a stand or sensor model.

Adding an effect re-derives the model through the same pipeline (new H columns, new combinations);
no column is ever written by hand. Sensor effects add a term to the readings as a function of the
true specific force w (block axes), the time t of the row and its temperature T; encoder effects add
a once-per-turn error to a read angle of the chain.
"""
from dataclasses import dataclass, replace

import sympy as sp

from .parameter import Parameter

TIME, TEMP = sp.Symbol("time_s", real=True), sp.Symbol("temp_c", real=True)
VARIABLE_DEFAULTS = {"time_s": 0.0, "temp_c": 20.0}     # s; degrees C (the reference 20 C)


@dataclass(frozen=True)
class Effect:
    """A catalogue effect: its physics in one line, its parameters, and how it enters the readings."""

    name: str
    physics: str                          # one line: what it is, as a formula
    params: tuple[Parameter, ...]
    term: object = None                   # sensor effects: (w_over_g 3-vector, symbols) -> 3-vector over g
    angle: str | None = None              # encoder effects: the read angle that gains the harmonic


def _p(name, latex, unit, meaning):
    return Parameter(name, latex, unit, meaning)


def _per_axis(prefix, latex, unit, meaning):
    return tuple(_p(f"{prefix}{i}", f"{latex}_{i}", unit, f"{meaning} of accelerometer {i}") for i in (1, 2, 3))


CROSS = ((1, 2), (1, 3), (2, 1), (2, 3), (3, 1), (3, 2))

CATALOGUE = {e.name: e for e in (
    Effect("scale_quadratic", "f_i += K2_i w_i^2 / g (second-order scale factor)",
           _per_axis("K2_", "K^{(2)}", "1", "quadratic scale factor"),
           term=lambda w, s: sp.Matrix([s[f"K2_{i + 1}"] * w[i] ** 2 for i in range(3)])),
    Effect("scale_asymmetry", "f_i += A_i |w_i| (scale factor differs for + and - inputs)",
           _per_axis("A_", "A", "1", "scale-factor asymmetry"),
           term=lambda w, s: sp.Matrix([s[f"A_{i + 1}"] * sp.Abs(w[i]) for i in range(3)])),
    Effect("cross_coupling", "f_i += sum_{j != i} C_ij w_i w_j / g (pendulosity; B(w)w of 001 is a case)",
           tuple(_p(f"C_{i}{j}", f"C_{{{i}{j}}}", "1", f"cross-coupling of accelerometer {i} with axis {j}")
                 for i, j in CROSS),
           term=lambda w, s: sp.Matrix([sum((s[f"C_{i + 1}{j}"] * w[i] * w[j - 1] for i2, j in CROSS
                                             if i2 == i + 1), sp.Integer(0)) for i in range(3)])),
    Effect("alpha_encoder_harmonic", "alpha_true = alpha - Delta_alpha - (a_s sin alpha + a_c cos alpha)",
           (_p("a_s", "a_s", "rad", "once-per-turn error of the outer encoder, sine"),
            _p("a_c", "a_c", "rad", "once-per-turn error of the outer encoder, cosine")), angle="alpha"),
    Effect("beta_encoder_harmonic", "beta_true = beta - Delta_beta - (b_s sin beta + b_c cos beta)",
           (_p("b_s", "b_s", "rad", "once-per-turn error of the inner encoder, sine"),
            _p("b_c", "b_c", "rad", "once-per-turn error of the inner encoder, cosine")), angle="beta"),
    Effect("bias_drift", "f_i += g D_i t (bias drifting linearly in time; t = column time_s, s)",
           _per_axis("D_", "D", "1/s", "bias drift over g"),
           term=lambda w, s: sp.Matrix([s[f"D_{i + 1}"] * TIME for i in range(3)])),
    Effect("bias_temperature", "f_i += g T_i (T - 20 C) (bias temperature coefficient; T = column temp_c)",
           _per_axis("T_", "T", "1/degC", "bias temperature coefficient over g"),
           term=lambda w, s: sp.Matrix([s[f"T_{i + 1}"] * (TEMP - 20) for i in range(3)])),
)}


def applicable(model):
    """Catalogue effects that make sense for the model (encoder effects need their angle)."""
    angles = {a.name for a in model.stand.angles}
    return [n for n, e in CATALOGUE.items() if e.angle is None or e.angle in angles]


def extend(model, names):
    """The model with the named effects added (a new Model; derivations are cached per model)."""
    model = replace(model, plan_deg=(), remount=False)
    for name in sorted(names, key=list(CATALOGUE).index):
        e = CATALOGUE[name]
        if e.angle is not None:
            chain = tuple(replace(ln, harmonic=tuple(p.name for p in e.params)) if ln.angle == e.angle else ln
                          for ln in model.stand.chain)
            stand = replace(model.stand, chain=chain, parameters=model.stand.parameters + e.params)
            model = replace(model, stand=stand)
        else:
            model = replace(model, effects=model.effects + (name,))
        model = replace(model, preferred=model.preferred + tuple(p.name for p in e.params),
                        source_file=f"{model.source_file} + effect {name}",
                        stand=replace(model.stand, name=f"{model.stand.name}_{name}",
                                      title=f"{model.stand.title} + {name}",
                                      source=f"extension of {model.stand.source} by {name}"))
    return model
