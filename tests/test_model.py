"""Projections between the bases, checked against closed forms and independent quadrature."""

import numpy as np
import pytest

from impactbeams.model import build_free_phase, build_model, unit_tip_shape
from references import gauss_rule


def test_unit_projections_against_quadrature(model50, default_params):
    p = default_params
    x1, w1 = gauss_rule(p.l1)
    x2, w2 = gauss_rule(p.l2)
    u1, u2 = unit_tip_shape(p.l1, x1), unit_tip_shape(p.l2, x2)
    free = model50.free
    Y1 = free.beam1.shapes(x1)
    quad = p.rhoA1 * (Y1 * w1) @ u1
    # closed form Y(l) / (c omega^2) vs quadrature; both O(1e-3) for mode 1, round-off 1e-16
    assert np.abs(quad - free.unit1[:50]).max() < 1e-14 * np.abs(free.unit1).max()
    Z1, Z2 = model50.contact.beam1(x1), model50.contact.beam2(x2)
    for quad_c, closed in ((p.rhoA1 * (Z1 * w1) @ u1, model50.contact_unit1),
                           (p.rhoA2 * (Z2 * w2) @ u2, model50.contact_unit2)):
        assert np.abs(quad_c - closed).max() < 1e-14 * np.abs(closed).max()


def test_overlap_matches_boundary_identity(model50, default_params):
    """rhoA int Y Z = EI Y(l) Z'''(l) / (omega_Z^2 - omega_Y^2) on each beam (free Y has no
    tip shear and both have no tip moment), an independent closed form of the quadrature."""
    p = default_params
    free, contact = model50.free, model50.contact
    wz, wy = contact.omega[:, None], free.omega[None, :]
    identity = (p.EI1 * contact.beam1.tip(3)[:, None] * free.tip1[None, :]
                + p.EI2 * contact.beam2.tip(3)[:, None] * free.tip2[None, :]) / (wz**2 - wy**2)
    # overlaps are O(1); the identity divides by omega differences, quadrature is at round-off
    assert np.abs(identity - model50.overlap).max() < 1e-12


def _round_trip_errors(params, n_values, make_vector, forward):
    errors = []
    for n in n_values:
        model = build_model(params, n)
        x = make_vector(model)
        P = model.overlap
        back = P @ (P.T @ x) if forward == "contact" else P.T @ (P @ x)
        errors.append(np.linalg.norm(back - x) / np.linalg.norm(x))
    return np.array(errors)


@pytest.mark.parametrize("k", [0, 1, 2, 4])
def test_contact_mode_round_trip_converges_with_modes(default_params, k):
    """A contact shape expanded in free modes and projected back returns itself up to
    truncation. Contact shapes carry a tip shear that free shapes lack, so the expansion
    converges algebraically: measured about n^-3.5; required at least n^-3."""
    def unit(model):
        e = np.zeros(model.overlap.shape[0])
        e[k] = 1.0
        return e

    errors = _round_trip_errors(default_params, (20, 50), unit, "contact")
    assert errors[1] <= errors[0] * (20 / 50) ** 3
    assert errors[1] < 5e-6  # measured 1.5e-8 (k=0) .. 3.6e-6 (k=4)


def test_free_field_with_equal_tips_round_trip(default_params):
    """A free field lies in the contact space only if its tips are equal (the tie): first
    modes of both beams scaled to unit tip. Measured 2e-10 at n = 50, rate about n^-4."""
    def equal_tips(model):
        n = model.n_modes
        x = np.zeros(2 * n)
        x[0], x[n] = 1 / model.free.tip1[0], 1 / model.free.tip2[n]
        return x

    errors = _round_trip_errors(default_params, (20, 50), equal_tips, "free")
    assert errors[1] <= errors[0] * (20 / 50) ** 3 and errors[1] < 1e-9


def test_static_expansions_converge_to_closed_form_compliances(default_params):
    """sum Y_n(l)^2 / omega_n^2 = c (a cantilever's tip compliance); the contact phase gives
    the two tips in parallel, c1 c2 / (c1 + c2). Tails fall like n^-3."""
    p = default_params
    c1, c2 = p.tip_compliance
    errors = []
    for n in (25, 50, 200):
        free = build_free_phase(p, n)
        errors.append(np.sum(free.tip1**2 / free.omega**2) / c1 - 1)
    assert abs(errors[2]) < 1e-6 and abs(errors[1] / errors[2]) > 40  # (200/50)^3 = 64
    model = build_model(p, 50)
    series = np.sum(model.contact_tip**2 / model.contact.omega**2)
    assert series == pytest.approx(c1 * c2 / (c1 + c2), rel=1e-5)


def test_static_shift_projections(model50, default_params):
    c1, c2 = default_params.tip_compliance
    free = model50.free
    assert np.array_equal(free.static_shift, c1 * free.unit1 - c2 * free.unit2)
    assert np.array_equal(model50.contact_static_shift,
                          c1 * model50.contact_unit1 - c2 * model50.contact_unit2)


def test_bad_mode_count():
    with pytest.raises(ValueError, match="n_modes = 0 is not allowed"):
        build_free_phase(None, 0)
