"""The geometry garant budget's figures between grid attitudes rest on (workflows/budget.py `_sups`,
workflows/attitudes.py), checked here independently of `attitudes.stretch`: the cube-sphere grid's cells, their
triangles, and how far a unit vector is from a triangle's hull along its ray."""
import numpy as np
import pytest

from garant.verify.workflows.attitudes import grid, stretch
from conftest import fast_first


@pytest.mark.parametrize("side", fast_first([3, 6, 24], 2))
def test_every_unit_vector_is_a_point_of_a_grid_triangles_hull_stretched_by_at_most_stretch(side):
    # Per axis and |e| are convex in n for a calibration without catalogue effects, so over the hull of a grid
    # triangle they are at most their largest at its corners; a unit vector n is t m with m in that hull and t =
    # 1 / |m|, and the figures add (t - 1) times the slope bound outward. Here, for 200,000 random unit vectors: the
    # cube face the ray crosses, its cell on that face (the grid's attitudes are the cells' corners, normalised),
    # the cell's triangle (split along the diagonal (0, 0)-(1, 1)) holding the ray, and m where the ray meets the
    # plane of the triangle's normalised corners: m inside the triangle (barycentric weights >= 0), every corner an
    # attitude of attitudes.grid, and 1 <= t <= attitudes.stretch(side), and not far above the largest t found. Red
    # with stretch returning 1 (no stretch: the figures would miss the part between attitudes).
    rng = np.random.default_rng(side)
    n = rng.normal(size=(200_000, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    # each vector's face: its largest coordinate, moved first (the faces are alike up to the order and signs)
    f = np.argmax(np.abs(n), axis=1)
    perm = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1]])[f]
    m = np.take_along_axis(n, perm, axis=1)
    sign = np.sign(m[:, 0])
    uv = m[:, 1:] / np.abs(m[:, :1])                           # the ray's point on the face, in [-1, 1]^2
    h = 2.0 / side
    ij = np.minimum(np.floor((uv + 1) / h), side - 1)
    frac = (uv + 1) / h - ij
    upper = frac[:, 1] > frac[:, 0]                           # the triangle of the cell holding the ray
    corner = [np.zeros_like(ij), np.where(upper[:, None], [[1.0, 1.0]], [[1.0, 0.0]]),
              np.where(upper[:, None], [[0.0, 1.0]], [[1.0, 1.0]])]

    def point(k):                                             # a corner as a unit vector in the original axes
        face = -1 + (ij + k) * h
        p = np.column_stack([sign, face])
        p /= np.linalg.norm(p, axis=1)[:, None]
        out = np.empty_like(p)
        np.put_along_axis(out, perm, p, axis=1)
        return out
    a, b, c = (point(k) for k in corner)
    normal = np.cross(b - a, c - a)
    t = np.einsum("ij,ij->i", normal, n) / np.einsum("ij,ij->i", normal, a)    # n = t m, m on the plane
    mm = n / t[:, None]
    weights = np.linalg.solve(np.stack([a, b, c], axis=2), mm[:, :, None])[:, :, 0]
    assert weights.min() >= -1e-9
    attitudes, _ = grid(side)
    for p in (a[:2000], b[:2000], c[:2000]):                 # each corner an attitude of the grid
        assert np.linalg.norm(p[:, None] - attitudes[None], axis=2).min(axis=1).max() < 1e-12
    assert t.min() >= 1 - 1e-12
    assert t.max() <= stretch(side) <= 1 + 1.5 * (t.max() - 1)
