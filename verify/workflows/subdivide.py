"""A premise box too wide to contract from, split until the readings refute its pieces (guarantee.py's first box).

The remainder of the linearisation grows with the square of the box it is proven over: under wide a-priori bounds
(a single-axis stand's turned mounting at --prior 1e-2 lies within 0.12 rad) it is a tenth of g per reading, the
estimator's errors exceed the box, and no a posteriori box starts. Each piece P of the box is taken on its own:
the model linearised at P's centre c, its remainder proven over P alone (about c: a quarter of the whole box's per
halving), and the set of P

    Q_P = {q in P : q = c + w - u, |y_k(c) - a_k(c)^T w| <= s_k + R_k(P), |u| <= shift(P)}

holds every q of P that fits the readings, as the whole box's set does (remainder.py, guarantee.InformationSet).
A piece is dropped when a proof says no q of it fits (the least tau with every row within (1 + tau) of its bound,
proven above 0 by weak duality: solve/hull.py), cut to the hull of Q_P when that shrinks it, and else halved along
its widest q; a piece whose remainder is within the noise bound, or not lowered by the two halvings it came from (the
parameters no plan separates set it then, not the q box), is kept as it is. The truth lies in one piece, in its set:
the hull of what is left holds every q that fits, whenever the premises hold. A budget of pieces (work, not time)
bounds the search; the pieces not taken up are kept whole.
"""
import dataclasses

import numpy as np

from ..solve import highs, hull, taylor
from .remainder import EPS, Remainder, _columns

#: Pieces examined at most: the single-axis stand on its 12 positions settles in 35 at --prior 1e-2, 152 at 1.5e-2.
PIECES = 256
#: Positions a piece is judged on at most, spread over all (a set over fewer readings holds the set over all, so a
#: piece refuted on them is refuted): the split's cost stops growing with the log.
POSITIONS = 64
#: Pieces between two progress lines.
SAY_EVERY = 32
#: A piece is cut to the hull of its set (and taken up again) when no q keeps more than this fraction of its width;
#: else it is halved.
CUT = 0.7
#: A piece is kept as it is when its remainder is above this fraction of that of the piece two halvings before it:
#: the q box does not set it (the parameters t no plan separates do, within their a-priori bounds), so halving gains
#: nothing. (One halving of five equally wide q lowers it by about a tenth: the single-axis stand at --prior 1.5e-2.)
SETTLED = 0.9


def proven_box(lin, z, noise, outer, at, progress=None):
    """The box of v = (q kept, t) that holds every q the readings allow within the premise box `outer` ((lo, hi) of
    every q, finite: the a-priori estimator's), or None when every piece is refuted (the premises are, then). `z`:
    the residuals; `noise`: each reading's bound (the noise bound less what repeats sharpen); `at`: the
    Linearisation moved to the centre q (guarantee.at: at(lin, q)); `progress(text)`, when given, hears of the
    split's start and of every SAY_EVERY pieces. The pieces are judged on at most POSITIONS positions."""
    say = progress or (lambda text: None)
    lin, z, noise = _spread(lin, z, noise)
    say(f"the a-priori box is too wide for the remainder to contract from: splitting it (at most {PIECES} pieces)")
    keep, nk = list(lin.keep), len(lin.keep)
    t = lin.t_bound
    q_lo, q_hi = (np.array(b, float) for b in outer)
    start = (np.r_[q_lo[keep], -t], np.r_[q_hi[keep], t])
    todo, left, pieces = [(*start, (np.inf, np.inf))], [], 0
    while todo and pieces < PIECES:
        lo, hi, before = todo.pop()                    # before: the remainders of the two pieces it was made from
        pieces += 1
        if pieces % SAY_EVERY == 0:
            say(f"piece {pieces}: {len(left)} kept, {len(todo)} to examine")
        got = _piece(lin, z, noise, q_lo, q_hi, lo, hi, lambda q: at(lin, q))
        if got is None:
            continue                                   # no q of this piece fits: refuted
        cut_lo, cut_hi, rb = got
        shrink = (cut_hi - cut_lo)[:nk] / np.maximum(hi - lo, 1e-300)[:nk]
        if rb <= noise.min() or rb > SETTLED * before[1]:
            left.append((cut_lo, cut_hi))              # within the noise, or two halvings did not lower it
        elif shrink.max() <= CUT:
            todo.append((cut_lo, cut_hi, (rb, before[0])))
        else:
            j = int(np.argmax((cut_hi - cut_lo)[:nk]))
            mid = 0.5 * (cut_lo[j] + cut_hi[j])
            a_hi, b_lo = cut_hi.copy(), cut_lo.copy()
            a_hi[j], b_lo[j] = mid, mid
            todo += [(b_lo, cut_hi, (rb, before[0])), (cut_lo, a_hi, (rb, before[0]))]
    left += [(lo, hi) for lo, hi, _ in todo]
    if not left:
        return None
    return np.min([b[0] for b in left], axis=0), np.max([b[1] for b in left], axis=0)


def _piece(lin, z, noise, q_lo, q_hi, lo, hi, at):
    """(lo, hi, the largest remainder of a reading) of the piece [lo, hi] cut to the hull of its set, or None when a
    proof refutes it."""
    keep, nk = list(lin.keep), len(lin.keep)
    ql, qh = q_lo.copy(), q_hi.copy()
    ql[keep], qh[keep] = lo[:nk], hi[:nk]
    qc = 0.5 * (ql + qh)
    local = at(qc)
    rem = Remainder(local, boxes=[(lo, hi)])
    rb, cb = rem(lo, hi)
    s = noise + rb + rem.t_residual
    shift = cb * (1 + taylor.SUM_ERROR) + np.abs(rem.G) @ lin.t_bound * (1 + taylor.SUM_ERROR)
    y = z - local.z0
    At = local.A.T
    w_lo, w_hi = ql - qc - shift, qh - qc + shift
    # the least tau with every row within s (1 + tau): w = 0 meets every row at tau = max |y| / s, so it is finite
    tau_max = float(np.max(np.abs(y) / s)) + 1.0
    B = np.vstack([np.hstack([At, s[:, None]]), np.hstack([At, -s[:, None]])])
    inf = np.full(len(y), np.inf)
    tau = np.zeros((1, At.shape[1] + 1))
    tau[0, -1] = 1.0
    try:
        tau_lo, _ = hull.ranges(B, np.r_[y - s, -inf], np.r_[inf, y + s], np.r_[w_lo, 0.0], np.r_[w_hi, tau_max],
                                tau)
    except hull.Empty:                                 # to HiGHS's tolerance only: no proof, the piece stays
        return lo, hi, float(rb.max())
    if tau_lo[0] > 0:
        return None
    try:
        w_min, w_max = hull.ranges(At, y - s, y + s, w_lo, w_hi, np.eye(At.shape[1]))
    except hull.Empty:
        return lo, hi, float(rb.max())
    pad = shift + taylor.SUM_ERROR * np.abs(qc) + 4 * EPS * (np.abs(w_min) + np.abs(w_max))
    cut_lo, cut_hi = lo.copy(), hi.copy()
    cut_lo[:nk] = np.maximum(lo[:nk], (qc + w_min - pad)[keep])
    cut_hi[:nk] = np.minimum(hi[:nk], (qc + w_max + pad)[keep])
    if np.any(cut_lo[:nk] > cut_hi[:nk]):
        return None                                    # its set's proven hull misses the piece
    return cut_lo, cut_hi, float(rb.max())


def _spread(lin, z, noise):
    """(lin, z, noise) on at most POSITIONS positions spread over all (highs.spread)."""
    n = len(lin.positions.f)
    if n <= POSITIONS:
        return lin, z, noise
    rows = highs.spread(n, POSITIONS)
    cols = _columns(rows)
    return (dataclasses.replace(lin, positions=lin.positions.at(rows), z0=lin.z0[cols], A=lin.A[:, cols],
                                Jt=lin.Jt[cols]), z[cols], noise[cols])
