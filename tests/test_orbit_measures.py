"""What a shaker's user reads of a periodic orbit (issue 31, item 4): beam 1's tip amplitude
absolute and relative to its clamp, the transmissibility, the contacts per orbit, the impact
velocity and the largest contact force, as `orbit_measures` gives them to a continuation.

Each is checked against an independent computation: the continuous beam's exact steady
response to a moving clamp (undamped) and a 200-mode modal sum (damped) below contact, and
`simulate` of the orbit from its state, sampled (the gap's rate at each onset by a backward
difference, the contact force and the tip on fine grids), above.
"""

import math

import numpy as np
import pytest

from impactbeams import Params, simulate
from impactbeams.continuation.beams import orbit_measures
from impactbeams.orbits import PeriodMap
from impactbeams.orbits.shooting import periodic_orbit
from test_base_excitation import clamped_response, modal_sum

U0 = 2e-6  # m
FAR = 1e-2  # m, a stop the tip never reaches (the largest a stop may be: 0.2 l1)


@pytest.mark.parametrize("zeta", [0.0, 0.02])
@pytest.mark.parametrize("omega", [50.0, 400.0])
def test_transmissibility_below_contact_is_the_linear_one(omega, zeta):
    """The no-contact steady orbit (a stop out of reach, shaker on beam 1's clamp): the tip's
    absolute amplitude over U0 is |Y(l1)| of the continuous beam (undamped: exact; damped:
    |1 + W| of the modal sum over 200 modes), its relative one |Y(l1) - 1| U0. The orbit's
    modal sum (20 modes) converges like N^-5 in the relative motion: 1e-7 relative holds."""
    p = Params(counterpart="stop", clearance=FAR, force_amplitude=0.0, base_amplitude=U0,
               shaker="beam1", omega=omega, damping_ratio=zeta, start="steady")
    period_map = PeriodMap(p, n_modes=20)
    state = period_map.rest_state()  # on the steady state: the orbit itself
    result = period_map(state)
    assert result.contacts == 0
    np.testing.assert_allclose(result.state, state, rtol=0, atol=1e-10 * np.abs(state).max())
    measures = orbit_measures(period_map, result)
    if zeta == 0.0:
        absolute = clamped_response(p.EI1, p.rhoA1, p.l1, omega)
    else:
        absolute = 1.0 + modal_sum(p.EI1, p.rhoA1, p.l1, omega, zeta)
    assert measures["transmissibility"] == pytest.approx(abs(absolute), rel=1e-7)
    assert measures["tip_relative_amplitude_1"] == pytest.approx(abs(absolute - 1.0) * U0,
                                                                 rel=1e-7)
    assert measures["max_impact_velocity"] == 0.0 and measures["peak_contact_force"] == 0.0


def test_without_base_motion_the_transmissibility_is_nan_and_relative_is_absolute():
    p = Params(counterpart="stop", clearance=FAR, force_amplitude=1e-4, omega=100.0,
               damping_ratio=0.02, start="steady")
    period_map = PeriodMap(p, n_modes=5)
    measures = orbit_measures(period_map, period_map(period_map.rest_state()))
    assert math.isnan(measures["transmissibility"])
    assert measures["tip_relative_amplitude_1"] == measures["tip_amplitude_1"]


@pytest.fixture(scope="module", params=["beam1", "both"])
def impacting(request):
    """A stable impacting orbit under base excitation (soft stop, 5 modes) and a run of it.

    ``shaker = "both"`` moves the stop with beam 1's clamp: the gap is then between moving
    parts.
    """
    p = Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
               force_amplitude=0.0, base_amplitude=5e-6, shaker=request.param,
               omega=200.0 if request.param == "beam1" else 240.0)
    orbit = periodic_orbit(p, n_modes=5, transient_periods=100)
    period_map = PeriodMap(p, n_modes=5)
    result = period_map(orbit.state)
    return p, orbit, result, orbit_measures(period_map, result)


def test_contacts_and_impact_velocity_against_the_simulated_orbit(impacting):
    """The orbit run by `simulate` from its state over one period: the same contacts, and
    at each onset the gap's rate by a second-order backward difference of the sampled gap
    (step 1e-7 s: error ~ h^2 g''' / 3, below 1e-8 of the rate)."""
    p, orbit, result, measures = impacting
    period = 2 * np.pi / p.omega
    run = simulate(p, period, n_modes=5, initial_state=orbit.state, energy_balance=False)
    onsets = run.impact_onset_time.values
    assert orbit.contacts >= 1 and onsets.size == result.contacts == orbit.contacts
    h = 1e-7
    times = np.sort(np.concatenate([onsets - 2 * h, onsets - h, onsets]))
    sampled = simulate(p, period, n_modes=5, initial_state=orbit.state, times=times,
                       energy_balance=False)
    gap = sampled.gap.values.reshape(-1, 3)
    rates = (3 * gap[:, 2] - 4 * gap[:, 1] + gap[:, 0]) / (2 * h)
    assert np.all(rates < 0)
    np.testing.assert_allclose(result.impact_velocities, rates, rtol=1e-6)
    assert measures["max_impact_velocity"] == pytest.approx(float(np.max(-rates)), rel=1e-6)


def test_peak_force_and_amplitudes_against_the_simulated_orbit(impacting):
    """The largest contact force against R sampled at 2000 points across each contact (the
    samples' maximum is below the peak by at most ~ (pi / 2000)^2 / 2 of it); the tip's
    absolute and relative amplitudes against 40001 samples of one period."""
    p, orbit, _, measures = impacting
    period = 2 * np.pi / p.omega
    run = simulate(p, period, n_modes=5, initial_state=orbit.state, energy_balance=False)
    inside = np.concatenate([np.linspace(t, t + d, 2000) for t, d in
                             zip(run.impact_onset_time.values, run.impact_duration.values,
                                 strict=True)])
    forces = simulate(p, period, n_modes=5, initial_state=orbit.state,
                      times=np.sort(inside), energy_balance=False).contact_force.values
    peak = measures["peak_contact_force"]
    assert forces.max() <= peak * (1 + 1e-12) and forces.max() >= peak * (1 - 2e-6)
    times = np.linspace(0.0, period, 40001)
    tips = simulate(p, period, n_modes=5, initial_state=orbit.state, times=times,
                    energy_balance=False).tip_deflection_1.values
    relative = tips - p.base_amplitude * np.sin(p.omega * times)  # beam 1's clamp moves
    for name, sampled in (("tip_amplitude_1", np.abs(tips).max()),
                          ("tip_relative_amplitude_1", np.abs(relative).max())):
        # the samples' maximum is below the refined one by at most ~ (Omega dt)^2 / 2 x 30
        # (the first modes carry the tip): 1e-6 relative
        assert sampled <= measures[name] * (1 + 1e-12), name
        assert sampled >= measures[name] * (1 - 1e-6), name
    assert measures["transmissibility"] == measures["tip_amplitude_1"] / p.base_amplitude


@pytest.mark.parametrize("shaker", [True, False])
def test_tip_maxima_are_the_maxima_of_a_dense_scan_around_them(shaker):
    """The tip's largest |y1| and |y1 - u_b1|, refined at the root of their rate, against a
    dense scan of exact samples: 4001 across the two grid spacings around the largest grid
    sample, then 4001 across the two around the largest of those (spacing 1e-11 s: the scan's
    error, |y''| (spacing / 2)^2 / 2 ~ 2e-22 m, is below the values' rounding); without
    beam 2, y2 is 0; with the clamp at rest, the relative amplitude is the absolute one."""
    drive = ({"shaker": "beam1", "base_amplitude": 1e-4, "force_amplitude": 0.0} if shaker
             else {"force_amplitude": 3e-2})
    p = Params.from_mapping({"l1": 0.2, "width1": 0.02, "thickness1": 0.001,
                             "counterpart": "stop", "clearance": 5e-4, "damping_ratio": 0.01,
                             "contact_stiffness": 1e4, "omega": 150.0, **drive})
    period_map = PeriodMap(p, n_modes=8)
    z = period_map.rest_state()
    for _ in range(60):
        z = period_map(z, measures=False).state
    result = period_map(z)
    assert result.contacts >= 1 and result.max_tip2 == 0.0
    grid = period_map._grid()

    def size(times, relative):
        """|y1| or |y1 - u_b1| at ``times`` (m)."""
        tip = period_map.tip_motions(result, times)[:, 0]
        return np.abs(tip - (p.base_amplitude * np.sin(p.omega * times) if relative else 0.0))

    for value, relative in ((result.max_tip1, False), (result.max_relative_tip1, True)):
        times = grid
        for _ in range(2):
            i = int(np.argmax(size(times, relative)))
            times = np.linspace(times[i - 1], times[i + 1], 4001)
        dense = size(times, relative).max()
        assert value == pytest.approx(dense, rel=4 * np.finfo(float).eps, abs=0.0)
    if not shaker:
        assert result.max_relative_tip1 == result.max_tip1
