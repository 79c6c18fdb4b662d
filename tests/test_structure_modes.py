"""Cantilevers with attachments (impactbeams.structure) against independent references.

References: the closed-form characteristic equation of a cantilever with a tip mass and rotary
inertia (references.py), a finite-element model with lumped attachments (Hermite elements,
written here from the element matrices, SciPy's eigensolver), the uniform cantilever of
impactbeams.modes, the static Green's function in closed form, Rayleigh's interlacing theorems.
"""

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq

from impactbeams.modes import free_modes
from impactbeams.params import ParameterError
from impactbeams.structure import Cantilever, PointMass, Segment, Spring, waves
from references import gauss_rule, tip_mass_roots

EI, RHOA, L = 9.0167e-3, 1.8402e-2, 0.1  # the default steel strip (N m^2, kg/m, m)
TIP_STIFFNESS = 3 * EI / L**3  # N/m


# --- an independent finite-element model ----------------------------------------------------


def hermite_stiffness(ei, h):
    """Stiffness of a Hermite beam element of length h (w_a, theta_a, w_b, theta_b)."""
    return ei / h**3 * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h**2, -6 * h, 2 * h**2],
                                 [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h**2, -6 * h, 4 * h**2]])


def fe_model(segments, attachments, per_metre, clamp=math.inf):
    """K, M (DOFs w, theta per node from the clamp out) and node positions of a Hermite
    mesh with lumped masses, rotary inertias and springs at nodes; ``clamp``: the clamp's
    rotational stiffness (inf: theta_0 held). ``segments``: (length, EI, rhoA) triples."""
    nodes, element_data = [0.0], []
    for i, (length, ei, rhoa) in enumerate(segments):
        count = round(length * per_metre)
        start = math.fsum(s[0] for s in segments[:i])
        end = math.fsum(s[0] for s in segments[:i + 1])  # as Cantilever.length
        element_data += [(length / count, ei, rhoa)] * count
        nodes += list(np.linspace(start, end, count + 1)[1:])
    size = 2 * len(nodes)
    K, M = np.zeros((size, size)), np.zeros((size, size))
    for e, (h, ei, rhoa) in enumerate(element_data):
        K[2 * e:2 * e + 4, 2 * e:2 * e + 4] += hermite_stiffness(ei, h)
        M[2 * e:2 * e + 4, 2 * e:2 * e + 4] += rhoa * h / 420 * np.array([
            [156, 22 * h, 54, -13 * h], [22 * h, 4 * h**2, 13 * h, -3 * h**2],
            [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h**2, -22 * h, 4 * h**2]])
    nodes = np.array(nodes)
    for a in attachments:
        node = int(np.argmin(np.abs(nodes - a.position)))
        assert abs(nodes[node] - a.position) < 1e-12, "attachments must sit on nodes"
        if isinstance(a, PointMass):
            M[2 * node, 2 * node] += a.mass
            M[2 * node + 1, 2 * node + 1] += a.rotary_inertia
        else:
            K[2 * node, 2 * node] += a.stiffness
            K[2 * node + 1, 2 * node + 1] += a.rotational_stiffness
    keep = [1] if math.isfinite(clamp) else []
    if keep:
        K[1, 1] += clamp
    keep += list(range(2, size))
    return K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], nodes


def fe_frequencies(K, M):
    """All FE natural frequencies (rad/s), ascending, as 1 / sqrt of the eigenvalues of
    (M, K): the low modes' with a round-off of about 1e-10 at 40 elements (eigh(K, M) loses
    eps cond(K), 5e-9 there)."""
    return 1.0 / np.sqrt(scipy.linalg.eigh(M, K, eigvals_only=True)[::-1])


def _to_structure(segments, attachments, clamp=math.inf):
    parts = list(attachments)
    if math.isfinite(clamp):
        parts.append(Spring(0.0, rotational_stiffness=clamp))
    return Cantilever(tuple(Segment(*s) for s in segments), tuple(parts))


# Configurations on a 0.1 m beam, every attachment on a multiple of 1 cm (a node of each mesh).
CASES = {
    "interior masses": ([(L, EI, RHOA)], [PointMass(0.03, 0.5 * RHOA * L, 2e-3 * RHOA * L**3),
                                          PointMass(0.07, 2.0 * RHOA * L, 0.0)], math.inf),
    "springs": ([(L, EI, RHOA)], [Spring(0.04, 30 * TIP_STIFFNESS, 0.0),
                                  Spring(0.08, 0.0, 2.0 * EI / L)], math.inf),
    "compliant clamp, tip spring and mass": (
        [(L, EI, RHOA)], [Spring(L, 5 * TIP_STIFFNESS, 0.5 * EI / L),
                          PointMass(L, 0.3 * RHOA * L, 1e-3 * RHOA * L**3)], 4.0 * EI / L),
    "stepped beam with a mass": ([(0.04, 3 * EI, 1.5 * RHOA), (0.06, EI, RHOA)],
                                 [PointMass(0.06, RHOA * L, 0.0)], math.inf),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_frequencies_converge_to_ours_at_the_fe_rate(name):
    """FE frequencies tend to ours as h^4 (error ratio 16 per halving of h), all attachments
    lumped at nodes: agreement to the FE's own error."""
    segments, attachments, clamp = CASES[name]
    ours = _to_structure(segments, attachments, clamp).modes(6).frequencies
    errors = []
    for per_metre in (100, 200, 400):
        K, M, _ = fe_model(segments, attachments, per_metre, clamp)
        errors.append(fe_frequencies(K, M)[:6] / ours - 1.0)
    errors = np.array(errors)
    assert (errors > 0).all()  # consistent mass: the FE frequencies lie above the exact ones
    rates = np.log2(errors[:-1] / errors[1:])  # measured: 3.76-4.00, then 3.95-4.01
    assert (np.abs(rates[0] - 4.0) < 0.3).all(), rates
    # modes 2-6 (mode 1's error at 40 elements, 1e-10 to 1e-8, meets the round-off there)
    assert (np.abs(rates[1, 1:] - 4.0) < 0.07).all(), rates


def test_uniform_beam_matches_impactbeams_modes():
    """No attachments: the frequencies and shapes of impactbeams.modes, to round-off."""
    n = 200
    ours = Cantilever.uniform(EI, RHOA, L).modes(n)
    reference = free_modes(EI, RHOA, L, n)
    assert np.abs(ours.frequencies / reference.frequencies - 1.0).max() < 1e-14
    x = np.linspace(0.0, L, 257)
    for derivative in range(4):
        theirs = reference.shapes(x, derivative)
        error = np.abs(ours(x, derivative) - theirs).max(axis=1) / np.abs(theirs).max(axis=1)
        assert error.max() < 1e-12, (derivative, error.max())


@pytest.mark.parametrize("mu, eta", [(0.1, 1e-3), (1.0, 1e-2), (10.0, 0.1), (1.0, 0.0)])
def test_tip_mass_and_rotary_inertia_against_the_characteristic_equation(mu, eta):
    beta = tip_mass_roots(mu, eta, 10)
    expected = np.sqrt(EI / RHOA) * (beta / L) ** 2
    beam = Cantilever.uniform(EI, RHOA, L, [PointMass(L, mu * RHOA * L, eta * RHOA * L**3)])
    ours = beam.modes(10).frequencies
    assert len(expected) == 10
    assert np.abs(ours / expected - 1.0).max() < 1e-10  # measured: 7e-16


def _mass_and_stiffness_products(beam, modes):
    """Phi^T M Phi and Phi^T K Phi by Gauss quadrature of the shapes, attachments added."""
    x, w = gauss_rule(beam.length, panels=400, order=16)
    pieces = beam.pieces
    piece = np.searchsorted(pieces.ends, x)
    Y, curvature = modes(x), modes(x, 2)
    mass = (Y * (pieces.rhoA[piece] * w)) @ Y.T
    stiffness = (curvature * (pieces.EI[piece] * w)) @ curvature.T
    for a in beam.attachments:
        value, slope = modes(a.position)[:, 0], modes(a.position, 1)[:, 0]
        if isinstance(a, PointMass):
            mass += a.mass * np.outer(value, value) + a.rotary_inertia * np.outer(slope, slope)
        else:
            stiffness += (a.stiffness * np.outer(value, value)
                          + a.rotational_stiffness * np.outer(slope, slope))
    return mass, stiffness


@pytest.mark.parametrize("name", sorted(CASES))
def test_modes_are_orthonormal_with_the_attachments(name):
    """int rhoA Y_n Y_m + sum m Y_n Y_m + sum J Y_n' Y_m' = delta_nm, and the strain energy
    (curvature, springs, compliant clamp) is diag(omega^2): the shapes solve the problem."""
    beam = _to_structure(*CASES[name])
    modes = beam.modes(30)
    mass, stiffness = _mass_and_stiffness_products(beam, modes)
    assert np.abs(mass - np.eye(30)).max() < 1e-12  # measured: 3e-15 to 1.3e-14
    scale = np.outer(modes.frequencies, modes.frequencies)
    assert np.abs(stiffness / scale - np.eye(30)).max() < 1e-12  # measured: 4e-15 to 1.2e-14


def test_shapes_meet_the_joint_conditions():
    """At an interior mass and spring: EI w''' jumps by (k - m omega^2) w, EI w'' by
    (kr - J omega^2) w' (values on each side from just beside the node)."""
    m, J, k, kr, x0 = 0.5 * RHOA * L, 2e-3 * RHOA * L**3, 20 * TIP_STIFFNESS, EI / L, 0.05
    beam = Cantilever.uniform(EI, RHOA, L, [PointMass(x0, m, J), Spring(x0, k, kr)])
    modes = beam.modes(8)
    w2 = modes.frequencies**2
    side = np.array([x0, np.nextafter(x0, 1.0)])  # the clamp side (the node itself), the far side
    jump3 = EI * np.diff(modes(side, 3), axis=1)[:, 0]
    jump2 = EI * np.diff(modes(side, 2), axis=1)[:, 0]
    value, slope = modes(x0)[:, 0], modes(x0, 1)[:, 0]
    scale3 = EI * np.abs(modes(side, 3)).max(axis=1)
    scale2 = EI * np.abs(modes(side, 2)).max(axis=1)
    assert np.abs(-jump3 - (k - m * w2) * value).max() / scale3.max() < 1e-9
    assert np.abs(jump2 - (kr - J * w2) * slope).max() / scale2.max() < 1e-9


def _bare_frequencies(n):
    return free_modes(EI, RHOA, L, n).frequencies


def _node_of_mode(mode):
    """A node of the bare cantilever's mode ``mode`` (1-based), away from the clamp (m)."""
    shapes = free_modes(EI, RHOA, L, mode).shapes
    x = np.linspace(0.2 * L, L, 2001)
    values = shapes(x)[mode - 1]
    i = np.nonzero(np.sign(values[1:]) != np.sign(values[:-1]))[0][0]
    return brentq(lambda s: shapes(s)[mode - 1, 0], x[i], x[i + 1], xtol=1e-300, rtol=1e-15)


def test_no_root_missed_for_200_modes_with_a_heavy_mass_at_a_node():
    """A point mass lowers each frequency at most to the one below (interlacing): with a
    heavy mass (10 beam masses) at a node of mode 3, every root lies in
    [omega_(n-1), omega_n] of the bare beam, and mode 3 keeps its bare frequency."""
    n = 200
    x0 = _node_of_mode(3)
    ours = Cantilever.uniform(EI, RHOA, L, [PointMass(x0, 10 * RHOA * L)]).modes(n).frequencies
    bare = _bare_frequencies(n)
    tol = 1e-12
    assert (ours <= bare * (1 + tol)).all()
    assert (ours[1:] >= bare[:-1] * (1 - tol)).all()
    assert np.abs(ours / bare[2] - 1.0).min() < 1e-12  # a root at the untouched mode
    assert (np.diff(ours) > 0).all()


def test_no_root_missed_for_200_modes_with_a_stiff_spring_at_a_node():
    """A spring raises each frequency at most to the next one: roots in
    [omega_n, omega_(n+1)] of the bare beam; a stiff spring at a node of mode 5 leaves that
    mode's frequency as it is."""
    n = 200
    x0 = _node_of_mode(5)
    beam = Cantilever.uniform(EI, RHOA, L, [Spring(x0, 1e9 * TIP_STIFFNESS)])
    ours = beam.modes(n).frequencies
    bare = _bare_frequencies(n + 1)
    tol = 1e-12
    assert (ours >= bare[:-1] * (1 - tol)).all()
    assert (ours <= bare[1:] * (1 + tol)).all()
    assert np.abs(ours / bare[4] - 1.0).min() < 1e-12


def _half_beam_frequencies(n):
    """The first n frequencies (rad/s) of the beam held (clamped) at mid-span: those of the
    clamped-clamped inner half (cos b cosh b = 1) and of the clamped-free outer half."""
    def clamped(b):
        return 2 * math.exp(-b) / (1 + math.exp(-2 * b)) - math.cos(b)  # cos cosh - 1 over cosh

    inner = np.array([brentq(clamped, j * np.pi, (j + 1) * np.pi, xtol=1e-300, rtol=1e-15)
                      for j in range(1, n + 1)])
    inner = np.sqrt(EI / RHOA) * (inner / (L / 2)) ** 2
    return np.sort(np.concatenate([inner, free_modes(EI, RHOA, L / 2, n).frequencies]))[:n]


def test_no_root_missed_for_200_clustered_roots():
    """Stiff translational and rotational springs at mid-span (1e9 times the beam's own
    stiffness there) all but clamp it: the inner half's clamped-clamped frequencies and the
    outer half's clamped-free ones approach each other exponentially with the mode number, so
    the roots come in pairs split only by the springs' compliance (down to 2e-6 relative).
    Every pair is found: the roots interlace with the bare beam's (a rank-2 stiffening:
    omega_n <= . <= omega_(n+2)), approach the held beam's, and the count at each midpoint
    between consecutive roots is the number of roots below it."""
    n = 200
    beam = Cantilever.uniform(EI, RHOA, L, [Spring(L / 2, 1e9 * TIP_STIFFNESS, 1e9 * EI / L)])
    ours = beam.modes(n).frequencies
    bare = _bare_frequencies(n + 2)
    assert (ours >= bare[:-2] * (1 - 1e-12)).all() and (ours <= bare[2:] * (1 + 1e-12)).all()
    assert np.abs(ours / _half_beam_frequencies(n) - 1.0).max() < 2e-3  # measured: 1.3e-3
    gaps = np.diff(ours) / ours[1:]
    assert gaps.min() < 1e-5  # the clusters are there
    midpoints = 0.5 * (ours[1:] + ours[:-1])
    assert [beam.frequency_count(w) for w in midpoints] == list(range(1, n))


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_count_equals_the_fe_count(name):
    """Wittrick-Williams: J(omega) is the number of FE eigenvalues below omega on a fine mesh,
    at many trial frequencies (those within the FE's error of a root left out)."""
    segments, attachments, clamp = CASES[name]
    beam = _to_structure(segments, attachments, clamp)
    exact = beam.modes(25).frequencies
    K, M, _ = fe_model(segments, attachments, 2000, clamp)
    fe = fe_frequencies(K, M)
    trials = np.random.default_rng(33).uniform(0.1 * exact[0], exact[-1], 400)
    trials = trials[np.abs(trials[:, None] / exact[None, :] - 1.0).min(axis=1) > 1e-3]
    assert len(trials) > 300
    counts = [beam.frequency_count(w) for w in trials]
    assert counts == list(np.searchsorted(fe, trials))


def green_uniform(x, y):
    """Deflection at x under a unit force at y of a clamped uniform cantilever (m/N)."""
    near, far = np.minimum(x, y), np.maximum(x, y)
    return near**2 * (3 * far - near) / (6 * EI)


def test_flexibility_of_the_uniform_cantilever_is_the_cubic():
    x = np.linspace(0.0, L, 41)
    G = Cantilever.uniform(EI, RHOA, L, [PointMass(0.05, 1.0)]).flexibility(x, x)
    expected = green_uniform(x[:, None], x[None, :])
    assert np.abs(G - expected).max() < 1e-14 * expected.max()


def test_flexibility_with_a_tip_spring_in_closed_form():
    """A tip spring k carries R = k w(L); under a unit force at y, w(L) = G0(L, y) - R c with
    c = L^3 / (3 EI), so R = k G0(L, y) / (1 + k c) and G = G0(x, y) - R G0(x, L)."""
    k = 7 * TIP_STIFFNESS
    x = np.linspace(0.0, L, 41)
    G = Cantilever.uniform(EI, RHOA, L, [Spring(L, k)]).flexibility(x, x)
    c = L**3 / (3 * EI)
    R = k * green_uniform(L, x) / (1 + k * c)
    expected = green_uniform(x[:, None], x[None, :]) - green_uniform(x, L)[:, None] * R[None, :]
    assert np.abs(G - expected).max() < 1e-14 * expected.max()
    assert G[-1, -1] == pytest.approx(1 / (TIP_STIFFNESS + k), rel=1e-14)


@pytest.mark.parametrize("name", sorted(CASES))
def test_flexibility_equals_the_fe_inverse_stiffness(name):
    """Hermite elements hold the static deflection under nodal loads exactly, so K^-1 at the
    nodes is the exact flexibility, to its round-off: eps cond(K), cond(K) 4e6 to 3e7 at 10
    elements (measured differences 2e-13 to 5e-13; 2e-12 to 1.5e-11 at 20 elements)."""
    segments, attachments, clamp = CASES[name]
    beam = _to_structure(segments, attachments, clamp)
    K, _, nodes = fe_model(segments, attachments, 100, clamp)
    # node j's w is DOF 2 j of the full mesh; the clamp's w (and theta unless compliant) removed
    w = 2 * np.arange(1, len(nodes)) - (1 if math.isfinite(clamp) else 2)
    flexibility = np.linalg.inv(K)[np.ix_(w, w)]
    ours = beam.flexibility(nodes[1:], nodes[1:])
    assert np.abs(ours - flexibility).max() < 2e-12 * np.abs(flexibility).max()


@pytest.mark.parametrize("name, rate", [("springs", -3.0),
                                        ("compliant clamp, tip spring and mass", -5.0)])
def test_residual_flexibility_falls_at_the_predicted_rate(name, rate):
    """R_N(L, L) = G(L, L) - sum Y_n(L)^2 / omega_n^2 > 0 falls like N^(rate). A free tip:
    Y_n(L)^2 tends to a constant and omega_n^2 grows like n^4, so R_N ~ N^-3. A tip mass
    holds the tip at high frequency (EI w''' = -m omega^2 w gives Y_n(L) ~ 1 / n), so N^-5."""
    beam = _to_structure(*CASES[name])
    modes = beam.modes(160)
    residual = [modes_prefix(modes, n).residual_flexibility(L, L)[0, 0] for n in (20, 40, 80, 160)]
    assert (np.array(residual) > 0).all()
    slopes = np.diff(np.log(residual)) / np.log(2.0)  # measured: -3.01 .. -3.00, -5.15 .. -5.04
    assert np.abs(slopes - rate).max() < 0.2, slopes
    assert np.abs(slopes[-1] - rate) < 0.05, slopes


def modes_prefix(modes, n):
    """The first n of ``modes``."""
    import dataclasses

    return dataclasses.replace(modes, frequencies=modes.frequencies[:n],
                               wave_numbers=modes.wave_numbers[:n], short=modes.short[:n],
                               coefficients=modes.coefficients[:n])


def test_dynamic_stiffness_is_continuous_where_the_series_hands_over():
    """Either side of b = SHORT (series below, scaled closed form above) the matrices and the
    counts agree; at b -> 0 it is the static Hermite element stiffness."""
    below, above = np.nextafter(waves.SHORT, 0.0), np.nextafter(waves.SHORT, 3.0)
    a, b = waves.dynamic_stiffness(EI, 30.0, below), waves.dynamic_stiffness(EI, 30.0, above)
    assert np.abs(a - b).max() < 1e-13 * np.abs(a).max()
    f, g = waves.free_end_stiffness(EI, 30.0, below), waves.free_end_stiffness(EI, 30.0, above)
    assert np.abs(f - g).max() < 1e-13 * np.abs(f).max()
    h, k = 1e-3, 1e-2  # b = 1e-5
    static = hermite_stiffness(EI, h)
    dynamic = waves.dynamic_stiffness(EI, k, k * h)
    assert np.abs(dynamic - static).max() < 1e-12 * np.abs(static).max()


BAD = [
    (lambda: Segment(0.0, EI, RHOA), "Segment.length = 0.0 is not allowed: must be a finite "
     "real number > 0 (m)"),
    (lambda: Segment(L, math.nan, RHOA), "Segment.EI = nan is not allowed"),
    (lambda: Segment(L, EI, "1"), "Segment.rhoA = '1' is not allowed"),
    (lambda: PointMass(0.05, -1e-3), "PointMass.mass = -0.001 is not allowed: must be a finite "
     "real number >= 0 (kg)"),
    (lambda: PointMass(0.05, 1e-3, math.inf), "PointMass.rotary_inertia = inf"),
    (lambda: Spring(0.05, -1.0), "Spring.stiffness = -1.0 is not allowed"),
    (lambda: Cantilever.uniform(EI, RHOA, L, [PointMass(0.2, 1e-3)]),
     "attachments[0].position = 0.2 is not allowed: must lie on the beam, 0 < x <= 0.1"),
    (lambda: Cantilever.uniform(EI, RHOA, L, [Spring(0.05), PointMass(0.0, 1e-3)]),
     "attachments[1].position = 0.0 is not allowed"),
    (lambda: Cantilever.uniform(EI, RHOA, L, [Spring(0.0, 10.0)]),
     "attachments[0].position = 0.0 is not allowed"),
    (lambda: Cantilever.uniform(EI, RHOA, L, [Spring(0.0, 0.0, 0.0)]),
     "Spring.rotational_stiffness at position 0 = 0.0 is not allowed: must be > 0"),
    (lambda: Cantilever.uniform(EI, RHOA, L, ["mass"]),
     "attachments[0] = 'mass' is not allowed: must be a PointMass or a Spring"),
    (lambda: Cantilever(()), "segments = () is not allowed"),
    (lambda: Cantilever.uniform(EI, RHOA, L).modes(0), "n = 0 is not allowed"),
    (lambda: Cantilever.uniform(EI, RHOA, L).frequency_count(-1.0), "omega = -1.0 is not allowed"),
    (lambda: Cantilever.uniform(EI, RHOA, L).frequency_count("5"), "omega = '5' is not allowed"),
    (lambda: Cantilever.uniform(EI, RHOA, L).flexibility([0.05, 0.11], 0.1),
     "x = 0.11 is not allowed: must lie on the beam, 0 <= x <= 0.1 (m)"),
    (lambda: Cantilever.uniform(EI, RHOA, L).modes(2)(math.nan), "x = nan is not allowed"),
]


@pytest.mark.parametrize("call, message", BAD, ids=[m.split(" ")[0] for _, m in BAD])
def test_bad_input_is_refused_in_one_line(call, message):
    with pytest.raises(ParameterError) as error:
        call()
    assert message in str(error.value)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("stiffness, orthonormal", [(1e9, 2e-10), (1e20, 3e-8)])
def test_clustered_and_merged_roots_get_orthonormal_shapes(stiffness, orthonormal):
    """Pairs of roots 2e-6 apart (springs 1e9 times the beam's stiffness) and pairs merged to
    round-off (1e20: the held beam, to 1e-15): every pair gets two mass-orthonormal shapes.
    A root alone gets a null vector accurate to eps / (distance to its neighbour); roots
    closer than sqrt(eps) share theirs (the null space at their mean): measured 5.7e-11 and
    1.3e-8 (a pair 1.45e-8 apart, just outside a shared null space)."""
    beam = Cantilever.uniform(EI, RHOA, L, [Spring(L / 2, stiffness * TIP_STIFFNESS,
                                                   stiffness * EI / L)])
    modes = beam.modes(60)
    if stiffness > 1e15:
        assert np.abs(modes.frequencies / _half_beam_frequencies(60) - 1.0).max() < 1e-14
    mass, _ = _mass_and_stiffness_products(beam, modes)
    assert np.abs(mass - np.eye(60)).max() < orthonormal


def test_the_count_does_not_flicker_next_to_a_root_of_commensurate_pieces():
    """Pieces of 4, 4 and 2 cm: mode 158 lies next to a pole of the free last piece. With the
    slope DOFs scaled so that K's entries spanned 16 orders of magnitude, eigvalsh's error
    flipped the count back and forth over 4e-4 of the frequency there, and the root went
    unbracketed; every entry of the order of EI k^3, the count rises once, monotonically."""
    beam = _to_structure(*CASES["springs"])
    root = beam.modes(160).frequencies[157]
    trials = root * np.linspace(0.992, 1.008, 401)  # the flicker was over 0.9995-1.0
    counts = np.array([beam.frequency_count(w) for w in trials])
    assert (np.diff(counts) >= 0).all() and counts[0] == 157 and counts[-1] == 158
