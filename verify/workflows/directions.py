"""Stand angles that hold the block with a given nominal up-direction: how a positions file of known
directions (a fixture, docs/formats.md) becomes positions of a stand described by its angles."""
import itertools

import numpy as np

from ..errors import DataError

GRID_DEG = 5.0


def _up(mod, deg):
    return np.asarray(mod.up_nominal(*np.deg2rad(deg)), float)


def angles_for(mod, U, path="directions"):
    """(K, n_angles) degrees within the stand's ranges with up_nominal(angles) = U[k] (unit vectors, (K, 3)):
    the nearest point of a 5-degree grid, then Gauss-Newton. One clear line when a direction is not
    reachable."""
    ranges = np.array(mod.ANGLE_RANGES_DEG, float)
    axes = [np.arange(lo, hi + 1e-9, GRID_DEG) for lo, hi in ranges]
    grid = np.array(list(itertools.product(*axes)))                       # (G, n)
    ups = _up(mod, grid.T).reshape(3, -1).T                               # (G, 3)
    out = []
    U = np.asarray(U, float)
    for k, u in enumerate(U / np.linalg.norm(U, axis=1, keepdims=True)):     # files round them
        x = grid[int(np.argmin(np.linalg.norm(ups - u, axis=1)))].copy()
        for _ in range(50):
            r = _up(mod, x) - u
            J = np.column_stack([(_up(mod, x + h) - _up(mod, x - h)) / 2e-6
                                 for h in np.eye(len(x)) * 1e-6])
            step, *_ = np.linalg.lstsq(J, -r, rcond=None)
            x = x + step
            if np.linalg.norm(step) < 1e-12:
                break
        x = ranges[:, 0] + (x - ranges[:, 0]) % 360.0                     # the same turn, within the range
        if np.any(x > ranges[:, 1]) or np.linalg.norm(_up(mod, x) - u) > 1e-8:
            raise DataError(f"{path}: position {k + 1}: the stand cannot hold the block with up-direction "
                            f"{np.round(u, 6).tolist()} within its angle ranges", param="data")
        out.append(x)
    return np.array(out)


def up_in_block(mod, angles_deg, mounts=None):
    """(S, 3): the nominal up-direction in block axes at each position (degrees; `mounts` the mounting
    index of each, for stands with several): which faces of the block point up there."""
    deg = np.asarray(angles_deg, float).reshape(len(angles_deg), -1)
    mounts = 0 if mounts is None else np.asarray(mounts, int)
    return np.asarray(mod.up_nominal(*np.deg2rad(deg.T), mount=mounts), float).reshape(3, -1).T
