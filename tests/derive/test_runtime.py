"""The generated runtime (generated/_runtime.py): the helpers every model module shares, and the typed protocols a
stand module and the norm module follow."""
import types

import numpy as np
import pytest

from garant.derive import codegen
from garant.generated import _runtime, norm
from garant.generated import MODELS


def _members(protocol):
    return set(protocol.__annotations__)


def test_the_protocols_are_the_api_each_module_exports():
    # The protocol and the list the registry checks a module against at load (codegen.API) are one list.
    assert _members(_runtime.StandModel) == set(codegen.API["stand"])
    assert _members(_runtime.NormModel) == set(codegen.API["norm"])


@pytest.mark.parametrize("name", [m for m in MODELS if m != "norm"])
def test_every_built_in_stand_follows_the_stand_protocol(name):
    from garant.verify import models
    mod = models.load(name)
    assert isinstance(mod, _runtime.StandModel)
    without = types.SimpleNamespace(**{k: getattr(mod, k) for k in codegen.API["stand"] if k != "PSI"})
    assert not isinstance(without, _runtime.StandModel)                   # one member missing: not a stand module


def test_the_norm_module_follows_its_protocol():
    assert isinstance(norm, _runtime.NormModel) and not isinstance(norm, _runtime.StandModel)


def _with_plans():
    from garant.verify import models
    return [m for m in MODELS if m != "norm" and len(models.load(m).PLAN_DEG)]


@pytest.mark.parametrize("name", _with_plans())
def test_estimate_on_plan_is_the_sum_over_the_plan_of_psi_times_z(name):
    # The shared on_plan against the sum written out: q_nu = sum_s sum_p PSI[nu, s, p] z[p, s].
    from garant.verify import models
    mod = models.load(name)
    z = np.random.default_rng(1).normal(size=(3, len(mod.PLAN_DEG)))
    by_hand = [sum(mod.PSI[nu, s, p] * z[p, s] for s in range(z.shape[1]) for p in range(3))
               for nu in range(len(mod.Q_NAMES))]
    np.testing.assert_allclose(mod.estimate_on_plan(z), by_hand, rtol=1e-13, atol=1e-15)
    with pytest.raises(ValueError, match="must have shape"):
        mod.estimate_on_plan(z.T)


def test_the_norm_estimate_on_plan_is_psi_times_sigma():
    z = np.random.default_rng(2).normal(size=len(norm.PLAN))
    np.testing.assert_allclose(norm.estimate_on_plan(z), norm.PSI @ z, rtol=1e-13)
    terms = {(nu, k): n / d for nu, row in enumerate(norm.ESTIMATOR_TERMS) for k, n, d in row}
    assert all(norm.PSI[nu, k] == w for (nu, k), w in terms.items()) and np.count_nonzero(norm.PSI) == len(terms)
