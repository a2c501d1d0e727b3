"""The straightforward alternatives the bench measures garant against (python -m verify.bench).

Written as a user would write them with numpy and HiGHS alone, and kept light: numpy is the only
import at the top, so a baseline run in its own process pays no more start-up than such a script.
"""
import numpy as np


def per_target_lp(A):
    """The straightforward LP: the primal (7)-(8) for each e_nu as its own problem, the whole matrix
    handed to a fresh HiGHS each time (what calling scipy.optimize.linprog per target does).
    Returns (Phi (K x m), sum |Phi| (m,))."""
    import highspy
    A = np.asarray(A, float)
    m, K = A.shape
    Phi = np.zeros((K, m))
    for nu in range(m):
        lp_ = highspy.HighsLp()
        lp_.num_col_, lp_.num_row_ = 2 * K, m
        lp_.col_cost_, lp_.col_lower_ = np.ones(2 * K), np.zeros(2 * K)
        lp_.col_upper_ = np.full(2 * K, highspy.kHighsInf)
        lp_.row_lower_ = lp_.row_upper_ = np.eye(m)[nu]
        lp_.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp_.a_matrix_.start_ = np.arange(0, 2 * K * m + 1, m, dtype=np.int32)
        lp_.a_matrix_.index_ = np.tile(np.arange(m, dtype=np.int32), 2 * K)
        lp_.a_matrix_.value_ = np.r_[A.T.ravel(), -A.T.ravel()]
        h = highspy.Highs()
        h.setOptionValue("output_flag", False)
        h.passModel(lp_)
        h.run()
        x = np.array(h.getSolution().col_value)
        Phi[:, nu] = x[:K] - x[K:]
    return Phi, np.abs(Phi).sum(axis=0)


def per_target_estimate(path, sigma=1e-5, g=9.81):
    """The baseline of `garant estimate` on a positions file, run as its own process: read the file with
    numpy, H from the generated module, the per-target LPs, print each q with sigma sum |Phi|."""
    from garant.generated import two_axis as mod
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    angles = np.deg2rad(data[:, :2]).T
    z = (data[:, 2:5] / g - mod.up_nominal(*angles).T).reshape(-1)
    A = np.transpose(mod.H(*angles), (1, 2, 0)).reshape(len(mod.Q_NAMES), -1)
    Phi, err = per_target_lp(A)
    for name, q, e in zip(mod.Q_NAMES, Phi.T @ z, err):
        print(f"{name} {q:+.6e} +- {sigma * e:.3e}")
