"""Models as data: a stand is a chain of rotations with named small errors, a block its error model.

The residual (1) of 000 is built from the description alone, so a new stand type is a new
description, not a new derivation.
"""
from dataclasses import dataclass, field

import sympy as sp

from .effects import TEMP, THERMAL_PREFIX, TIME, effect
from .parameter import Parameter
from .remount import mountings
from .rotations import C, small_turn


@dataclass(frozen=True)
class Angle:
    """A stand angle as read from its encoder (the argument of H), and the values it can take:
    `range_deg` (continuous) or `detents_deg` (a finite set), in degrees."""

    name: str
    latex: str
    meaning: str
    range_deg: tuple[float, float] = (0.0, 360.0)
    detents_deg: tuple[float, ...] = ()
    speed_deg_s: float | None = None              # top speed and acceleration (plan --route), if stated
    acceleration_deg_s2: float | None = None

    @property
    def symbol(self):
        """The angle's real SymPy symbol."""
        return sp.Symbol(self.name, real=True)


@dataclass(frozen=True)
class Link:
    """One elementary rotation C_axis of the chain from the instrument frame to the base.

    With `angle` set, the link turns by the read angle less its encoder offset `error`
    (true = read - offset); without it, the link is a fixed small error `sign * error`.
    """

    axis: int | tuple                   # 1, 2, 3, or an exact unit vector (a tilted axis)
    angle: str | None = None
    error: str | None = None
    sign: int = 1
    harmonic: tuple[str, str] | None = None   # encoder error a_s sin(read) + a_c cos(read)
    fixed_deg: object = None            # a fixed turn by this exact angle in degrees (a wedge), plus `error`


@dataclass(frozen=True)
class Stand:
    """A stand: its read angles, its chain (instrument side first), and its error parameters.

    The up-vector of the base is e3; the mounting misalignment `theta` (three parameters) turns
    the instrument frame z relative to the table frame j; `gravity_error` is Delta_g/g.
    """

    name: str
    title: str
    angles: tuple[Angle, ...]
    chain: tuple[Link, ...]
    parameters: tuple[Parameter, ...]
    theta: tuple[str, str, str]
    gravity_error: str
    source: str
    settle_s: float | None = None                 # settling time at a position, s (plan --route)
    remount_s: float | None = None                # time to remount the block in another mounting, s


@dataclass(frozen=True)
class Block:
    """Accelerometer block error model: f = (E + Gamma) w + Delta_f0 ((1) of 000)."""

    parameters: tuple[Parameter, ...] = field(default_factory=lambda: tuple(_block_parameters()))


def _block_parameters():
    for i in range(1, 4):
        for j in range(1, 4):
            kind = "scale-factor error" if i == j else "misalignment"
            yield Parameter(f"Gamma{i}{j}", rf"\Gamma_{{{i}{j}}}", "1",
                            f"{kind} of accelerometer {i} towards axis {j}")
    for i in range(1, 4):
        yield Parameter(f"bias{i}", rf"\Delta f^0_{i}/g", "1", f"bias of accelerometer {i} over g")


@dataclass(frozen=True)
class Model:
    """A stand with a block on it, and the preferred order that names the combinations q."""

    stand: Stand
    block: Block
    preferred: tuple[str, ...]
    plan_deg: tuple[tuple[int, int], ...] = ()
    remount: bool = False          # derive (25)-(29): the block may be mounted by any turn Q
    mountings: tuple[str, ...] = ("+x+y+z",)   # exact turns Q the block is used in (v_block = Q v_table)
    source_file: str = ""          # the description file, for generated headers
    effects: tuple[str, ...] = ()  # sensor effects of the catalogue (derive/effects.py) added to the block

    @property
    def parameters(self):
        """Every physical parameter: the stand's, the block's and the effects' added."""
        return self.stand.parameters + self.block.parameters + tuple(
            p for name in self.effects for p in effect(name).params)

    @property
    def parameter_kinds(self):
        """The kind of each parameter, in the order of `parameters`: stand (the stand's own errors),
        mounting (the block on the stand, theta), gravity (Delta_g/g), block (Gamma), bias (enters the
        readings linearly), effect (a catalogue effect)."""
        st = self.stand
        kinds = ["mounting" if p.name in st.theta else "gravity" if p.name == st.gravity_error else "stand"
                 for p in st.parameters]
        kinds += ["bias" if p.name.startswith("bias") else "block" for p in self.block.parameters]
        return tuple(kinds) + tuple("bias" if p.name.startswith("bias") else "effect"       # a thermal bias: linear
                                    for name in self.effects for p in effect(name).params)

    @property
    def variables(self):
        """Row variables besides the angles that the model depends on (time, temperature)."""
        names = set()
        for name in self.effects:
            names |= {TIME, TEMP} & self._effect_term(name).free_symbols
        return tuple(v for v in (TIME, TEMP) if v in names)

    def _effect_term(self, name):
        w = sp.Matrix(sp.symbols("w1:4", real=True))
        return effect(name).term(w, self.symbols)

    @property
    def symbols(self):
        """{name: symbol} of every physical parameter."""
        return {p.name: p.symbol for p in self.parameters}

    @property
    def angle_symbols(self):
        """The symbols of the read angles, in the description's order."""
        return tuple(a.symbol for a in self.stand.angles)


def mount_matrices(model):
    """Q of each mounting of the model, by name ((25) of 000)."""
    table = mountings()
    return [table[name] for name in model.mountings]


def link_angle(link, symbols, angles):
    """The true turn of a link: sign * (read - offset - harmonic error), or sign * fixed error."""
    error = symbols[link.error] if link.error else 0
    if link.angle is None:
        fixed = sp.pi * link.fixed_deg / 180 if link.fixed_deg is not None else 0
        return link.sign * (fixed + error)
    read = angles[link.angle]
    wobble = 0
    if link.harmonic:
        a_s, a_c = (symbols[n] for n in link.harmonic)
        wobble = a_s * sp.sin(read) + a_c * sp.cos(read)
    return link.sign * (read - error - wobble)


def trig_degrees(model):
    """Degree of the readings as a trigonometric polynomial in each read angle, or None when they are not
    one. Each link the angle drives is C(axis, sign (read - offset)): entries of degree 1 in the read
    angle, so a chain of k such links gives degree k; a sensor effect polynomial of degree d in the
    specific force multiplies it by d; a harmonic encoder error (sin of sin) or |w| is no polynomial."""
    if any(link.harmonic for link in model.stand.chain) or model.variables:
        return None
    w = sp.symbols("w1:4", real=True)
    factor = 1
    for name in model.effects:
        term = effect(name).term(sp.Matrix(w), model.symbols)
        for e in term:
            try:
                factor = max(factor, sp.Poly(e, *w).total_degree())
            except sp.PolynomialError:
                return None
    return tuple(factor * sum(link.angle == a.name for link in model.stand.chain) for a in model.stand.angles)


def chain_factors(stand, symbols, angles):
    """The chain's link matrices, instrument side first (000, section 2); their product is table_from_base."""
    return [C(link.axis, link_angle(link, symbols, angles)) for link in stand.chain]


def _product(mats):
    """Product of the matrices, multiplied from the right (matrix-vector when the last is e3)."""
    R = mats[-1]
    for M in reversed(mats[:-1]):
        R = M * R
    return R


def table_from_base(stand, symbols, angles, *, nominal=False):
    """Matrix taking base axes to instrument axes: the product of the chain's links."""
    factors = chain_factors(stand, symbols, angles)
    if nominal:                      # the errors set to 0 in each factor before the product, not after
        zero = {s: sp.Integer(0) for s in symbols.values()}
        factors = [f.xreplace(zero) for f in factors]
    return _product(factors)


def up_nominal(model, Q=None):
    """Nominal up-vector u in block axes: ideal stand, read angles, block mounted by Q."""
    angles = {a.name: a.symbol for a in model.stand.angles}
    u = table_from_base(model.stand, model.symbols, angles, nominal=True) * sp.Matrix([0, 0, 1])
    return u if Q is None or Q == sp.eye(3) else Q * u


def _force_factors(model, Q=None):
    """Factors whose product is the readings over g less the biases: (E + Gamma), (1 - dg), Q, turn,
    links, e3."""
    s = model.symbols
    angles = {a.name: a.symbol for a in model.stand.angles}
    EG, _ = block_matrices(model)
    dg = s[model.stand.gravity_error]
    mount = [] if Q is None or Q == sp.eye(3) else [Q]
    return [EG, (1 - dg) * sp.eye(3), *mount, small_turn([s[n] for n in model.stand.theta]),
            *chain_factors(model.stand, s, angles), sp.Matrix([0, 0, 1])]


@dataclass(frozen=True)
class Turn:
    """A turn R about the axis n all mountings share, which the block and the mounting absorb exactly.

    With several mountings Q_k all turns about one axis n, R(n, a) Q_k = Q_k R(n, a), so a unit reads like
    the one with (E + Gamma) R^T for E + Gamma and R C(theta) for its mounting. The mounting's theta1 joins
    the instrument-side link's offset exactly (C1(theta1) C1(s (read - offset)) is one turn about axis 1),
    and the mounting folded with it, N = C3(theta3) C2(theta2) C1(theta1 - s offset), turned by the a with
    (R N)[3, 2] = 0 is C3(theta3') C2(theta2'): the unit with theta1 = offset = 0. `condition` holds
    (A0, A1, A2) of (R N)[3, 2] = A0 + A1 cos a + A2 sin a; `theta` the expressions of sin theta2',
    sin theta3' and cos theta3' (entries (3, 1), (1, 2), (2, 2) of R N), all in `c` = cos a, `s` = sin a."""

    axis: tuple             # n, an exact unit vector
    offset: str             # the link's offset parameter that takes theta1
    c: sp.Symbol
    s: sp.Symbol
    condition: tuple
    theta: tuple


def absorbed(model):
    """(names, Gamma', turn, drift') of the parameters the block absorbs exactly, else ((), None, None, {}).

    Without sensor effects the readings depend on Gamma and Delta_g only through (1 - Delta_g)(E + Gamma),
    and with one mounting Q also theta only through (1 - Delta_g)(E + Gamma) Q C(theta) = (E + Gamma') Q,
    Gamma' = (1 - Delta_g)(E + Gamma) Q C(theta) Q^T - E: a unit and the one with Gamma' and these at 0
    read the same at every position, so data tell only Gamma' (the q of (4) of 000 taken literally,
    Gamma13 - theta2, are known only to about |Gamma| |theta| whatever the plan). The instrument-side
    link's encoder offset (Delta_beta of the two-axis stand) is one more fixed turn beside the mounting,
    C_k(s (read - offset)) = C_k(-s offset) C_k(s read), and goes into Gamma' with it. With several mountings
    about one axis, theta1 and the first link's offset go instead (`Turn`): Gamma' = (1 - Delta_g)(E + Gamma)
    R^T - E, in `turn.c`, `turn.s`. Checked here, not assumed: the identities exactly, and the absorbed
    parameters nowhere else in the readings.

    The thermal effect (derive/effects.py `thermal`) adds sum_k tau^k Gamma_Tk to Gamma: the readings read
    (E + Gamma(T)) w, so the same turn goes into each Gamma_Tk, Gamma_Tk' = (1 - Delta_g) Gamma_Tk Q C Q^T
    (R^T with a turn): `drift'` maps each Gamma_ij_Tk to its entry of Gamma_Tk'. Any other effect: none."""
    st = model.stand
    none = (), None, None, {}
    if any(not e.startswith(THERMAL_PREFIX) for e in model.effects) or len(model.effects) > 1:
        return none
    s = model.symbols
    EG, _ = block_matrices(model)
    dg = s[st.gravity_error]
    degree = int(model.effects[0][len(THERMAL_PREFIX):].split("_t")[0]) if model.effects else 0
    drifts = [sp.Matrix(3, 3, lambda i, j: s[f"Gamma{i + 1}{j + 1}_T{k}"]) for k in range(1, degree + 1)]
    names, Gp, same, turn = (st.gravity_error,), (1 - dg) * EG - sp.eye(3), True, None
    links = st.chain
    if len(model.mountings) == 1:
        Q = mount_matrices(model)[0]
        turn_m = small_turn([s[n] for n in st.theta])
        gone_names = {*st.theta, st.gravity_error}
        first = links[0]
        angles = {a.name: a.symbol for a in st.angles}
        if first.angle is not None and first.error and not first.harmonic and first.fixed_deg is None:
            # the instrument-side link's offset is one more fixed turn beside the mounting:
            # C_k(s (read - offset)) = C_k(-s offset) C_k(s read), checked exactly below
            offset = C(first.axis, -first.sign * s[first.error])
            at_zero = C(first.axis, link_angle(first, s, angles).subs(s[first.error], 0))
            split = (offset * at_zero - C(first.axis, link_angle(first, s, angles))).applyfunc(
                lambda e: sp.expand(sp.expand_trig(e)))
            if split == sp.zeros(3, 3):
                turn_m, gone_names, links = turn_m * offset, gone_names | {first.error}, links[1:]
        names = tuple(p.name for p in model.parameters if p.name in gone_names)
        Gp = (1 - dg) * EG * Q * turn_m * Q.T - sp.eye(3)
        Dp = [(1 - dg) * D * Q * turn_m * Q.T for D in drifts]
        same = all(sp.expand(A * Q - (1 - dg) * B * Q * turn_m) == sp.zeros(3, 3)
                   for A, B in zip([sp.eye(3) + Gp, *Dp], [EG, *drifts]))
    else:
        turn = _turn(model)
        Dp = [(1 - dg) * D for D in drifts]                   # Delta_g alone, unless the turn goes too
        if turn is not None:
            names = tuple(p.name for p in model.parameters if p.name in (turn.offset, st.theta[0], st.gravity_error))
            R = _turn_matrix(turn.axis, turn.c, turn.s)
            Gp = (1 - dg) * EG * R.T - sp.eye(3)
            Dp = [(1 - dg) * D * R.T for D in drifts]
            links = st.chain[1:]
    angles = {a.name: a.symbol for a in st.angles}
    rest = set().union(*(C(ln.axis, link_angle(ln, s, angles)).free_symbols for ln in links))
    gone = {s[n] for n in names} | ({s[n] for n in st.theta} if turn is not None else set())
    if not same or rest & gone:
        return none
    drift = {f"Gamma{i + 1}{j + 1}_T{k + 1}": D[i, j] for k, D in enumerate(Dp) for i in range(3) for j in range(3)}
    return names, Gp, turn, drift


def _turn_matrix(axis, c, s):
    """R(n, a) of rotations.C about the axis n, written in c = cos a and s = sin a."""
    a = sp.Symbol("a", real=True)
    return C(tuple(axis), a).xreplace({sp.cos(a): c, sp.sin(a): s})


def _turn(model):
    """The Turn of a model with several mountings, or None: every mounting a turn about one axis n, and the
    instrument-side link a read turn about axis 1 with an offset (the checks, exact, are here)."""
    st, s = model.stand, model.symbols
    axes = []
    for Q in mount_matrices(model):
        if Q != sp.eye(3):
            fixed = (Q - sp.eye(3)).nullspace()
            if len(fixed) != 1:
                return None
            axes.append(fixed[0] / fixed[0].norm())
    link = st.chain[0]
    if not axes or link.axis != 1 or link.angle is None or not link.error:
        return None
    n = axes[0]
    if any(sp.simplify(v - n) != sp.zeros(3, 1) and sp.simplify(v + n) != sp.zeros(3, 1) for v in axes):
        return None
    c, sn = sp.Symbol("turn_c", real=True), sp.Symbol("turn_s", real=True)
    R = _turn_matrix(n, c, sn)
    if any(sp.expand(R * Q - Q * R) != sp.zeros(3, 3) for Q in mount_matrices(model)):
        return None
    theta = [s[x] for x in st.theta]
    angle = {a.name: a.symbol for a in st.angles}
    folded = small_turn([theta[0] - link.sign * s[link.error], theta[1], theta[2]])
    # C3 C2 C1(theta1) C1(link) = C3 C2 C1(theta1 - s offset) C1(link at offset 0): the C1 factors alone
    lhs = C(1, theta[0]) * C(1, link_angle(link, s, angle))
    rhs = C(1, theta[0] - link.sign * s[link.error]) * C(1, link_angle(link, s, angle).subs(s[link.error], 0))
    if (lhs - rhs).applyfunc(lambda e: sp.expand(sp.expand_trig(e))) != sp.zeros(3, 3):
        return None
    M = R * folded
    cond = sp.Poly(sp.expand(M[2, 1]), c, sn)
    if cond.total_degree() > 1:
        return None
    A = (cond.coeff_monomial(1), cond.coeff_monomial(c), cond.coeff_monomial(sn))
    return Turn(tuple(n), link.error, c, sn, A, (M[2, 0], M[0, 1], M[1, 1]))


def block_matrices(model):
    """(E + Gamma) and the biases over g, from the block parameters."""
    s = model.symbols
    Gamma = sp.Matrix(3, 3, lambda i, j: s[f"Gamma{i + 1}{j + 1}"])
    bias = sp.Matrix([s[f"bias{i}"] for i in range(1, 4)])
    return sp.eye(3) + Gamma, bias


def specific_force_over_g(model, Q=None):
    """Readings over model gravity g: (E + Gamma)(1 - Delta_g/g) Q u_true + Delta_f0/g ((1) of 000),
    plus the sensor effects of the catalogue as functions of the true specific force over g."""
    return _product(_force_factors(model, Q)) + block_matrices(model)[1] + _effects_over_g(model, Q)


def _effects_over_g(model, Q, nominal=False):
    """Sensor effects over g; with `nominal`, at the nominal specific force (enough at first order,
    since every effect term is an effect parameter times a function of w)."""
    out = sp.zeros(3, 1)
    if model.effects:
        w = up_nominal(model, Q) if nominal else _product(_force_factors(model, Q)[1:])
        for name in model.effects:
            out += effect(name).term(w, model.symbols)
    return out


def residual(model, Q=None):
    """Exact residual z of (1) of 000: measured over g minus the nominal up-vector (block axes)."""
    return specific_force_over_g(model, Q) - up_nominal(model, Q)


def jacobian(model):
    """First-order part of (1) for every mounting: dz/dp at p = 0, stacked, (3 x mountings) x n.

    By the product rule over the factors, each differentiated alone and the rest taken at p = 0,
    which is much faster than differentiating the expanded product.
    """
    return sp.Matrix.vstack(*[_jacobian(model, Q) for Q in mount_matrices(model)])


def _jacobian(model, Q):
    syms = [p.symbol for p in model.parameters]
    zero = {x: sp.Integer(0) for x in syms}          # xreplace: a plain symbol swap, rebuilt and evaluated
    factors = _force_factors(model, Q)
    at0 = [f.xreplace(zero) for f in factors]
    bias = block_matrices(model)[1] + _effects_over_g(model, Q, nominal=True)
    free = [f.free_symbols for f in factors]
    cols = []
    for x in syms:            # entrywise diff: Matrix.diff builds an ArrayDerivative first, 3x slower
        col = bias.applyfunc(lambda e: e.diff(x)).xreplace(zero)
        for i, f in enumerate(factors):
            if x not in free[i]:
                continue
            df = f.applyfunc(lambda e: e.diff(x))
            col += _product(at0[:i] + [df.xreplace(zero)] + at0[i + 1:])
        cols.append(col.applyfunc(sp.expand))
    return sp.Matrix.hstack(*cols)
