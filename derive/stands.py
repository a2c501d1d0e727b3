"""Built-in stand descriptions. Each is data: angles, chain of links, named small errors."""
from .model import Angle, Block, Link, Model, Parameter, Stand
from .norm import NormModel

TWO_AXIS = Stand(
    name="two_axis",
    title="Precision two-axis stand (Golovan & Matasov 2020)",
    source="000, section 2",
    angles=(
        Angle("alpha", r"\alpha", "outer-frame angle as read, rad"),
        Angle("beta", r"\beta", "inner-frame angle as read, rad"),
    ),
    # Instrument side first: (E + hat theta) C3(b - dbeta) C2(eps) C1(a - dalpha) C1(-a*) C2(kappa) e3
    chain=(
        Link(axis=3, angle="beta", error="Delta_beta"),
        Link(axis=2, error="epsilon"),
        Link(axis=1, angle="alpha", error="Delta_alpha"),
        Link(axis=1, error="alpha_star", sign=-1),
        Link(axis=2, error="kappa"),
    ),
    parameters=(
        Parameter("kappa", r"\kappa", "rad", "tilt of the outer axis from the horizontal"),
        Parameter("epsilon", r"\epsilon", "rad", "non-orthogonality of outer and inner axes"),
        Parameter("Delta_alpha", r"\Delta\alpha", "rad", "outer encoder offset (read - true)"),
        Parameter("Delta_beta", r"\Delta\beta", "rad", "inner encoder offset (read - true)"),
        Parameter("alpha_star", r"\alpha^*", "rad",
                  "deviation of the inner axis from the vertical plane of the outer axis"),
        Parameter("theta1", r"\theta_1", "rad", "mounting misalignment of the block about j1"),
        Parameter("theta2", r"\theta_2", "rad", "mounting misalignment of the block about j2"),
        Parameter("theta3", r"\theta_3", "rad", "mounting misalignment of the block about j3"),
        Parameter("Delta_g", r"\Delta g/g", "1", "relative error of the model gravity g"),
    ),
    theta=("theta1", "theta2", "theta3"),
    gravity_error="Delta_g",
)

# The starred rows of Table 2 of 000, in degrees (alpha, beta).
OPTIMAL10 = ((0, 0), (0, 180), (180, 90), (180, 270), (90, 90), (270, 90), (90, 270),
             (90, 180), (270, 180), (90, 0))

TWO_AXIS_MODEL = Model(
    stand=TWO_AXIS,
    block=Block(),
    # The leading parameter of each q of (4) of 000, in the paper's order; the rest follow.
    preferred=("kappa", "Delta_alpha", "epsilon", "Gamma13", "Gamma11", "Gamma12", "bias1",
               "Gamma23", "Gamma21", "Gamma22", "bias2", "Gamma31", "Gamma32", "Gamma33", "bias3",
               "alpha_star", "Delta_beta", "theta1", "theta2", "theta3", "Delta_g"),
    plan_deg=OPTIMAL10,
    remount=True,
)

MODELS = {"two_axis": TWO_AXIS_MODEL}

# The coarse stand of 001; pendulosity axes (i, j, k) = (2, 3, 1).
NORM_MODELS = {"norm": NormModel(axes=(2, 3, 1))}
