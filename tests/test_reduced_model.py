"""The reduced model handed to harmonic-balance peers (`packing.reduced_model`).

Its equations are checked against the engine itself: without contact, the closed-form steady
response of the reduced model against `simulate(start="steady")`; in contact, the engine's
steady impacting orbit against the reduced model's linear response to that orbit's own
contact force (the orbit is that response, whatever the law, if the modal equations, the
drive and the static correction are the same).
"""

import warnings

import numpy as np
import pytest

from impactbeams import Contact, Params, simulate
from impactbeams.packing import reduced_model
from impactbeams.params import ParameterError

N_MODES = 3


def tip_harmonics(model, contact: np.ndarray | None = None) -> np.ndarray:
    """Complex amplitudes Y_h of y1(l1, t) = Re sum_h Y_h e^(i h Omega t), periodic response.

    ``contact``: the contact force's amplitudes R_h (R = Re sum_h R_h e^(i h Omega t)), or
    None (no contact). y1 = tip1 . eta + r1 (R - F): the tip's static correction under both
    of its loads.
    """
    contact = np.zeros(2, complex) if contact is None else contact
    h = np.arange(contact.size)
    drive = np.where(h == 1, -1j * model.force_amplitude, 0.0)  # F0 sin = Re(-i F0 e^(iwt))
    dynamic = (model.frequencies[None] ** 2 - (h[:, None] * model.omega) ** 2
               + 1j * h[:, None] * model.omega * model.damping[None])
    eta = (np.outer(contact - drive, model.tip1) - np.outer(contact, model.tip2)) / dynamic
    return eta @ model.tip1 + model.residual1 * (contact - drive)


def test_reduced_model_holds_the_static_correction() -> None:
    params = Params(damping_ratio=0.02)
    model = reduced_model(params, N_MODES)
    c1, c2 = params.tip_compliance
    # each beam's modes plus its residual make its whole tip compliance (round-off)
    assert np.sum(model.tip1**2 / model.frequencies**2) + model.residual1 == pytest.approx(
        c1, rel=1e-13)
    assert np.sum(model.tip2**2 / model.frequencies**2) + model.residual2 == pytest.approx(
        c2, rel=1e-13)
    k = model.stiffness
    assert model.effective_stiffness == pytest.approx(
        k / (1 + k * (model.residual1 + model.residual2)), rel=1e-14)
    assert np.array_equal(model.damping, 2 * 0.02 * model.frequencies)


@pytest.mark.parametrize("change", [{"contact_law": "tied"}, {"contact_damping": 0.1},
                                    {"base_amplitude": 1e-6}, {"contact_side": "above"},
                                    {"contact_position1": 0.1}, {"contact_position2": 0.1},
                                    # two tip stops from below: two gap elements
                                    {"contacts": (Contact(clearance=1e-5),
                                                  Contact(clearance=2e-5, stiffness=1e5))}])
def test_reduced_model_refuses_what_it_cannot_express(change: dict) -> None:
    name = next(iter(change))
    with pytest.raises(ParameterError, match=f"reduced_model: {name} = "):
        reduced_model(Params(**change), N_MODES)


def test_reduced_model_without_contact_is_the_engines_steady_response() -> None:
    params = Params(damping_ratio=0.02, force_amplitude=1e-4, omega=350.0, clearance=1e-3,
                    start="steady")
    times = np.linspace(0.0, 0.05, 37)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # 3 modes do not resolve Hertz k
        run = simulate(params, 0.05, N_MODES, times=times)
    harmonics = tip_harmonics(reduced_model(params, N_MODES))
    expected = np.real(np.exp(1j * np.outer(times, [0, 1]) * params.omega) @ harmonics)
    # both are closed forms of the same linear equations: round-off of the 3e-6 m amplitude
    np.testing.assert_allclose(run.tip_deflection_1.values, expected, rtol=0,
                               atol=1e-12 * np.max(np.abs(expected)))


def test_reduced_model_in_contact_is_the_engines_orbit() -> None:
    params = Params(damping_ratio=0.02, force_amplitude=1e-4, omega=280.0)
    period = 2 * np.pi / params.omega
    samples = 1 << 15
    times = 799 * period + period * np.arange(samples) / samples
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        run = simulate(params, 800 * period, N_MODES, times=times)
    force = run.contact_force.values
    assert force.max() > 0  # the orbit impacts (one contact per period)
    contact = np.fft.rfft(force) / samples * 2
    contact[0] /= 2
    harmonics = tip_harmonics(reduced_model(params, N_MODES), contact)
    spectrum = np.zeros(samples, complex)  # the sample times are a whole number of periods
    spectrum[:harmonics.size] = harmonics  # and a uniform grid: sum over h by an inverse FFT
    expected = np.real(samples * np.fft.ifft(spectrum))
    # 800 periods bring the transient below 1e-12 (1600 change nothing); the contact force's
    # kinks alias in its sampled Fourier coefficients, an error that falls like samples^-2.5:
    # 2.2e-5, 7.6e-7 of the amplitude at 4096, 16384 samples, about 1.3e-7 at 32768
    np.testing.assert_allclose(run.tip_deflection_1.values, expected, rtol=0,
                               atol=1e-6 * np.max(np.abs(expected)))
