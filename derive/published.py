"""Published results of 000 (Golovan & Matasov 2020) as printed, for comparison. Plain data, no SymPy.

Expressions are strings in alpha, beta; estimator terms are (weight, component p = 1..3,
alpha in degrees, beta in degrees), as the paper writes z^(p)(alpha, beta).
"""

#: (3) of 000 as printed. The printed H^(3) has 14 entries: one zero of positions 3..11 is lost.
H_000 = (
    ("-cos(beta)", "-cos(alpha)*sin(beta)", "-cos(alpha)*cos(beta)", "cos(alpha)",
     "sin(alpha)*sin(beta)", "sin(alpha)*cos(beta)", "1", "0", "0", "0", "0", "0", "0", "0", "0"),
    ("sin(beta)", "-cos(alpha)*cos(beta)", "cos(alpha)*sin(beta)", "0", "0", "0", "0", "cos(alpha)",
     "sin(alpha)*sin(beta)", "sin(alpha)*cos(beta)", "1", "0", "0", "0", "0"),
    ("0", "sin(alpha)", "0", "0", "0", "0", "0", "0", "0", "0",
     "sin(alpha)*sin(beta)", "sin(alpha)*cos(beta)", "cos(alpha)", "1"),
)

#: (4) of 000: q_nu as printed, in the names of derive/stands/two_axis.toml.
Q_000 = (
    "kappa", "Delta_alpha + alpha_star", "epsilon", "Gamma13 - theta2", "Gamma11 - Delta_g",
    "Gamma12 - Delta_beta + theta3", "bias1", "Gamma23 + theta1", "Gamma21 + Delta_beta - theta3",
    "Gamma22 - Delta_g", "bias2", "Gamma31 + theta2", "Gamma32 - theta1", "Gamma33 - Delta_g", "bias3",
)

#: Closed-form optimal estimators of section 4.3 of 000 on the starred plan of Table 2.
ESTIMATORS_000 = {
    "q1": (("-1/4", 1, 0, 0), ("1/4", 1, 0, 180), ("1/4", 2, 180, 90), ("-1/4", 2, 180, 270)),
    "q2": (("1/4", 1, 180, 90), ("-1/4", 1, 180, 270), ("-1/4", 2, 0, 0), ("1/4", 2, 0, 180)),
    "q3": (("-1/4", 1, 0, 0), ("1/4", 1, 0, 180), ("-1/4", 2, 180, 90), ("1/4", 2, 180, 270)),
    "q4": (("1/4", 1, 0, 0), ("1/4", 1, 0, 180), ("-1/4", 1, 180, 90), ("-1/4", 1, 180, 270)),
    "q5": (("1/2", 1, 90, 90), ("-1/2", 1, 90, 270)),
    "q6": (("-1/2", 1, 90, 180), ("1/2", 1, 270, 180)),
    "q7": (("1/4", 1, 0, 0), ("1/4", 1, 0, 180), ("1/4", 1, 180, 90), ("1/4", 1, 180, 270)),
    "q8": (("1/4", 2, 0, 0), ("1/4", 2, 0, 180), ("-1/4", 2, 180, 90), ("-1/4", 2, 180, 270)),
    "q9": (("1/2", 2, 90, 90), ("-1/2", 2, 270, 90)),
    "q10": (("1/2", 2, 90, 0), ("-1/2", 2, 90, 180)),
    "q11": (("1/2", 2, 90, 0), ("1/2", 2, 90, 180)),
    "q12": (("1/2", 3, 90, 90), ("-1/2", 3, 90, 270)),
    "q13": (("1/2", 3, 90, 0), ("-1/2", 3, 90, 180)),
    "q14": (("1/2", 3, 0, 0), ("-1/2", 3, 180, 90)),
    "q15": (("1/2", 3, 0, 0), ("1/2", 3, 180, 90)),
}

#: The starred 10-position plan of Table 2 of 000, degrees (alpha, beta).
PLAN_000 = ((0, 0), (0, 180), (180, 90), (180, 270), (90, 90), (270, 90), (90, 270),
            (90, 180), (270, 180), (90, 0))

#: Table 1 of 000: the necessary position sets of the base parameters, degrees (alpha, beta).
TABLE1_000 = {
    "q3": (((0, 0), (0, 180), (180, 90), (180, 270)), ((0, 0), (0, 180), (180, 0), (180, 180)),
           ((0, 90), (0, 270), (180, 90), (180, 270)), ((180, 0), (180, 180), (0, 90), (0, 270))),
    "q12": (((90, 90), (90, 270)), ((270, 90), (270, 270))),
    "q13": (((90, 0), (90, 180)), ((270, 0), (270, 180))),
    "q6": (((90, 180), (270, 180)), ((90, 0), (270, 0))),
    "q9": (((90, 270), (270, 270)), ((90, 90), (270, 90))),
}

#: Table 2 of 000: groups of parameters and their alternative position sets (first one starred).
TABLE2_000 = (
    (("q1", "q2", "q3", "q4", "q7", "q8", "q14", "q15"), TABLE1_000["q3"]),
    (("q5", "q9", "q12"), (((90, 90), (270, 90), (90, 270)), ((90, 90), (270, 90), (270, 270)),
                           ((90, 90), (90, 270), (270, 270)), ((90, 270), (270, 270), (270, 90)))),
    (("q6", "q10", "q11", "q13"), (((90, 180), (270, 180), (90, 0)), ((90, 180), (270, 180), (270, 0)),
                                   ((90, 0), (270, 0), (90, 180)), ((90, 0), (270, 0), (270, 180)))),
)

#: Section 4.3 of 000: "at least 64" optimal 10-position plans; fewer than 10 cannot be optimal.
AT_LEAST_PLANS_000 = 64
MIN_POSITIONS_000 = 10

#: The table of 001 (section 4): optimal estimators of the 9 linear parameters on 18 directions.
#: Directions as exact strings (components), terms (weight, direction index 1..18).
DIRECTIONS_001 = (
    "1, 0, 0", "-1, 0, 0", "0, 1, 0", "0, -1, 0", "0, 0, 1", "0, 0, -1",
    "sqrt(2)/2, sqrt(2)/2, 0", "sqrt(2)/2, -sqrt(2)/2, 0", "-sqrt(2)/2, -sqrt(2)/2, 0", "-sqrt(2)/2, sqrt(2)/2, 0",
    "sqrt(2)/2, 0, sqrt(2)/2", "sqrt(2)/2, 0, -sqrt(2)/2", "-sqrt(2)/2, 0, -sqrt(2)/2", "-sqrt(2)/2, 0, sqrt(2)/2",
    "0, sqrt(2)/2, sqrt(2)/2", "0, -sqrt(2)/2, sqrt(2)/2", "0, -sqrt(2)/2, -sqrt(2)/2", "0, sqrt(2)/2, -sqrt(2)/2",
)
ESTIMATORS_001 = {
    "lambda1_star": (("1/2", 1), ("1/2", 2)), "eps1_over_g": (("1/2", 1), ("-1/2", 2)),
    "lambda2_star": (("1/2", 3), ("1/2", 4)), "eps2_over_g": (("1/2", 3), ("-1/2", 4)),
    "lambda3_star": (("1/2", 5), ("1/2", 6)), "eps3_over_g": (("1/2", 5), ("-1/2", 6)),
    "alpha": (("1/2", 7), ("-1/2", 8), ("1/2", 9), ("-1/2", 10)),
    "beta": (("1/2", 11), ("-1/2", 12), ("1/2", 13), ("-1/2", 14)),
    "gamma": (("1/2", 15), ("-1/2", 16), ("1/2", 17), ("-1/2", 18)),
}
#: Section 4 of 001: guaranteed errors in units of delta_sigma_max, in the order of q.
ERRORS_001 = (1, 1, 1, 2, 2, 2, 1, 1, 1, 4, 4, 4)
#: Sections 4 and 6 of 001: 18 tests for the 9 linear parameters; "42" optimal directions in all.
DIRECTIONS_COUNT_001 = {"linear": 18, "all": 42}
