import os
import tempfile

import numpy as np
import pytest

# Derived descriptions are cached (verify/models.py); the tests keep theirs apart from the user's.
os.environ.setdefault("GARANT_CACHE", tempfile.mkdtemp(prefix="garant-test-cache-"))

from garant.generated import two_axis as two_axis


@pytest.fixture(scope="session")
def mod():
    return two_axis


def simulate(mod, positions_deg, physical, sigma, g=9.81, seed=0):
    """Readings (N, 3) in m/s^2 from the exact model plus noise bounded by sigma (units of g)."""
    P = np.deg2rad(np.asarray(positions_deg, float))
    f = mod.readings(P[:, 0], P[:, 1], physical, g).T
    rng = np.random.default_rng(seed)
    return f + g * rng.uniform(-sigma, sigma, f.shape)


def write_csv(path, positions_deg, f, extra=None):
    with open(path, "w") as fh:
        cols = ["alpha_deg", "beta_deg", "f1", "f2", "f3"] + list(extra or {})
        fh.write(",".join(cols) + "\n")
        for k, ((a, b), row) in enumerate(zip(positions_deg, f)):
            cells = [repr(float(a)), repr(float(b))] + [repr(float(v)) for v in row]
            cells += [str(v[k]) for v in (extra or {}).values()]
            fh.write(",".join(cells) + "\n")
    return path
