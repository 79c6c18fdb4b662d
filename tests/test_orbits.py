"""Periodic orbits: the period map and its monodromy, shooting, Floquet multipliers.

The orbit of the tests: k = 1e4 N/m resolved by 12 modes per beam, zeta = 0.05, a stable
period-1 orbit with 6 contacts (one episode) per period (tests/test_lyapunov.py).
"""

import math

import numpy as np
import pytest

from impactbeams import ParameterError, Params
from impactbeams.kernels.layout import FREE, ROW_FREQUENCY
from impactbeams.orbits import PeriodMap

N_MODES = 12
PERIODIC = {"contact_stiffness": 1e4, "damping_ratio": 0.05}
DASHPOT = {**PERIODIC, "contact_damping": 0.5}


def energy_scale(period_map):
    """D with D z = (omega q, q'): the energy norm's coordinates."""
    omega = period_map.packed.tables[FREE, ROW_FREQUENCY]
    return np.concatenate([omega, np.ones(omega.size)])


def settled(period_map, periods=60):
    """The section state after ``periods`` maps from the run's start."""
    z = period_map.rest_state()
    for _ in range(periods):
        z = period_map(z, measures=False).state
    return z


@pytest.fixture(scope="module")
def dashpot_map():
    period_map = PeriodMap(Params(**DASHPOT), n_modes=N_MODES)
    return period_map, settled(period_map)


def central_differences(period_map, z, step):
    """dP/dz by central differences of the nonlinear map, steps ``step`` / D per coordinate."""
    scale = energy_scale(period_map)
    size = step * np.linalg.norm(scale * z)
    columns = []
    for j in range(z.size):
        e = np.zeros(z.size)
        e[j] = size / scale[j]
        columns.append((period_map(z + e, measures=False).state
                        - period_map(z - e, measures=False).state) / (2 * e[j]))
    return np.array(columns).T


def test_monodromy_matches_finite_differences(dashpot_map):
    """With a dashpot (saltation at the onsets): the tangent Jacobian against central
    differences of the map at relative step 1e-4 in the energy norm (the differences' round-off,
    ~2e-10 / 1e-4, dominates: measured 2e-6, as for tests/test_lyapunov.py's flow map)."""
    period_map, z = dashpot_map
    result = period_map(z, directions="all", measures=False)
    scale = energy_scale(period_map)
    carried = scale[:, None] * result.jacobian / scale[None, :]
    reference = scale[:, None] * central_differences(period_map, z, 1e-4) / scale[None, :]
    assert np.linalg.norm(carried - reference, 2) < 2e-5 * np.linalg.norm(reference, 2)


def test_jacobian_columns_are_the_monodromy_applied_to_directions(dashpot_map):
    """A block of directions gets the same tangent propagation as the identity's columns:
    equal to round-off of the sums (the rows are carried independently, 1e-12 relative)."""
    period_map, z = dashpot_map
    full = period_map(z, directions="all", measures=False).jacobian
    block = np.random.default_rng(1).standard_normal((z.size, 3))
    carried = period_map(z, directions=block, measures=False).jacobian
    assert np.allclose(carried, full @ block, rtol=0, atol=1e-12 * np.abs(full @ block).max())


def test_period_map_counts_and_measures(dashpot_map):
    period_map, z = dashpot_map
    result = period_map(z)
    assert result.status == "complete"
    assert result.contacts >= 1 and result.episodes >= 1
    assert result.peak_force > 0 and result.impulse > 0
    assert result.max_tip1 > 0 and result.max_tip2 > 0
    two = PeriodMap(Params(**DASHPOT), n_modes=N_MODES, periods=2)(z)
    assert two.contacts == 2 * result.contacts  # a period-1 orbit
    assert two.impulse == pytest.approx(2 * result.impulse, rel=1e-8)


def test_period_map_refuses_what_it_cannot_do():
    with pytest.raises(ParameterError, match="spring contact law"):
        PeriodMap(Params(contact_law="tied"))
    with pytest.raises(ParameterError, match="omega"):
        PeriodMap(Params(**PERIODIC, omega=0.0), n_modes=N_MODES)
    period_map = PeriodMap(Params(**PERIODIC), n_modes=N_MODES)
    with pytest.raises(ParameterError, match=r"state = \(3,\): must be a finite modal state"):
        period_map(np.zeros(3))
    bad = period_map.rest_state()
    bad[0] = math.nan
    with pytest.raises(ParameterError, match="state"):
        period_map(bad)
    with pytest.raises(ParameterError, match="directions"):
        period_map(period_map.rest_state(), directions=np.zeros((5, 2)))
