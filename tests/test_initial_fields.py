"""Initial fields projected on beams with attachments and on stepped beams (issue 33).

``q_n = sum_s rhoA_s int w Y_n dx + sum_k (m_k w(x_k) Y_n(x_k) + J_k w'(x_k) Y_n'(x_k))``:
checked against the mass-orthonormality of the modes (a mode's shape projects on its unit
vector), the static tip-load shape's exact projection ``Y_n(L) / (c omega_n^2)`` (the beam's
own Green's function), today's uniform projection, a stepped beam of equal segments and the
energy balance of a run that starts from a projected field.
"""

import numpy as np
import pytest

from impactbeams import simulate
from impactbeams.modes import beam
from impactbeams.packing import pack_run
from impactbeams.params import Params
from impactbeams.structure import PointMass, Segment, Spring
from impactbeams.structure.waves import quadrature
from impactbeams.trajectory import InitialFields
from impactbeams.trajectory.start import projected_fields

N_MODES = 10
# a tip mass with rotary inertia, an interior one with rotary inertia, a spring with both
# stiffnesses: every term of the mass product and a curvature jump under each inertia
PARTS = (PointMass(0.1, 1e-3, 1e-7), PointMass(0.05, 2e-3, 3e-8), Spring(0.025, 300.0, 0.4))
STOP = Params(counterpart="stop", contact_stiffness=1e4)


def _state(params: Params, fields: InitialFields, n_modes: int = N_MODES) -> np.ndarray:
    return projected_fields(pack_run(params, n_modes, 0.01, 0.01), fields)


# a stiffer, heavier root (tests/test_segments.py's): 3 EI, 1.5 rhoA over 4 cm
ROOT = (Segment(0.04, 3 * STOP.EI1, 1.5 * STOP.rhoA1), Segment(0.06, STOP.EI1, STOP.rhoA1))


@pytest.mark.parametrize(("params", "tolerance"), [
    # masses and springs only: the Gauss quadrature per piece is exact to round-off (measured
    # 1.6e-15)
    (STOP.replace(attachments1=(PointMass(0.1, 1e-3), PointMass(0.05, 2e-3),
                                Spring(0.025, 300.0, 0.4))), 1e-14),
    # rotary inertias: the slope by fourth-order differences, round-off ~11 eps / (k h) ~ 3e-12
    # of the slope scale k |Y| (measured 8.4e-12)
    (STOP.replace(attachments1=PARTS), 2e-11),
    # a stepped beam with a tip mass and rotary inertia (measured 2.9e-12)
    (STOP.replace(segments1=ROOT, attachments1=PARTS[:1]), 2e-11)],
    ids=["masses-springs", "inertias", "stepped"])
def test_a_mode_shape_projects_on_its_unit_vector(params, tolerance):
    """<Y_m, Y_n> = delta_mn with the attachments: each mode's shape, given as a field,
    projects on its own coordinate only (both the deflection and the velocity)."""
    assert _worst_unit_error(params, 1) < tolerance


def _worst_unit_error(params, which):
    """The largest error of the states projected from beam ``which``'s mode shapes (as its
    deflection and velocity fields) against those modes' unit vectors."""
    packed = pack_run(params, N_MODES, 0.01, 0.01)
    free = packed.dynamics.free
    shapes, n = getattr(free, f"beam{which}").shapes, free.frequencies.size
    first = 0 if which == 1 else free.modes_per_beam[0]  # beam 2's coordinates after beam 1's
    worst = 0.0
    for m in range(N_MODES):
        shape = lambda x, m=m: shapes(x)[m]  # noqa: E731
        z = projected_fields(packed, InitialFields(**{f"deflection{which}": shape,
                                                      f"velocity{which}": shape}))
        unit = np.eye(n)[first + m]
        worst = max(worst, np.abs(z[:n] - unit).max(), np.abs(z[n:] - packed.v0 - unit).max())
    return worst


def test_beam_2s_fields_project_on_its_own_modes():
    """Two beams, each with a tip mass and rotary inertia: beam 2's mode shapes given as
    beam 2's fields project on beam 2's coordinates (after beam 1's), nothing on beam 1's
    (the difference slope as above; measured 6.7e-12)."""
    params = Params(contact_stiffness=1e4, attachments1=PARTS[:1],
                    attachments2=(PointMass(0.12, 5e-4, 5e-8),))
    assert _worst_unit_error(params, 2) < 2e-11


def test_the_static_tip_load_shape_projects_on_its_exact_modal_series():
    """u = G(x, L) / c (unit tip deflection, from the beam's Green's function with its springs)
    projects on <u, Y_n> = Y_n(L) / (c omega_n^2) (the free phase's unit1, from the strain
    energy: no quadrature); measured 3.5e-13 of the largest, the difference slope at the
    inertias (2e-11 as above)."""
    params = STOP.replace(attachments1=PARTS)
    packed = pack_run(params, N_MODES, 0.01, 0.01)
    cantilever = beam(params, 1)
    z = projected_fields(packed, InitialFields(deflection1=cantilever.unit_tip_shape))
    expected = packed.dynamics.free.unit1
    assert np.abs(z[:N_MODES] - expected).max() < 2e-11 * np.abs(expected).max()
    # its modal series at the tip: sum Y_n(L)^2 / (c omega_n^2) < 1, the static shape's tip,
    # approached from below (the higher modes' share, 3e-7 past 10 modes, is missing)
    tip = z[:N_MODES] @ packed.dynamics.free.tip1
    assert 1.0 - 1e-5 < tip < 1.0


def test_a_rigid_unit_field_projects_on_the_participation_factors():
    """w = 1 projects on Gamma_n = <1, Y_n>, which `participation` writes in closed form (the
    jumps of the third derivative per piece, no quadrature; measured 2.8e-13 of the largest:
    the difference slope of a constant, whose stencil's weights sum to 0 only to round-off,
    over the step)."""
    params = STOP.replace(attachments1=PARTS)
    cantilever = beam(params, 1)
    shapes = cantilever.free_modes(N_MODES).shapes
    gamma = cantilever.participation(shapes)
    projected = cantilever.projection(shapes, np.ones_like)
    assert np.abs(projected - gamma).max() < 1e-12 * np.abs(gamma).max()


def test_uniform_beams_project_as_before_bit_for_bit():
    """Without attachments the projection is rhoA int w Y_n dx on today's quadrature."""
    params = Params(contact_stiffness=1e4)
    packed = pack_run(params, N_MODES, 0.01, 0.01)
    field = lambda x: 1e-6 * np.sin(7.0 * x) * x  # noqa: E731
    z = projected_fields(packed, InitialFields(deflection1=field, velocity2=field))
    shapes1, shapes2 = packed.dynamics.free.beam1.shapes, packed.dynamics.free.beam2.shapes
    x1, w1 = quadrature(params.l1, 2.0 * float(np.max(shapes1.k)))
    x2, w2 = quadrature(params.l2, 2.0 * float(np.max(shapes2.k)))
    assert np.array_equal(z[:N_MODES], params.rhoA1 * (shapes1(x1) @ (w1 * field(x1))))
    assert np.array_equal(z[3 * N_MODES:] - packed.v0[N_MODES:],
                          params.rhoA2 * (shapes2(x2) @ (w2 * field(x2))))


def test_a_stepped_beam_of_equal_segments_projects_as_the_uniform_beam():
    """Two equal halves are the uniform beam: its modes and the projection on them, to the
    round-off of the wave-coefficient modes against the closed forms (measured 7e-16)."""
    field = lambda x: 1e-6 * (x / 0.1) ** 2 * np.cos(9.0 * x)  # noqa: E731
    fields = InitialFields(deflection1=field, velocity1=field)
    uniform = _state(STOP, fields)
    half = Segment(STOP.l1 / 2, STOP.EI1, STOP.rhoA1)
    stepped = _state(Params(counterpart="stop", contact_stiffness=1e4, segments1=(half, half)),
                     fields)
    assert np.abs(stepped - uniform).max() < 1e-12 * np.abs(uniform).max()


def test_a_run_from_a_projected_field_on_a_tip_mass_beam_keeps_its_energy():
    """F0 = 0, no damping: energy - unresolved kinetic energy stays constant through the
    impacts of a run started from deflection and velocity fields on a beam with a tip mass
    (as tests/test_attachments.py's balance, 1e-12 of the energy; measured 1.2e-15). Its
    energy at t = 0 is the fields' own, from the structure's static data: a u(L) and b u(L)
    with u the unit tip-load shape have strain energy a^2 / (2 c) and kinetic energy
    b^2 <u, u> / 2; the 20 modes hold all but the truncated tail of it (Bessel: never more;
    measured 5.8e-11 less)."""
    params = STOP.replace(attachments1=(PointMass(0.1, 1e-3, 1e-7),), clearance=1e-5)
    cantilever = beam(params, 1)
    u, a, b = cantilever.unit_tip_shape, 5e-5, 0.05  # m, m/s at the tip
    fields = InitialFields(deflection1=lambda x: a * u(x), velocity1=lambda x: b * u(x))
    ds = simulate(params, 0.05, n_modes=20, energy_balance=True, initial_state=fields)
    assert ds.impact.size >= 2
    balance = (ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force).values
    assert np.abs(balance - balance[0]).max() < 1e-12 * np.abs(ds.energy.values).max()
    exact = a**2 / (2 * cantilever.tip_compliance) + b**2 * cantilever.structure.static_mass / 2
    assert 0.0 <= 1.0 - float(ds.energy[0]) / exact < 1e-9
