"""Everything the kernels need for one geometry, precomputed once as plain arrays.

Quasi-static parts (MODEL.md) are all multiples of the unit tip-load shapes
``u_i(x) = (3 l_i x^2 - x^3) / (2 l_i^3)`` (unit tip deflection), with ``c_i = l_i^3 / (3 EI_i)``:

* free phase: ``y_1s = -c_1 F(t) u_1``, ``y_2s = 0``;
* contact phase: ``y_is = -c_i Q_i(t) u_i`` with ``Q_1 = F - R_qs``, ``Q_2 = R_qs``,
  ``R_qs = (c_1 F - Delta) / (c_1 + c_2)`` the quasi-static contact force;
* the initial uplift fields are ``delta_i u_i``.

So the projections reduce to ``<u_i, mode>``, the mode-to-mode overlaps and the static
difference field ``s = c_1 u_1 (+) (-c_2 u_2)``: between phases, ``y_s(contact) - y_s(free)
= R_qs s``. Inner products are the mass-weighted <u, v> = sum_i rhoA_i int u_i v_i dx.
Projections of ``u_i`` use the exact boundary identity
``rhoA int u Y = (EI Y'''(l) + Y(l) / c) / omega^2`` (integration by parts, since
u'''' = 0 and u''(l) = Y''(l) = 0); mode-to-mode overlaps use composite Gauss-Legendre
quadrature. The tests check each against the other method.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.polynomial.legendre import leggauss

from impactbeams.modes import BeamShapes, ContactModes, FreeModes, contact_modes, free_modes
from impactbeams.params import Params

_GAUSS_ORDER = 12


def quadrature(length: float, max_wavenumber: float) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss-Legendre nodes (m) and weights on [0, length].

    Two panels per half-wave of the product of two shapes with wave numbers up to
    ``max_wavenumber`` (1/m).
    """
    n_panels = max(16, int(np.ceil(4 * max_wavenumber * length / np.pi)))
    nodes, weights = leggauss(_GAUSS_ORDER)
    edges = np.linspace(0.0, length, n_panels + 1)
    a, b = edges[:-1, None], edges[1:, None]
    return ((a + b) / 2 + (b - a) / 2 * nodes).ravel(), ((b - a) / 2 * weights).ravel()


def unit_tip_shape(length: float, x: np.ndarray) -> np.ndarray:
    """u(x) = (3 l x^2 - x^3) / (2 l^3): static tip-load shape with unit tip deflection."""
    return (3 * length * x**2 - x**3) / (2 * length**3)


@dataclasses.dataclass(frozen=True)
class ModalModel:
    """Modal bases of both phases and their projections for one geometry.

    Free coordinates are ordered beam 1 modes then beam 2 modes (``2 n_modes``); the contact
    phase has ``2 n_modes`` modes too (same number of degrees of freedom: by interlacing they
    span the same frequency band).

    Attributes (SI units):
        params: the geometry (forcing values in it are not used here).
        beam1, beam2: free cantilever modes of each beam.
        contact: contact-phase modes.
        free_omega, contact_omega: natural frequencies (rad/s) in phase order.
        free_tip1, free_tip2: tip displacement of each free coordinate's shape on beam 1 / 2
            (zero for the other beam's modes).
        contact_tip: common tip displacement of the contact shapes.
        contact_shear2: EI_2 Z_2m'''(l_2), tip shear (contact force) per contact coordinate (N).
        overlap: <Z_m, Y_n>, shape (contact, free).
        free_unit1, free_unit2: <u_1, Y_n>, <u_2, Y_n> (kg^1/2).
        contact_unit1, contact_unit2: <u_1, Z_m> on beam 1 only, <u_2, Z_m> on beam 2 only.
        free_static_shift: <s, Y_n>; contact_static_shift: <s, Z_m>.
        free_drive, contact_drive: b_n such that q_n'' + omega_n^2 q_n = b_n F''(t) (m kg^1/2/N):
            free ``Y_1n(l1) / omega_1n^2`` (beam 1), 0 (beam 2); contact
            ``c1 c2 / (c1 + c2) (<u_1, Z_m> + <u_2, Z_m>)``.
    """

    params: Params
    n_modes: int
    beam1: FreeModes
    beam2: FreeModes
    contact: ContactModes
    free_omega: np.ndarray
    contact_omega: np.ndarray
    free_tip1: np.ndarray
    free_tip2: np.ndarray
    contact_tip: np.ndarray
    contact_shear2: np.ndarray
    overlap: np.ndarray
    free_unit1: np.ndarray
    free_unit2: np.ndarray
    contact_unit1: np.ndarray
    contact_unit2: np.ndarray
    free_static_shift: np.ndarray
    contact_static_shift: np.ndarray
    free_drive: np.ndarray
    contact_drive: np.ndarray


def _free_on_beam(shapes: BeamShapes, n_before: int, n_after: int, x: np.ndarray) -> np.ndarray:
    """Free shapes of one beam evaluated at x, padded with zero rows for the other beam."""
    values = shapes(x)
    return np.vstack([np.zeros((n_before, x.size)), values, np.zeros((n_after, x.size))])


def build_model(params: Params, n_modes: int) -> ModalModel:
    """Precompute the modal model with ``n_modes`` free modes per beam, ``2 n_modes`` contact."""
    if not isinstance(n_modes, (int, np.integer)) or isinstance(n_modes, bool) or n_modes < 1:
        raise ValueError(f"n_modes = {n_modes!r} is not allowed: must be an integer >= 1")
    n = int(n_modes)
    p = params
    c1, c2 = p.tip_compliance
    beam1 = free_modes(p.EI1, p.rhoA1, p.l1, n)
    beam2 = free_modes(p.EI2, p.rhoA2, p.l2, n)
    contact = contact_modes(p, 2 * n)
    k_max = max(beam1.shapes.k[-1], beam2.shapes.k[-1], contact.beam1.k[-1], contact.beam2.k[-1])
    x1, w1 = quadrature(p.l1, k_max)
    x2, w2 = quadrature(p.l2, k_max)
    m1, m2 = p.rhoA1 * w1, p.rhoA2 * w2  # mass-weighted quadrature weights
    free1 = _free_on_beam(beam1.shapes, 0, n, x1)  # free coordinates on beam 1
    free2 = _free_on_beam(beam2.shapes, n, 0, x2)
    z1, z2 = contact.beam1(x1), contact.beam2(x2)
    zeros = np.zeros(n)
    free_tip1 = np.concatenate([beam1.shapes.tip(), zeros])
    free_tip2 = np.concatenate([zeros, beam2.shapes.tip()])
    free_unit1 = free_tip1 / (c1 * np.concatenate([beam1.omega, beam2.omega]) ** 2)
    free_unit2 = free_tip2 / (c2 * np.concatenate([beam1.omega, beam2.omega]) ** 2)
    contact_tip = contact.beam1.tip()
    contact_unit1 = (p.EI1 * contact.beam1.tip(3) + contact_tip / c1) / contact.omega**2
    contact_unit2 = (p.EI2 * contact.beam2.tip(3) + contact_tip / c2) / contact.omega**2
    return ModalModel(
        params=p,
        n_modes=n,
        beam1=beam1,
        beam2=beam2,
        contact=contact,
        free_omega=np.concatenate([beam1.omega, beam2.omega]),
        contact_omega=contact.omega,
        free_tip1=free_tip1,
        free_tip2=free_tip2,
        contact_tip=contact_tip,
        contact_shear2=p.EI2 * contact.beam2.tip(3),
        overlap=(z1 * m1) @ free1.T + (z2 * m2) @ free2.T,
        free_unit1=free_unit1,
        free_unit2=free_unit2,
        contact_unit1=contact_unit1,
        contact_unit2=contact_unit2,
        free_static_shift=c1 * free_unit1 - c2 * free_unit2,
        contact_static_shift=c1 * contact_unit1 - c2 * contact_unit2,
        free_drive=np.concatenate([beam1.shapes.tip() / beam1.omega**2, zeros]),
        contact_drive=c1 * c2 / (c1 + c2) * (contact_unit1 + contact_unit2),
    )
