"""The spring law's contact phase per active set of several contacts (issue 33, item 3).

`impactbeams.contact.active_sets`: one active contact is the single contact's own phase bit for
bit; two give the modal stiffness diag(omega^2) + B K_eff B^T with K_eff = (K^-1 + R_N)^-1,
checked against a dense eigen-decomposition and R_N against the modes' own tail.
"""

import numpy as np
import pytest

from impactbeams import Contact, Params, two_sided_stop
from impactbeams.contact.active_sets import possible_sets, several_contacts
from impactbeams.packing import dynamics_arrays

STOP = Params(counterpart="stop", contact_stiffness=1e4)
MID = 0.5 * STOP.l1  # m
TWO = STOP.replace(contacts=(Contact(MID, clearance=2e-6), Contact(clearance=5e-6)))


@pytest.mark.parametrize("params", [TWO, TWO.replace(damping_ratio=0.01),
                                    STOP.replace(contacts=two_sided_stop(MID))])
def test_one_active_contact_is_the_single_contacts_phase_bit_for_bit(params):
    """sets[(j,)] is `spring_contact` of contact j's own run: eigenvalues, modes, k_e."""
    contacts = several_contacts(params, 8)
    for j, run in enumerate(params.each_contact()):
        one, own = contacts.sets[(j,)], dynamics_arrays(run, 8).spring
        for name in ("eigenvalues", "right", "left"):
            np.testing.assert_array_equal(getattr(one, name), getattr(own, name))
        assert one.effective_stiffness[0, 0] == own.effective_stiffness
        np.testing.assert_array_equal(one.force_weights[0], own.phase * own.force_weights)


@pytest.mark.parametrize(("contacts", "count"), [
    ((Contact(MID), Contact()), 4),
    (two_sided_stop(MID), 3),
    ((*two_sided_stop(), Contact(MID)), 6),
    ((*two_sided_stop(), *two_sided_stop(MID)), 9),
])
def test_the_sets_that_can_occur(contacts, count):
    """Every subset but those closing both sides of a two-sided stop: 2^n, 3^p 2^(n - 2p)."""
    sets = possible_sets(STOP.replace(contacts=contacts))
    assert len(sets) == count and sets[0] == ()


def test_two_active_contacts_modal_stiffness_against_a_dense_solver():
    """Frequencies of diag(omega^2) + B K_eff B^T by rank-one updates vs numpy's eigh (to its
    own error, 1e-13 of the largest), K_eff vs (K^-1 + R_N)^-1, the modes orthonormal."""
    contacts = several_contacts(TWO, 10)
    both = contacts.sets[(0, 1)]
    omega, weights = contacts.frees[0].frequencies, contacts.gap_weights.T
    k_eff = np.linalg.inv(np.diag(1.0 / contacts.stiffness) + contacts.residual)
    np.testing.assert_allclose(both.effective_stiffness, k_eff, rtol=1e-14, atol=1e-12)
    dense = np.sqrt(np.linalg.eigvalsh(np.diag(omega**2) + weights @ k_eff @ weights.T))
    assert np.all(np.abs(both.frequencies**2 - dense**2) <= 1e-13 * dense[-1]**2)
    vectors = both.right[:omega.size].real
    np.testing.assert_allclose(vectors.T @ vectors, np.eye(omega.size), atol=1e-13)
    # the lowest frequency lies above each single contact's: two springs stiffen it
    assert both.frequencies[0] > max(contacts.sets[(j,)].frequencies[0] for j in (0, 1))


def test_residual_flexibility_is_the_modes_tail():
    """R_N(10 modes) - R_N(200 modes) = sum over modes 11..200 of b_a b_b / omega^2 (each
    from the Green's function minus its own modes: an independent route to the same tail)."""
    few, many = several_contacts(TWO, 10), several_contacts(TWO, 200)
    weights, omega = many.gap_weights, many.frees[0].frequencies
    tail = (weights[:, 10:] / omega[10:]**2) @ weights[:, 10:].T
    np.testing.assert_allclose(few.residual - many.residual, tail, rtol=1e-9)
    assert few.residual[0, 1] != 0.0


def test_dashpots_matrix_correction():
    """C_eff = (I + K R_N)^-1 C (I + R_N K)^-1 (one contact: c / (1 + k r_N)^2)."""
    params = TWO.replace(contacts=(Contact(MID, damping=0.3), Contact(damping=0.1)))
    contacts = several_contacts(params, 10)
    a = np.linalg.inv(np.eye(2) + np.diag(contacts.stiffness) @ contacts.residual)
    expected = a @ np.diag(contacts.damping) @ np.linalg.inv(
        np.eye(2) + contacts.residual @ np.diag(contacts.stiffness))
    np.testing.assert_allclose(contacts.sets[(0, 1)].effective_damping, expected, rtol=1e-13)
    r = contacts.residual[0, 0]
    np.testing.assert_allclose(contacts.sets[(0,)].effective_damping[0, 0],
                               0.3 / (1 + 1e4 * r)**2, rtol=1e-15)
