"""Elementary passive rotations and the skew matrix of a small turn (section 2 and 7 of 000)."""
import sympy as sp


def C(axis, x):
    """Passive rotation by angle x about coordinate axis 1, 2 or 3 (C1, C2, C3 of section 2 of 000), or about an
    exact unit vector n: cos x E + (1 - cos x) n n^T - sin x [n x] (C1 when n = e1)."""
    c, s = sp.cos(x), sp.sin(x)
    if isinstance(axis, tuple):
        n = sp.Matrix(axis)
        cross = sp.Matrix([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
        return c * sp.eye(3) + (1 - c) * n * n.T - s * cross
    if axis == 1:
        return sp.Matrix([[1, 0, 0], [0, c, s], [0, -s, c]])
    if axis == 2:
        return sp.Matrix([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    if axis == 3:
        return sp.Matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    raise ValueError(f"rotation axis must be 1, 2 or 3, not {axis!r}")


def hat(theta):
    """Skew matrix of a small turn theta, the paper's form in section 7 of 000: E + hat(theta) ~ turn."""
    t1, t2, t3 = theta
    return sp.Matrix([[0, t3, -t2], [-t3, 0, t1], [t2, -t1, 0]])


def small_turn(theta):
    """Exact rotation C3(theta3) C2(theta2) C1(theta1); equals E + hat(theta) to first order."""
    t1, t2, t3 = theta
    return C(3, t3) * C(2, t2) * C(1, t1)
