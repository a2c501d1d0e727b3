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
    Effect("scale_temperature", "f_i += S_i (T - 20 C) w_i (scale-factor temperature coefficient; T = column temp_c)",
           _per_axis("S_", "S", "1/degC", "scale-factor temperature coefficient"),
           term=lambda w, s: sp.Matrix([s[f"S_{i + 1}"] * (TEMP - 20) * w[i] for i in range(3)])),
)}


def _degree(k):
    """The suffix of an effect's term of degree k in T: none for 1, _2, _3."""
    return "" if k == 1 else f"_{k}"


def _power(k, mark=""):
    """The suffix of a parameter's degree k: none for 1, 2 or 3 (with `mark`, ^2)."""
    return "" if k == 1 else f"{mark}{k}"


#: The rate of the logged temperature (C/s): a log's samples give it, no stand's positions file does.
TEMP_RATE = sp.Symbol("temp_rate_c_s", real=True)

#: Effects of a log's samples only (calibrate-norm --effect, --diagnose, --thermal-degree D): the temperature's rate,
#: and the terms of degree 2 and 3 in T of a warm-up's polynomials (a stand's chamber has the `thermal` effect).
LOG_EFFECTS = {e.name: e for e in (
    Effect("temperature_lag", "f_i += g L_i dT/dt (the bias lags the logged temperature: L_i = -tau d(bias_i/g)/dT, "
                              "tau the lag, s; dT/dt of column temp_c, C/s)",
           _per_axis("L_", "L", "s/degC", "bias lag behind the logged temperature, over g"),
           term=lambda w, s: sp.Matrix([s[f"L_{i + 1}"] * TEMP_RATE for i in range(3)])),
    *(Effect(f"bias_temperature_{k}", f"f_i += g T{k}_i (T - 20 C)^{k} (the bias's term of degree {k} in T; "
                                      "T = column temp_c)",
             _per_axis(f"T{k}_", f"T^{{({k})}}", f"1/degC^{k}", f"bias temperature coefficient of degree {k} over g"),
             term=lambda w, s, k=k: sp.Matrix([s[f"T{k}_{i + 1}"] * (TEMP - 20) ** k for i in range(3)]))
      for k in (2, 3)),
    *(Effect(f"scale_temperature_{k}", f"f_i += S{k}_i (T - 20 C)^{k} w_i (the scale factor's term of degree {k} "
                                       "in T; T = column temp_c)",
             _per_axis(f"S{k}_", f"S^{{({k})}}", f"1/degC^{k}", f"scale-factor temperature coefficient of degree {k}"),
             term=lambda w, s, k=k: sp.Matrix([s[f"S{k}_{i + 1}"] * (TEMP - 20) ** k * w[i] for i in range(3)]))
      for k in (2, 3)),
    *(Effect(f"misalignment_temperature{_degree(k)}",
             f"f_2 += X{_power(k)}_21 (T - 20 C)^{k} w_1, f_3 += (X{_power(k)}_31 w_1 + X{_power(k)}_32 w_2) "
             f"(T - 20 C)^{k} (the "
             f"misalignments' term of degree {k} in T; T = column temp_c)",
             tuple(_p(f"X{_power(k)}_{i}{j}", f"X^{{({k})}}_{{{i}{j}}}", "1/degC" + _power(k, "^"),
                      f"misalignment temperature coefficient of degree {k}, axis {i} towards {j}")
                   for i, j in ((2, 1), (3, 1), (3, 2))),
             term=lambda w, s, k=k: sp.Matrix([0, s[f"X{_power(k)}_21"] * w[0] * (TEMP - 20) ** k,
                                               (s[f"X{_power(k)}_31"] * w[0] + s[f"X{_power(k)}_32"] * w[1])
                                               * (TEMP - 20) ** k]))
      for k in (1, 2, 3)),
)}


BLOCK_PARAMETERS = tuple(f"Gamma{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)) + ("bias1", "bias2", "bias3")
THERMAL_PREFIX = "thermal_d"


def thermal_name(degree, t0):
    """The name of the thermal effect of `degree` about t0 (whole degrees C): thermal_d2_t20, thermal_d1_tm5."""
    if not (isinstance(degree, int) and 1 <= degree <= 3):
        raise ValueError(f"thermal degree {degree!r}: 1, 2 or 3")
    t0 = int(t0)
    return f"{THERMAL_PREFIX}{degree}_t{'m' if t0 < 0 else ''}{abs(t0)}"


def thermal(degree, t0):
    """Every block parameter p (Gamma_ij, bias_i) a polynomial in the temperature T (column temp_c, C):
    p(T) = p + sum_k p_Tk (T - t0)^k, k = 1..degree, added to the readings as Gamma_Tk w and bias_Tk are
    ((1) of 000 at first order; the block model, (E + Gamma) w + bias, at T = t0)."""
    tau = TEMP - t0
    params = tuple(_p(f"{name}_T{k}", rf"{name}_{{T{k}}}", f"1/degC^{k}" if k > 1 else "1/degC",
                      f"coefficient of (T - {t0} C)^{k} of {name}")
                   for k in range(1, degree + 1) for name in BLOCK_PARAMETERS)

    def term(w, s):
        return sp.Matrix([sum((tau ** k * (sum((s[f"Gamma{i}{j}_T{k}"] * w[j - 1] for j in (1, 2, 3)), sp.Integer(0))
                                           + s[f"bias{i}_T{k}"]) for k in range(1, degree + 1)), sp.Integer(0))
                          for i in (1, 2, 3)])
    return Effect(thermal_name(degree, t0), f"each Gamma_ij and bias_i + sum_k p_Tk (T - {t0} C)^k, k <= {degree}",
                  params, term=term)


def effect(name):
    """A catalogue effect by name, or the thermal effect its name describes (thermal_name)."""
    if name in CATALOGUE:
        return CATALOGUE[name]
    if name.startswith(THERMAL_PREFIX):
        degree, t0 = name[len(THERMAL_PREFIX):].split("_t")
        return thermal(int(degree), -int(t0[1:]) if t0.startswith("m") else int(t0))
    raise KeyError(name)


def applicable(model):
    """Catalogue effects that make sense for the model (encoder effects need their angle)."""
    angles = {a.name for a in model.stand.angles}
    return [n for n, e in CATALOGUE.items() if e.angle is None or e.angle in angles]


def extend(model, names):
    """The model with the named effects added (a new Model; derivations are cached per model)."""
    model = replace(model, plan_deg=(), remount=False)
    for name in sorted(names, key=lambda n: list(CATALOGUE).index(n) if n in CATALOGUE else len(CATALOGUE)):
        e = effect(name)
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
