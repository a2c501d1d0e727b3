"""Worst cases of a function over a box of parameters and a set of positions, searched where they live.

A remainder of a linearisation grows with the size of every parameter, so its maximum over a box
sits at a vertex (a sign pattern): the search starts from random sign patterns at many positions,
flips single signs while any flip increases |f| (a vertex local maximum), then moves the position
by local ascent with the vertex fixed, and flips again. A search finds lower bounds of the worst
case, never proofs: a bound that a search exceeds is false; one it does not exceed still needs a proof.
"""
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Worst:
    """The largest |f| a search found, where, and how it was found."""

    value: float          # the largest |f| found
    x: np.ndarray         # the position there
    p: np.ndarray         # the parameters there (a vertex of the box, or inside when interior=True)


def _flip_ascent(f, X, S, mx, val, rounds):
    """Greedy single-sign flips, all starts at once, until no flip increases |f|."""
    for _ in range(rounds):
        gain, which = np.zeros(S.shape[1]), np.full(S.shape[1], -1)
        for k in range(S.shape[0]):
            S[k] *= -1
            v = np.abs(f(X, S * mx[:, None]))
            S[k] *= -1
            better = v > val + gain
            gain[better], which[better] = (v - val)[better], k
        moved = np.flatnonzero(which >= 0)
        if not moved.size:
            break
        S[which[moved], moved] *= -1
        val[moved] += gain[moved]
    return S, val


def vertex_search(f, X0, mx, project=lambda X: X, step=0.05, starts=4, keep=40, ascent=300, rounds=40,
                  seed=0):
    """max |f(x, p)| over positions x (columns of X0 start the search; `project` maps a moved x back
    onto the set, e.g. normalises a direction) and p in the box |p_i| <= mx_i (at its vertices).

    f(X, P) takes positions (d, N) and parameters (n, N) and returns (N,)."""
    rng = np.random.default_rng(seed)
    mx = np.asarray(mx, float)
    X = np.repeat(np.asarray(X0, float), starts, axis=1)
    S = rng.choice([-1.0, 1.0], size=(len(mx), X.shape[1]))
    S, val = _flip_ascent(f, X, S, mx, np.abs(f(X, S * mx[:, None])), rounds)
    top = np.argsort(val)[-keep:]
    X, S, val = X[:, top], S[:, top], val[top]
    scale = step
    for _ in range(ascent):
        trial = project(X + scale * rng.normal(size=X.shape))
        v = np.abs(f(trial, S * mx[:, None]))
        up = v > val
        X[:, up], val[up] = trial[:, up], v[up]
        scale *= 0.985
    S, val = _flip_ascent(f, X, S, mx, val, rounds)
    k = int(np.argmax(val))
    return Worst(float(val[k]), X[:, k].copy(), S[:, k] * mx)


def sphere_directions(n):
    """n nearly uniform unit vectors (Fibonacci lattice), shape (3, n)."""
    k = np.arange(n) + 0.5
    polar, azimuth = np.arccos(1 - 2 * k / n), np.pi * (1 + 5 ** 0.5) * k
    return np.array([np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)])


def unit(X):
    """The columns of X scaled to unit length."""
    return X / np.linalg.norm(X, axis=0)
