"""The tied law (the paper's): contact modes of the pair, overlaps and static shifts.

Everything the kernels need for one geometry, precomputed once as plain arrays. Quasi-static
parts (docs/model.md) are multiples of the unit tip-load shapes ``u_i``
(`impactbeams.contact.free`):

* free phase: ``y_1s = -c_1 F(t) u_1``, ``y_2s = 0``;
* contact phase: ``y_is = -c_i Q_i(t) u_i`` with ``Q_1 = F - R_qs``, ``Q_2 = R_qs``,
  ``R_qs = (c_1 F - Delta) / (c_1 + c_2)`` the quasi-static contact force;
* the initial uplift fields are ``delta_i u_i``.

So the projections reduce to ``<u_i, mode>``, the mode-to-mode overlaps and the static
difference field ``s = c_1 u_1 (+) (-c_2 u_2)``: between phases, ``y_s(contact) - y_s(free)
= R_qs s``. Inner products are the mass-weighted <u, v> = sum_i rhoA_i int u_i v_i dx.
Projections of ``u_i`` use the exact boundary identity
``rhoA int u Y = (EI Y'''(l) + Y(l) / c) / omega^2``; mode-to-mode overlaps use composite
Gauss-Legendre quadrature. The tests check each against the other method.

Against a stop the contact phase is beam 1 alone with its tip held at ``-Delta``: the
clamped-pinned modes (``n`` of them, as many as the free coordinates), c2 = 0 so that
``R_qs = (c_1 F - Delta) / c_1`` and the contact shapes see no drive (the tip force goes into
the stop), and the contact force is beam 1's tip shear ``-EI_1 Z'''(l_1)``.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from impactbeams.blas import one_blas_thread
from impactbeams.contact.free import FreePhase, build_free_phase, quadrature
from impactbeams.modes import BeamShapes, ContactModes, beam, contact_modes
from impactbeams.params import ParameterError, Params


@dataclasses.dataclass(frozen=True)
class ModalModel:
    """Modal bases of both phases and their projections for one geometry.

    The contact phase has as many modes as the free phase has coordinates (``2 n_modes``,
    against a stop ``n_modes``): by interlacing they span the same frequency band.

    Attributes (SI units):
        params: the geometry (forcing values in it are not used here).
        n_modes: free modes per beam.
        free: the free phase (see `FreePhase`).
        contact: contact-phase modes.
        contact_tip: common tip displacement of the contact shapes.
        contact_shear2: the contact force per contact coordinate (N): EI_2 Z_2m'''(l_2), beam
            2's tip shear; against a stop -EI_1 Z_1m'''(l_1), beam 1's.
        overlap: <Z_m, Y_n>, shape (contact, free), by quadrature.
        contact_unit1, contact_unit2: <u_1, Z_m> on beam 1 only, <u_2, Z_m> on beam 2 only.
        contact_static_shift: <s, Z_m> = c_1 contact_unit1 - c_2 contact_unit2.
        contact_drive: kappa_m with r_m'' + omega_m^2 r_m = kappa_m F''(t):
            c1 c2 / (c1 + c2) (<u_1, Z_m> + <u_2, Z_m>).
    """

    params: Params
    n_modes: int
    free: FreePhase
    contact: ContactModes
    contact_tip: np.ndarray
    contact_shear2: np.ndarray
    overlap: np.ndarray
    contact_unit1: np.ndarray
    contact_unit2: np.ndarray
    contact_static_shift: np.ndarray
    contact_drive: np.ndarray


def _free_on_beam(shapes: BeamShapes, n_before: int, n_after: int, x: np.ndarray) -> np.ndarray:
    """Free shapes of one beam evaluated at x, padded with zero rows for the other beam."""
    values = shapes(x)
    return np.vstack([np.zeros((n_before, x.size)), values, np.zeros((n_after, x.size))])


@one_blas_thread
def build_tied_model(params: Params, n_modes: int) -> ModalModel:
    """The tied law's modal model: ``n_modes`` free modes per beam and as many contact modes.

    Its contact modes and overlaps are the closed forms of uniform beams: a beam with
    attachments (which a tied `Params` refuses; a spring law's passed here) raises
    ParameterError.
    """
    free = build_free_phase(params, n_modes)  # checks both arguments first
    if not (beam(params, 1).closed_form and beam(params, 2).closed_form):
        raise ParameterError("build_tied_model: the tied law supports the paper's uniform beams "
                             "only, not a beam with attachments or a user structure, nor a "
                             "stepped beam (use the spring law)")
    if not params.partner.has_beam2:
        return _stop_model(params, free)
    n = free.beam1.frequencies.size
    p = params
    c1, c2 = p.tip_compliance
    contact = contact_modes(p, 2 * n)
    k_max = max(free.beam1.shapes.k[-1], free.beam2.shapes.k[-1], contact.beam1.k[-1],
                contact.beam2.k[-1])
    x1, w1 = quadrature(p.l1, k_max)
    x2, w2 = quadrature(p.l2, k_max)
    z1, z2 = contact.beam1(x1), contact.beam2(x2)
    free1 = _free_on_beam(free.beam1.shapes, 0, n, x1)
    free2 = _free_on_beam(free.beam2.shapes, n, 0, x2)
    contact_tip = contact.beam1.tip()
    contact_unit1 = (p.EI1 * contact.beam1.tip(3) + contact_tip / c1) / contact.frequencies**2
    contact_unit2 = (p.EI2 * contact.beam2.tip(3) + contact_tip / c2) / contact.frequencies**2
    return ModalModel(
        params=p,
        n_modes=n,
        free=free,
        contact=contact,
        contact_tip=contact_tip,
        contact_shear2=p.EI2 * contact.beam2.tip(3),
        overlap=(z1 * p.rhoA1 * w1) @ free1.T + (z2 * p.rhoA2 * w2) @ free2.T,
        contact_unit1=contact_unit1,
        contact_unit2=contact_unit2,
        contact_static_shift=c1 * contact_unit1 - c2 * contact_unit2,
        contact_drive=c1 * c2 / (c1 + c2) * (contact_unit1 + contact_unit2),
    )


def _stop_model(params: Params, free: FreePhase) -> ModalModel:
    """The tied law against a stop: beam 1 clamped-pinned in contact, tip held at -Delta.

    The contact shapes' tip values are zero (exactly, not the ~1e-16 of their closed form);
    c2 = 0, so the contact drive c1 c2 / (c1 + c2) (...) and every beam-2 row vanish.
    """
    p = params
    c1 = p.tip_compliance[0]
    n = free.frequencies.size
    contact = contact_modes(p, n)
    x1, w1 = quadrature(p.l1, max(free.beam1.shapes.k[-1], contact.beam1.k[-1]))
    overlap = (contact.beam1(x1) * p.rhoA1 * w1) @ free.beam1.shapes(x1).T
    shear1 = p.EI1 * contact.beam1.tip(3)
    contact_unit1 = shear1 / contact.frequencies**2  # the boundary identity with Z(l1) = 0
    zeros = np.zeros(n)
    return ModalModel(params=p, n_modes=n, free=free, contact=contact, contact_tip=zeros,
                      contact_shear2=-shear1, overlap=overlap, contact_unit1=contact_unit1,
                      contact_unit2=zeros, contact_static_shift=c1 * contact_unit1,
                      contact_drive=zeros)


_warned: set[str] = set()


def build_model(params: Params, n_modes: int) -> ModalModel:
    """Deprecated alias of [`build_tied_model`][impactbeams.contact.tied.build_tied_model].

    Warns once per process (DeprecationWarning): it builds the tied law's model only.
    """
    if "build_model" not in _warned:
        _warned.add("build_model")
        warnings.warn("build_model is deprecated: use build_tied_model (it builds the tied "
                      "law's model)", DeprecationWarning, stacklevel=2)
    return build_tied_model(params, n_modes)
