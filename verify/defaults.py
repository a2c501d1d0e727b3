"""The defaults and names the command line states before any work: the gravity assumed, the plan search's
budgets, the log formats and OpenAXES sensors. Nothing numeric is imported here, so that `garant --help` and an
argument error answer before numpy loads (each module that computes imports its own)."""

#: The gravity assumed when none is given, m/s^2.
G_DEFAULT = 9.81

#: Every information set is also bounded for the noise bound (sigma, or each interval's) this much larger: the
#: figures `sigma_wider` print, how much the bounds lean on it.
SIGMA_WIDER = 1.1

#: Nodes of the branch and bound for the fewest positions (a mixed-integer program: solve/highs.py; the
#: built-in stands prove their minimum in a few), then nodes for counting the plans of that size (in all).
#: Budgeted by work, the result is the same on every machine; the time limits are a safety stop only.
SEARCH_NODES = 20_000
COUNT_NODES = 20

#: The most candidate positions (times mountings) a plan search takes unless told otherwise: a 3-degree
#: grid on the two-axis stand (14,400) takes about 30 s on one core.
MAX_CANDIDATES = 10_000

#: Safety stops only (s): the search for the fewest positions and the count of its plans are budgeted by
#: work (--search-nodes, --count-nodes: solve/highs.py), so that they give the same plan on every machine;
#: a time limit that fires instead is said, for its result may differ elsewhere.
SEARCH_SECONDS = 300.0
COUNT_SECONDS = 120.0

#: The most runs `repeatability` compares unless told otherwise: the effect test fits every run at once, so its
#: LP grows with the square of the runs (20 runs of 16 positions take 0.2 s, 200 runs 80 s).
MAX_RUNS = 50

#: The log formats calibrate-norm, apply and repeatability read (io/recordings.py READERS, in this order).
FORMATS = ("imu_tk", "csv", "openaxes", "mimu", "npy", "imucal", "ulog", "dataflash", "rosbag")
#: The effects calibrate-norm can add (generated/norm.py EFFECTS, in its order; named here so that --help needs no
#: numpy: tests/cli/test_cli.py fails when the two differ).
NORM_EFFECTS = ("scale_quadratic", "scale_asymmetry", "cross_coupling", "bias_drift", "bias_temperature",
                "scale_temperature", "temperature_lag", "bias_temperature_2", "bias_temperature_3",
                "scale_temperature_2", "scale_temperature_3", "misalignment_temperature", "misalignment_temperature_2",
                "misalignment_temperature_3")
#: The accelerometers of an OpenAXES log, by the prefix of their columns.
SENSORS = {"adxl355": "ACCEL_ADXL355_{}", "bmi160": "ACCEL_BMI160_{}"}
