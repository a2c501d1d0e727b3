"""Still intervals of a static log (io/recordings.py reads it): the moving variance that finds them, each
interval's mean with its white-noise and batch-means standard errors, and the random walk of the longest."""
import numpy as np

from ..errors import DataError, opt
from ..io.recordings import BATCHES, Still, median


BLOCK = 1 << 20        # windows per block of the moving variance: memory stays near one block, not the log


def moving_variance(x, n):
    """Sum over the axes of the variance of each window of n samples: (N - n + 1,). Block by block:
    cumulative sums of the block's samples less its first one (small sums, so the variance does not
    cancel), each axis contiguous; any window's variance is then O(1)."""
    out = np.empty(len(x) - n + 1)
    for start in range(0, len(out), BLOCK):
        stop = min(start + BLOCK, len(out))
        seg = x[start:stop + n - 1]
        d = np.subtract(seg.T, seg[0][:, None], out=np.empty((3, len(seg))))
        c = np.zeros((3, len(seg) + 1))
        np.cumsum(d, axis=1, out=c[:, 1:])
        c2 = np.zeros(len(seg) + 1)
        np.cumsum(np.einsum("ij,ij->j", d, d), out=c2[1:])
        s1 = c[:, n:] - c[:, :-n]
        out[start:stop] = (c2[n:] - c2[:-n]) / n - np.einsum("ij,ij->j", s1, s1) / (n * n)
    return out


def _segment(x):
    """Mean, white-noise standard error and batch-means standard error of the mean of each axis of the
    samples x (k, 3), axis by axis. Batch means: the interval cut into BATCHES equal runs (the last
    k mod BATCHES samples left out of the batches only); their scatter / sqrt(BATCHES) is the standard
    error of the mean whatever the noise's correlation, as long as it is shorter than a run."""
    x = x.T.copy()
    k = x.shape[1]
    mean = x.mean(axis=1)
    d = x - mean[:, None]
    var = np.einsum("ij,ij->i", d, d) / (k - 1)
    n = k // BATCHES
    batch = None
    if n >= 2:
        b = x[:, :n * BATCHES].reshape(3, BATCHES, n).mean(axis=2)
        batch = b.std(axis=1, ddof=1) / np.sqrt(BATCHES)
    return mean, np.sqrt(var / k), batch


def still_intervals(log, window=1.0, init=5.0, k=10.0, min_still=2.0):
    """Still intervals: moving variance (window s) below k times that of the first `init` seconds.

    Returns (intervals, note): the note says how the threshold was set.
    """
    dt = log.dt or float(median(np.diff(log.t)))
    span = float(log.t[-1] - log.t[0])
    if window >= span / 4:
        raise DataError(f"{opt('window')} {window:g} s: the moving-variance window must be under a quarter of the "
                        f"log's "
                        f"{span:.4g} s")
    n = max(int(round(window / dt)), 5)
    var = moving_variance(log.raw, n)
    first = var[: max(int(init / dt) - n, 1)]
    base = float(median(first))
    note = f"threshold {k:g} x the moving variance of the first {init:g} s"
    h = 0.05 * (len(var) - 1)                     # the 5th percentile's place among the sorted values
    below = np.count_nonzero(var < base / 20)
    if below > np.floor(h) and (below > np.ceil(h) or np.quantile(var, 0.05) < base / 20):
        base, note = float(np.quantile(var, 0.05)), (f"the first {init:g} s are not still; threshold {k:g} x "
                                                     "the 5th percentile of the moving variance")
    still = np.concatenate([[False], var < k * base, [False]])
    edges = np.flatnonzero(np.diff(still.astype(np.int8)))
    out, last = [], len(log.t) - 1
    for i, j in zip(edges[::2], edges[1::2]):                  # runs [i, j) of still windows
        a, b = i + n // 2, j + n // 2                            # window centre indices
        if log.t[min(b, last)] - log.t[a] >= min_still:
            mean, std_error, batch = _segment(log.raw[a:b])
            out.append(Still(float(log.t[a]), float(log.t[min(b, last)]), mean, std_error, int(b - a), batch))
    return out, note


def still_of(log, a, b):
    """The still interval of the log's samples a to b (b excluded): its span, mean and standard errors."""
    mean, std_error, batch = _segment(log.raw[a:b])
    return Still(float(log.t[a]), float(log.t[b - 1]), mean, std_error, int(b - a), batch)


#: The shortest still interval a random walk is read from (s): an Allan deviation at a quarter of it.
RANDOM_WALK_SECONDS = 40.0


def random_walk(log, stills, M, b):
    """(accelerometer random walk in m/s^3/sqrt(Hz), or None, and why not): from the longest still interval
    of at least RANDOM_WALK_SECONDS, calibrated (a = M (raw - b)), the Allan variance at tau = a quarter of
    it less the white noise's (N^2 / tau, N from the samples), as K^2 = 3 (sigma^2 - N^2 / tau) / tau, the
    largest of the three axes. A statistical figure, not a bound; None when no interval is long enough or
    the white noise hides the walk there."""
    if not stills:
        return None, "no still interval"
    st = max(stills, key=lambda s: s.stop - s.start)
    span = st.stop - st.start
    if span < RANDOM_WALK_SECONDS:
        return None, f"the longest still interval is {span:.3g} s, under the {RANDOM_WALK_SECONDS:g} s it needs"
    rows = (log.t >= st.start) & (log.t <= st.stop)
    a = (np.asarray(M, float) @ (log.raw[rows] - np.asarray(b, float)).T).T
    dt = float(median(np.diff(log.t[rows])))
    n = len(a) // 4                                            # tau: a quarter of the interval, 4 clusters
    means = a[: 4 * n].reshape(4, n, 3).mean(axis=1)
    tau = n * dt
    allan = 0.5 * np.mean(np.diff(means, axis=0) ** 2, axis=0)
    white = np.var(np.diff(a, axis=0), axis=0) / 2 * dt / tau     # N^2 / tau, N^2 = var * dt
    excess = allan - white
    if np.all(excess <= 0):
        return None, f"the white noise hides it over the longest still interval ({span:.3g} s)"
    return float(np.sqrt(3 * excess.max() / tau)), ""
