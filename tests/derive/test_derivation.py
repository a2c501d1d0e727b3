"""The derivation reproduces (3) and (4) of 000, and generated code agrees with the symbols."""
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

from garant.derive import published
from garant.derive.derivation import derive
from garant.derive.rotations import C, small_turn
from garant.derive.builtin import TWO_AXIS_MODEL

a, b = sp.symbols("alpha beta", real=True)


@pytest.fixture(scope="module")
def d():
    return derive(TWO_AXIS_MODEL)


def parse(text):
    return sp.sympify(text, locals={"alpha": a, "beta": b})


def test_H_equals_published_3_with_the_lost_zero(d):
    # (3) of 000; the printed H^(3) has 14 entries: one zero of positions 3..11 is lost in the transcription.
    h3 = list(published.H_000[2])
    h3.insert(3, "0")
    printed = [published.H_000[0], published.H_000[1], h3]
    for p in range(3):
        for nu in range(15):
            assert sp.simplify(d.ident.H[p, nu] - parse(printed[p][nu])) == 0, (p + 1, nu + 1)


def test_q_equals_published_4(d):
    # (4) of 000: the 15 identifiable combinations, found from 21 physical parameters.
    syms = {p.name: p.symbol for p in TWO_AXIS_MODEL.parameters}
    assert d.ident.R.rows == 15
    for nu, text in enumerate(published.Q_000):
        q = sum(c * p.symbol for c, p in zip(d.ident.R.row(nu), TWO_AXIS_MODEL.parameters))
        assert sp.expand(q - sp.sympify(text, locals=syms)) == 0, nu + 1


def test_unseparable_directions(d):
    # Gamma11, Gamma22, Gamma33 move with Delta_g/g; Delta_alpha with alpha_star (q2 of (4)).
    assert set(d.ident.free) == {"alpha_star", "Delta_beta", "theta1", "theta2", "theta3", "Delta_g"}
    for v in d.ident.null_space:
        assert d.ident.R * v == sp.zeros(15, 1)


def test_linearisation_is_first_order_of_exact_residual(d):
    # z = H^T q + O(|p|^2): check the symbolic Jacobian against finite differences of (1).
    syms = [p.symbol for p in TWO_AXIS_MODEL.parameters]
    rng = np.random.default_rng(1)
    f = sp.lambdify([a, b, *syms], list(d.force_over_g[0] - d.up_nominal[0]), "numpy")
    for _ in range(5):
        al, be = rng.uniform(0, 2 * np.pi, 2)
        p = rng.normal(size=len(syms)) * 1e-4
        z = np.array(f(al, be, *p))
        q = np.array(d.ident.R, dtype=float) @ p
        Hn = np.array(d.ident.H.subs({a: al, b: be}), dtype=float)
        assert np.abs(z - Hn @ q).max() < 50 * np.abs(p).max() ** 2


def test_generated_H_agrees_with_symbolic_at_random_angles(d, mod):
    Hf = sp.lambdify([a, b], d.ident.H, "numpy")
    rng = np.random.default_rng(2)
    for al, be in rng.uniform(-7, 7, (20, 2)):
        np.testing.assert_allclose(mod.H(al, be), np.array(Hf(al, be), float), atol=1e-14)


def test_generated_readings_agree_with_symbolic(d, mod):
    syms = [p.symbol for p in TWO_AXIS_MODEL.parameters]
    f = sp.lambdify([a, b, *syms], list(d.force_over_g[0]), "numpy")
    rng = np.random.default_rng(3)
    for _ in range(10):
        al, be = rng.uniform(0, 2 * np.pi, 2)
        p = rng.normal(size=len(syms)) * 1e-2
        np.testing.assert_allclose(mod.readings(al, be, p, 9.8), 9.8 * np.array(f(al, be, *p), float),
                                   rtol=1e-13, atol=1e-13)


def test_H_broadcasts(mod):
    al = np.linspace(0, 6, 7)
    assert mod.H(al, al[:, None]).shape == (3, 15, 7, 7)
    assert mod.H(0.1, 0.2).shape == (3, 15)


@settings(max_examples=50, deadline=None)
@given(st.integers(1, 3), st.floats(-10, 10))
def test_rotations_are_orthonormal(axis, x):
    R = C(axis, sp.Float(x))
    assert np.allclose(np.array(R * R.T, float), np.eye(3))
    assert abs(float(R.det()) - 1) < 1e-12


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-0.1, 0.1), min_size=3, max_size=3))
def test_small_turn_is_E_plus_hat_to_first_order(theta):
    from garant.derive.rotations import hat
    R = np.array(small_turn([sp.Float(t) for t in theta]), float)
    E_hat = np.eye(3) + np.array(hat(theta), float)
    assert np.abs(R - E_hat).max() <= 2 * max(abs(t) for t in theta) ** 2 + 1e-15


@pytest.mark.slow
def test_trig_degree_counts_links_and_effect_powers():
    # The readings are a trigonometric polynomial of degree (links driven by the angle) x (the power of
    # the specific force in the sensor effects); no polynomial with a harmonic encoder error or |w|.
    from garant.derive.effects import extend
    from garant.derive.model import trig_degrees
    assert trig_degrees(TWO_AXIS_MODEL) == (1, 1)
    quadratic = extend(TWO_AXIS_MODEL, ["scale_quadratic"])
    assert trig_degrees(quadratic) == (2, 2)
    for name in ("scale_asymmetry", "alpha_encoder_harmonic", "bias_drift"):
        assert trig_degrees(extend(TWO_AXIS_MODEL, [name])) is None
    # The degree is what interpolation needs: 2d + 1 nodes per angle reproduce the readings, d - 1 do not.
    from garant.derive.model import specific_force_over_g
    f = specific_force_over_g(quadratic)
    syms = [p.symbol for p in quadratic.parameters]
    a, b = quadratic.angle_symbols
    rng = np.random.default_rng(0)
    fn = sp.lambdify([a, b], f.subs(dict(zip(syms, rng.uniform(-0.05, 0.05, len(syms))))), "numpy")

    def interpolated(x, y, d):
        n = 2 * d + 1
        nodes = 2 * np.pi * np.arange(n) / n
        def w(t):
            return (1 + 2 * sum(np.cos(m * (t - nodes)) for m in range(1, d + 1))) / n
        return sum(w(x)[i] * w(y)[j] * np.array(fn(nodes[i], nodes[j]), float) for i in range(n) for j in range(n))
    x, y = 0.7, -2.1
    exact = np.array(fn(x, y), float)
    assert np.abs(interpolated(x, y, 2) - exact).max() < 1e-12
    assert np.abs(interpolated(x, y, 1) - exact).max() > 1e-4


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(-3, 3), st.integers(0, 4), st.integers(0, 5), st.integers(0, 3),
                          st.integers(0, 4), st.integers(0, 2)), min_size=1, max_size=6))
def test_trig_basis_is_the_groebner_remainder_modulo_sin2_plus_cos2(terms):
    # The canonical basis of identify ((4) of 000) is the unique remainder modulo s^2 + c^2 - 1 per angle;
    # trig_basis takes it by rewriting s^2 without sp.reduced: both must give the same exact polynomial.
    from garant.derive.combinations import trig_basis
    a, b, t = sp.symbols("a b t", real=True)
    expr = sum(sp.Rational(k, 3) * sp.cos(a)**i * sp.sin(a)**j * sp.cos(b)**m * sp.sin(b)**n * t**e
               for k, i, j, m, n, e in terms)
    ca, sa, cb, sb = sp.symbols("ca sa cb sb")
    poly = sp.expand(expr.xreplace({sp.cos(a): ca, sp.sin(a): sa, sp.cos(b): cb, sp.sin(b): sb}))
    _, rem = sp.reduced(poly, [sa**2 + ca**2 - 1, sb**2 + cb**2 - 1], sa, sb, ca, cb, t, order="lex")
    got = sum((c * m for m, c in trig_basis(expr, (a, b), (t,)).items()), sp.Integer(0))
    want = rem.xreplace({ca: sp.cos(a), sa: sp.sin(a), cb: sp.cos(b), sb: sp.sin(b)})
    assert sp.expand(got - want) == 0
    assert all(c.is_Rational for c in trig_basis(expr, (a, b), (t,)).values())


def _effect_jacobians(name):
    """SymPy's own Jacobian d phi_j / d w of each basis vector of the effect (derive/norm.py `effect_basis`), as
    functions of (n1, n2, n3, time_s, temp_c, temp_rate_c_s); the temperature written as 20 + (temp_c - 20) and
    expanded, so that a cubic in T is not evaluated in its cancelling expanded form."""
    from garant.derive import norm as dn
    T, rate = sp.Symbol("temp_c", real=True), sp.Symbol("temp_rate_c_s", real=True)
    tau = sp.Symbol("tau", real=True)
    names, basis = dn.effect_basis(name)
    out = []
    for phi in basis:
        J = sp.Matrix(phi).jacobian(sp.Matrix(dn.n_sym)).xreplace({T: tau + 20}).applyfunc(sp.expand)
        f = sp.lambdify((*dn.n_sym, sp.Symbol("time_s", real=True), tau, rate), J, "numpy")
        out.append(lambda n1, n2, n3, t, temp, r, f=f: f(n1, n2, n3, t, temp - 20, r))
    return out


def test_the_effect_terms_are_the_derived_basis_exactly():
    # generated/norm.py EFFECT_TERMS (data the generated runtime evaluates) summed back in SymPy with exact
    # coefficients equals derive/norm.py `effect_basis` of every effect: red when a term, a sign or an exponent is
    # dropped in rendering (a table without the cross-coupling's n1*n3 term differs by it).
    from garant.derive import norm as dn
    from garant.generated import norm as N
    absolute = [sp.Abs(v) for v in dn.n_sym]
    v = (sp.Symbol("time_s", real=True), sp.Symbol("temp_c", real=True) - sp.Rational(N.EFFECT_T0_C),
         sp.Symbol("temp_rate_c_s", real=True))
    for name, params in N.EFFECTS.items():
        names, basis = dn.effect_basis(name)
        assert tuple(names) == params
        got = [[sp.Integer(0)] * 3 for _ in params]
        for j, i, num, den, a, b, e in N.EFFECT_TERMS[name]:
            got[j][i] += sp.Rational(num, den) * sp.Mul(*(x**k for x, k in zip((*dn.n_sym, *absolute, *v),
                                                                                 (*a, *b, *e))))
        assert all(sp.expand(g - want) == 0 for row, wrow in zip(got, basis) for g, want in zip(row, wrow)), name


def test_the_effects_jacobian_bound_holds_over_the_unit_cube_and_is_reached_at_a_vertex():
    # generated/norm.py effect_jacobian_bound (the unit ball, _runtime.effect_slope with size 1) against SymPy's own
    # Jacobian at the 8 vertices of the cube [-1, 1]^3 (which holds the ball) and 50 points of the ball: never
    # below it, and equal to the largest at a vertex for the polynomial effects. Red when a term's bound drops its
    # exponent (2 w_i of the quadratic scale factor bounded by 1).
    import itertools

    from garant.generated import norm as N
    rng = np.random.default_rng(6)
    for name in N.EFFECTS:
        jac = _effect_jacobians(name)
        t, T, rate = rng.uniform(-50, 50), rng.uniform(-10, 60), rng.uniform(-0.1, 0.1)
        bound = N.effect_jacobian_bound(name, t, T, rate)
        vertices = [np.array(s, float) for s in itertools.product((-1, 1), repeat=3)]
        inside = [z / max(1.0, np.linalg.norm(z)) for z in rng.uniform(-1, 1, (50, 3))]
        for j, J in enumerate(jac):
            at = np.array([np.abs(np.array(J(*z, t, T, rate), float)) for z in vertices + inside])
            assert np.all(at <= bound[j] * (1 + 1e-12) + 1e-15), (name, j)
            if name != "scale_asymmetry":
                np.testing.assert_allclose(at[:8].max(axis=0), bound[j], rtol=1e-12, atol=1e-15)


@pytest.mark.slow
def test_the_effects_slope_bound_holds_over_its_box_and_is_reached_at_a_vertex():
    # generated/norm.py effect_slope_bound (_runtime.effect_slope with size |w| + r) against SymPy's own Jacobian of
    # each effect's basis, evaluated at the 8 vertices of the box |z - w| <= r and 50 points inside: never below
    # it; for the polynomial effects (a Jacobian linear in w) equal to the largest at a vertex, for |w_i| at most 1.
    # Red when a term of the expansion is dropped (the cross-coupling bound without r is exceeded at a vertex).
    import itertools

    from garant.generated import norm as N
    rng = np.random.default_rng(5)
    for name in N.EFFECTS:
        jac = _effect_jacobians(name)
        for _ in range(20):
            w = rng.normal(size=3)
            w /= np.linalg.norm(w)
            r, t, T, rate = rng.uniform(0, 0.05), rng.uniform(-50, 50), rng.uniform(-10, 60), rng.uniform(-0.1, 0.1)
            bound = N.effect_slope_bound(name, w[:, None], np.array([r]), np.array([t]), np.array([T]),
                                         np.array([rate]))[..., 0]
            vertices = [w + r * np.array(s) for s in itertools.product((-1, 1), repeat=3)]
            inside = [w + r * rng.uniform(-1, 1, 3) for _ in range(50)]
            for j, J in enumerate(jac):
                at = np.array([np.abs(np.array(J(*z, t, T, rate), float)) for z in vertices + inside])
                assert np.all(at <= bound[j] * (1 + 1e-12) + 1e-15), (name, j)
                if name != "scale_asymmetry":
                    np.testing.assert_allclose(at[:8].max(axis=0), bound[j], rtol=1e-12, atol=1e-15)
