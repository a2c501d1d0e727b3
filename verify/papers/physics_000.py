"""The two-axis stand of 000 written directly from the paper in numpy, for cross-checks.

Nothing here comes from derive/ or generated/: the elementary passive rotations C1, C2, C3 of
section 2, the chain of the stand (1) and the block turned by a mounting Q (section 7), so a check
that simulates here and estimates with the generated module compares two independent routes.
"""
import numpy as np

STAND = ("kappa", "epsilon", "Delta_alpha", "Delta_beta", "alpha_star", "Delta_g")


def C(axis, x):
    """Passive rotation by x about coordinate axis 1, 2 or 3 (C1, C2, C3 of 000)."""
    c, s = np.cos(x), np.sin(x)
    return {1: np.array([[1, 0, 0], [0, c, s], [0, -s, c]]),
            2: np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]]),
            3: np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])}[axis]


def up_table(alpha, beta, s=None):
    """The up-vector in table axes, (1) of 000: C3(b - dbeta) C2(eps) C1(a - dalpha) C1(-a*) C2(kappa) e3."""
    s = s or dict.fromkeys(STAND, 0.0)
    return (C(3, beta - s["Delta_beta"]) @ C(2, s["epsilon"]) @ C(1, alpha - s["Delta_alpha"])
            @ C(1, -s["alpha_star"]) @ C(2, s["kappa"]) @ np.array([0.0, 0.0, 1.0]))


def readings_over_g(alpha, beta, stand, Q, Gamma, bias, theta_k):
    """f/g of a block mounted by Q with its errors in block axes: (E + Gamma)(1 - Delta_g) R(theta_k) Q u
    + bias, R(theta) = C3(theta3) C2(theta2) C1(theta1) the exact small turn of E + hat(theta)."""
    R = C(3, theta_k[2]) @ C(2, theta_k[1]) @ C(1, theta_k[0])
    return ((np.eye(3) + Gamma) * (1 - stand["Delta_g"])) @ R @ Q @ up_table(alpha, beta, stand) + bias


def residual_table_axes(alpha, beta, f_over_g, Q):
    """z of (1) turned to table axes by Q^-1 ((26) of 000)."""
    return Q.T @ (f_over_g - Q @ up_table(alpha, beta))
