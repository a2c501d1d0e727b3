"""The attitudes a budget is taken over (workflows/budget.py): the directions of a cube-sphere grid, its covering
chord, and how far outside the hull of a grid triangle a unit vector can lie (`stretch`), which lets a convex error
be bounded between grid attitudes by its values at them."""
import numpy as np

EPS = np.finfo(float).eps


def grid(side):
    """(N, 3) unit directions of the cube-sphere grid with `side` cells per face side, and its covering chord: a
    point of a face lies within sqrt(2) / side of a grid point in face coordinates, and the radial map onto the
    sphere (the projection onto the unit ball) is 1-Lipschitz."""
    t = np.linspace(-1.0, 1.0, side + 1)
    u, v = (x.ravel() for x in np.meshgrid(t, t))
    one = np.ones_like(u)
    faces = [np.column_stack(c) for s in (1.0, -1.0) for c in ((s * one, u, v), (u, s * one, v), (u, v, s * one))]
    P = np.vstack(faces)
    P = np.unique(np.round(P, 12), axis=0)
    return P / np.linalg.norm(P, axis=1)[:, None], np.sqrt(2.0) / side


def stretch(side):
    """The largest t = 1 / (the distance of a grid triangle's plane from 0) over the triangles of `grid(side)` (each
    face cell split along either diagonal; the faces are alike): every unit vector is t m with m in a triangle's
    hull and 1 <= t <= it."""
    t = np.linspace(-1.0, 1.0, side + 1)
    u, v = np.meshgrid(t, t, indexing="ij")
    P = np.stack([np.ones_like(u), u, v], axis=-1)
    P /= np.linalg.norm(P, axis=-1, keepdims=True)
    a, b, c, d = P[:-1, :-1], P[1:, :-1], P[1:, 1:], P[:-1, 1:]
    near = np.inf
    for x, y, z in ((a, b, c), (a, c, d), (a, b, d), (b, c, d)):
        normal = np.cross(y - x, z - x)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        near = min(near, float(np.abs((normal * x).sum(axis=-1)).min()))
    return (1.0 / near) * (1 + 16 * EPS)
