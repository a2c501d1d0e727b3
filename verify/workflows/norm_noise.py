"""The noise rule of a norm calibration (calibrate-norm): the bound of each still interval's mean from the data
themselves, stated as statistical, and the noise premise as every printed bound states it."""
import numpy as np

from ..io.recordings import BATCHES

#: The noise rule's multiple of the standard error of an interval's mean: with BATCHES = 8 batch means,
#: the two-sided 99.73 % point of Student's t with 7 degrees of freedom (tests/workflows/test_calibrate_norm.py
#: computes it); with white-noise standard errors only (a means file: no samples), 3.
K_BATCH = 4.53
K_SE = 3.0


def noise_rule(stills, M, n, g, quantum=0.0):
    """The bound of |delta_sigma| from the data themselves, per still interval (units of g): K_BATCH
    batch-means standard errors of its mean (K_SE white-noise ones where no samples were read) plus
    half the quantisation step (raw units), carried through the calibration to the sensed direction n:
    |n^T M (k se + quantum/2)| / g, component-wise bounded. A stated statistical rule (99.73 % per
    interval and axis when the batch means are independent and normal), not the fit's own residual."""
    rows = np.abs(n.T @ M)                                    # (K, 3)
    return (rows * noise_axes(stills, quantum)).sum(axis=1) / g


def noise_axes(stills, quantum=0.0):
    """The noise rule's bound of each axis of each interval's raw mean (K, 3), raw units."""
    return np.array([(K_BATCH * st.batch_error if st.batch_error is not None else K_SE * st.std_error)
                     + quantum / 2 for st in stills])


def noise_rule_name(stills, quantum=0.0):
    """What the noise rule is, in words, as printed beside every bound that rests on it."""
    if all(st.batch_error is not None for st in stills):
        text = (f"noise rule (statistical, 99.73 %, not guaranteed: {K_BATCH:g} standard errors of each interval's "
                f"mean from {BATCHES} batch means, which allows correlated noise")
    else:
        text = (f"noise rule (statistical, not guaranteed: {K_SE:g} standard errors of each interval's mean, white "
                "noise assumed: the means file has no samples")
    return text + (f", plus half a count ({quantum:g} raw units)" if quantum else "") + \
        "; --delta-sigma states a guaranteed one)"


def premise(dsig, source, stated, si, g):
    """The noise premise as the bound uses it. A stated --delta-sigma on a log in m/s^2 bounds the raw mean's
    error in norm, carried through the calibration (|M^T n| D per interval: a unit with scale errors of -5e-2
    reads 5 % more noise once calibrated); the noise rule bounds each axis's raw error and is carried through M
    component by component; on a log in counts a stated bound is one of the calibrated reading."""
    if stated and si:
        return (f"each still interval's mean is within delta_sigma_max = {dsig:.3e} (units of g; {g * dsig:.3e} m/s^2, "
                f"Euclidean norm) of the truth in the raw readings ({source}), carried through M to each interval "
                "(|M^T n| delta_sigma_max)")
    if stated:
        return (f"each still interval's mean, as this fit calibrates it, is within delta_sigma_max = {dsig:.3e} (units "
                f"of g) of the truth along its direction ({source})")
    return (f"each axis of each still interval's raw mean is within its noise rule of the truth, carried through M "
            f"to the interval's direction (at most delta_sigma_max = {dsig:.3e}, units of g; {source})")
