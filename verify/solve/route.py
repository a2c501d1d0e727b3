"""The order in which a stand visits a plan's positions: the shortest total stand time (moves with a
trapezoidal speed profile per angle, all angles at once, then settling; a remount where the mounting
changes), or without stated speeds the smallest largest angle of any move. Exact (Held-Karp dynamic
programming over subsets) up to EXACT_UP_TO positions; above, nearest neighbour from every start then
2-opt, with a lower bound (the minimum spanning tree: every route is a spanning path) to state the gap."""
from dataclasses import dataclass

import numpy as np

#: The most positions ordered exactly (2^12 x 12^2 steps: well under a second).
EXACT_UP_TO = 12


@dataclass(frozen=True)
class Motion:
    """What the stand states of its motion: per angle top speed (deg/s) and acceleration (deg/s^2),
    None where not stated; the settling time at a position and the remount time (s)."""

    speed: tuple
    acceleration: tuple
    settle: float = 0.0
    remount: float = 0.0

    @property
    def timed(self):
        """Whether every angle states its speed: the route then minimises time."""
        return all(v is not None for v in self.speed)


def travel(P, ranges):
    """Angle travelled by each angle between every two positions (S, S, n), degrees: the short way round
    on an angle that turns fully, straight within a limited range (no wrap)."""
    P = np.asarray(P, float)
    d = np.abs(P[:, None, :] - P[None, :, :])
    full = np.array([hi - lo >= 360 for lo, hi in ranges])
    return np.where(full, np.minimum(d % 360, 360 - d % 360), d)


def move_time(d, speed, acceleration):
    """Time (s) to turn d degrees from rest to rest with top speed v and acceleration a (trapezoid, or a
    triangle when the top speed is not reached); no acceleration stated: the top speed at once."""
    d = np.asarray(d, float)
    if acceleration is None:
        return d / speed
    reach = speed ** 2 / acceleration                   # the distance accelerating to v and back takes
    return np.where(d >= reach, d / speed + speed / acceleration, 2 * np.sqrt(d / acceleration))


def costs(P, mounts, ranges, motion):
    """The cost of each move (S, S): its time in s (the slowest angle, then settling, plus a remount where
    the mounting changes) when the stand states its speeds, else the largest angle it turns (degrees)."""
    D = travel(P, ranges)
    change = np.asarray(mounts)[:, None] != np.asarray(mounts)[None, :]
    if not motion.timed:
        return D.max(axis=2)
    T = np.max([move_time(D[:, :, i], v, a) for i, (v, a) in enumerate(zip(motion.speed, motion.acceleration))],
               axis=0)
    C = T + motion.settle + np.where(change, motion.remount, 0.0)
    np.fill_diagonal(C, 0.0)
    return C


def _value(C, order, bottleneck):
    steps = C[order[:-1], order[1:]]
    return (float(steps.max()) if len(steps) else 0.0, float(steps.sum())) if bottleneck else float(steps.sum())


def held_karp(C, bottleneck=False):
    """The exact best open route through every position (any start): least total cost, or with
    `bottleneck` least largest step, then least total. Returns the order (list of indices)."""
    n = len(C)
    if n <= 1:
        return list(range(n))
    full = 1 << n
    best = np.full((full, n), np.inf) if not bottleneck else np.full((full, n, 2), np.inf)
    parent = np.full((full, n), -1, int)
    for v in range(n):
        best[1 << v, v] = 0.0
    for mask in range(1, full):
        for v in range(n):
            if not (mask >> v) & 1 or parent[mask, v] == -1 and mask != 1 << v:
                continue
            here = best[mask, v]
            for w in range(n):
                if (mask >> w) & 1:
                    continue
                nxt = mask | (1 << w)
                if bottleneck:
                    cand = (max(here[0], C[v, w]), here[1] + C[v, w])
                    if tuple(cand) < tuple(best[nxt, w]):
                        best[nxt, w], parent[nxt, w] = cand, v
                elif here + C[v, w] < best[nxt, w]:
                    best[nxt, w], parent[nxt, w] = here + C[v, w], v
    ends = best[full - 1]
    v = min(range(n), key=lambda u: tuple(ends[u]) if bottleneck else ends[u])
    order, mask = [], full - 1
    while v != -1:
        order.append(v)
        v, mask = parent[mask, v], mask & ~(1 << v)
    return order[::-1]


def heuristic(C, bottleneck=False):
    """Nearest neighbour from every start, each improved by 2-opt (reversing a stretch while that
    lowers the cost): the best route found."""
    n = len(C)
    best, best_v = None, None
    for start in range(n):
        order, left = [start], set(range(n)) - {start}
        while left:
            nxt = min(left, key=lambda w: C[order[-1], w])
            order.append(nxt)
            left.remove(nxt)
        improved = True
        while improved:
            improved = False
            for i in range(1, n - 1):
                for j in range(i + 1, n):
                    trial = order[:i] + order[i:j + 1][::-1] + order[j + 1:]
                    if _value(C, trial, bottleneck) < _value(C, order, bottleneck):
                        order, improved = trial, True
        v = _value(C, order, bottleneck)
        if best_v is None or v < best_v:
            best, best_v = order, v
    return best


def spanning_tree_bound(C):
    """A lower bound on any open route's total cost: the weight of a minimum spanning tree (Prim) of the
    symmetrised costs, since a route is a spanning path (each step costs at least the cheaper direction)."""
    S = np.minimum(C, C.T)
    n = len(S)
    inside, dist, total = np.zeros(n, bool), S[0].copy(), 0.0
    inside[0] = True
    for _ in range(n - 1):
        d = np.where(inside, np.inf, dist)
        k = int(np.argmin(d))
        total += d[k]
        inside[k] = True
        dist = np.minimum(dist, S[k])
    return float(total)


def order(C, bottleneck=False):
    """(order, method, lower bound or None): exact up to EXACT_UP_TO positions, else the heuristic with
    the spanning-tree bound on the total (None for the bottleneck objective)."""
    if len(C) <= EXACT_UP_TO:
        return held_karp(C, bottleneck), "exact (Held-Karp, every order)", None
    return heuristic(C, bottleneck), "nearest neighbour from every start, then 2-opt", (
        None if bottleneck else spanning_tree_bound(C))
