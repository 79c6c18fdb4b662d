"""Finite-element reference of the two cantilevers with the compliant (spring) tip contact.

Independent of impactbeams' kernels (numpy/scipy only; `params` is any object with the
attributes of `impactbeams.params.Params`). It reuses the Hermite-cubic beam assembly and the
exact modal propagation of `fe_reference.py`; the law is MODEL.md's "Compliant contact":

- gap g = clearance + y1(l1) - y2(l2) (m); e = e_tip1 - e_tip2 so that g = clearance + e . x;
  against a rigid stop (``params.counterpart == "stop"``) beam 1 alone, e = e_tip1;
- contact force R = -k g (N) while g < 0 and R > 0, else 0; R pushes beam 1's tip up and beam
  2's tip down, i.e. the nodal load R e; F(t) = F0 sin(Omega t) pushes beam 1's tip down;
- onset: g falls through 0; release: R falls through 0 (with c = 0 that is g rising through 0).

Each phase is linear with constant coefficients and harmonic forcing:
free M x'' + K x = p1 sin(Omega t); contact M x'' + (K + k e e^T) x = -k clearance e + p1 sin.
Both are diagonalised by their own mass-normalised FE modes (from the closed-form flexibility;
the contact flexibility by Sherman-Morrison, F_k = F - k F e e^T F / (1 + k e^T F e), no
cancellation) and propagated in closed form with every FE mode (`fe_reference._Modal`, exact at
resonance). x and x' are continuous at every switch (no projection, no loss): the modal states
map by the orthogonal matrix phi_c^T M phi_f. Events are located on a grid resolving every mode
that matters for g or R, with a cubic-Hermite dip check, and refined by brentq to a few ulps
(`fe_reference._first_negative`). Per contact the impulse is integrated in closed form
(int (q_n - static_n) dt = (b_n int sin(Omega t) dt - [q_n']) / omega_n^2, exact) and the peak
force is refined by brentq on dR/dt = 0.

The time integration is thus exact for the FE system; what is left is the mesh error, O(h^4)
for frequencies (Richardson estimates in tests/test_fe_spring.py). Only c = 0 (no dashpot)
and zeta = 0 are implemented here.

Units: SI (m, s, N, kg, rad/s).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from fe_reference import (
    _XTOL,
    _eig,
    _first_negative,
    _free_phase,
    _grid_step,
    _Modal,
    _Output,
    _Pair,
    static_tip_shape,
    stepped_beam,
)


@dataclass(frozen=True)
class _PointPair(_Pair):
    """The pair with its gap at nodes of the beams, from side s (docs/model.md, "Where the
    contact acts"): g = clearance + s (y1(x1) - y2(x2)), DOFs ``contact1`` and ``contact2``
    (None at a stop); the tip force stays at beam 1's tip (``tip1``)."""

    contact1: int = 0
    contact2: int | None = None
    side: float = 1.0

    def gap_rows(self, matrix: np.ndarray) -> np.ndarray:
        rows = matrix[self.contact1] - (0.0 if self.contact2 is None else matrix[self.contact2])
        return self.side * rows


def _node_dof(position: float, length: float, n_elements: int, offset: int) -> int:
    """The deflection DOF of the node at ``position`` (m), which must be a node of the mesh."""
    node = round(position / length * n_elements)
    assert node > 0 and abs(node * length / n_elements - position) < 1e-12 * length
    return offset + 2 * (node - 1)  # node 0 is the clamp, removed


def build_pair(params, n_elements: tuple[int, int]) -> _Pair:
    """Block-diagonal FE system of both beams (beam 1's DOFs first); beam 1 alone at a stop.

    A contact elsewhere than the tips or from above (``params.contact_position1``,
    ``contact_position2``, ``contact_side``, as in impactbeams' Params; the positions on nodes)
    gives a `_PointPair`, whose gap is at those nodes.

    A stepped beam (``params.segments1``, ``segments2``: objects with ``length``, ``EI``,
    ``rhoA``; each a whole number of elements) has EI and rhoA per element (`stepped_beam`).
    A beam's attachments (``params.attachments1``, ``attachments2``: objects with a
    ``position`` (m) on a node, as `impactbeams.structure`'s parts) sit on that node: a point
    mass (``mass`` kg, ``rotary_inertia`` kg m^2) lumped on its deflection and slope, a spring
    to ground (``stiffness`` N/m, ``rotational_stiffness`` N m/rad) added to K, and to the
    closed-form flexibility by the Woodbury identity (no solve with K).
    """
    p = params
    beams = (1,) if getattr(p, "counterpart", "beam") == "stop" else (1, 2)
    if any(getattr(p, f"segments{beam}", ()) for beam in beams):  # a stepped beam
        pair = _Pair.of_beams([_stepped(p, beam, n_elements[beam - 1]) for beam in beams])
    elif beams == (1,):
        pair = _Pair.single(p.EI1, p.rhoA1, p.l1, n_elements[0])
    else:
        pair = _Pair.build(p.EI1, p.rhoA1, p.l1, p.EI2, p.rhoA2, p.l2, tuple(n_elements))
    K, M = pair.K.copy(), pair.M.copy()
    springs = []  # (DOF, stiffness)
    for beam, offset in ((1, 0), (2, pair.n1)):
        for part in getattr(p, f"attachments{beam}", ()):
            n, length = n_elements[beam - 1], getattr(p, f"l{beam}")
            node = round(part.position / length * n)
            assert node > 0 and abs(node * length / n - part.position) < 1e-12 * length
            w = offset + 2 * (node - 1)  # node 0 is the clamp, removed
            if hasattr(part, "mass"):
                M[w, w] += part.mass
                M[w + 1, w + 1] += part.rotary_inertia
                continue
            springs += [(dof, k) for dof, k in ((w, part.stiffness),
                                                (w + 1, part.rotational_stiffness)) if k]
    F = pair.F
    if springs:
        dofs, k = np.array([s[0] for s in springs]), np.array([s[1] for s in springs])
        K[dofs, dofs] += k
        at = F[:, dofs]
        F = F - at @ np.linalg.solve(np.eye(len(k)) + k[:, None] * F[np.ix_(dofs, dofs)],
                                     k[:, None] * at.T)
    pair = dataclasses.replace(pair, K=K, M=M, F=F)
    x1, x2 = getattr(p, "contact_position1", None), getattr(p, "contact_position2", None)
    side = -1.0 if getattr(p, "contact_side", "below") == "above" else 1.0
    if x1 is None and x2 is None and side == 1.0:
        return pair
    contact1 = _node_dof(p.l1 if x1 is None else x1, p.l1, n_elements[0], 0)
    contact2 = None if pair.tip2 is None else _node_dof(p.l2 if x2 is None else x2, p.l2,
                                                         n_elements[1], pair.n1)
    fields = {f.name: getattr(pair, f.name) for f in dataclasses.fields(_Pair)}
    return _PointPair(**fields, contact1=contact1, contact2=contact2, side=side)


def _stepped(params, beam: int, n_elements: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """K, M, F of beam ``beam``: its ``segments`` (objects with length, EI, rhoA), or uniform."""
    segments = [(s.length, s.EI, s.rhoA) for s in getattr(params, f"segments{beam}", ())]
    return stepped_beam(segments or [tuple(getattr(params, f"{key}{beam}")
                                           for key in ("l", "EI", "rhoA"))], n_elements)


def _gap_vector(pair: _Pair) -> np.ndarray:
    return pair.gap_rows(np.eye(pair.K.shape[0]))


def spring_flexibility(pair: _Pair, k: float) -> np.ndarray:
    """(K + k e e^T)^-1 by Sherman-Morrison on the closed-form flexibility (m/N ...)."""
    e = _gap_vector(pair)
    fe = pair.F @ e
    return pair.F - np.outer(fe, fe) * (k / (1.0 + k * (e @ fe)))


def spring_frequencies(params, k: float, n_modes: int, n_elements: tuple[int, int]) -> np.ndarray:
    """Lowest n_modes FE natural frequencies (rad/s) of the beams with a tip spring k (N/m)."""
    pair = build_pair(params, n_elements)
    return _eig(spring_flexibility(pair, k), pair.M)[0][:n_modes]


@dataclass(frozen=True)
class SpringFE:
    """Modal forms of the free and spring-contact phases of the FE system."""

    pair: _Pair
    k: float
    free: _Modal
    gap: _Output  # g = clearance + r . q_free
    contact: _Modal
    force: _Output  # R = -k g in contact coordinates
    to_contact: np.ndarray  # q_contact = to_contact @ q_free (orthogonal)

    @classmethod
    def build(cls, params, k: float, F0: float, Omega: float, n_elements) -> SpringFE:
        pair = build_pair(params, n_elements)
        free, gap = _free_phase(pair, params.clearance, F0, Omega)
        e = _gap_vector(pair)
        omega_c, phi_c = _eig(spring_flexibility(pair, k), pair.M)
        fe = pair.F @ e
        x_static = fe * (-k * params.clearance / (1.0 + k * (e @ fe)))  # F_k (-k clearance e)
        p1 = -F0 * pair.unit(pair.tip1)
        contact = _Modal(omega_c, phi_c, phi_c.T @ pair.M @ x_static, phi_c.T @ p1, Omega)
        force = _Output(c0=-k * params.clearance, c_sin=0.0, r=-k * (e @ phi_c))
        return cls(pair, k, free, gap, contact, force, phi_c.T @ pair.M @ free.phi)

    def energy(self, in_contact: bool, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Kinetic + bending + k g^2 / 2 (in contact) (J); rows of q, v are time samples.

        Evaluated in the free FE modes (x^T K x = sum omega_f^2 q_f^2), whatever the phase.
        """
        if in_contact:
            qf, vf = q @ self.to_contact, v @ self.to_contact
            g = self.gap.c0 + qf @ self.gap.r
            spring = 0.5 * self.k * g**2
        else:
            qf, vf, spring = q, v, 0.0
        return 0.5 * (np.sum(vf**2, axis=1) + np.sum((self.free.omega * qf) ** 2, axis=1)) + spring


def _impulse(modal: _Modal, out: _Output, t0: float, t1: float, v0, v1) -> float:
    """Exact int_{t0}^{t1} (c0 + r . q) dt for a phase without the c_sin term."""
    w, big_w = modal.omega, modal.forcing_omega
    sin_int = 0.0 if big_w == 0.0 else (np.cos(big_w * t0) - np.cos(big_w * t1)) / big_w
    q_int = modal.static * (t1 - t0) + (modal.b * sin_int - (v1 - v0)) / w**2
    return out.c0 * (t1 - t0) + out.r @ q_int


def _peak(modal: _Modal, out: _Output, t0: float, q0, v0, t1: float, dt: float) -> float:
    """Largest value of the output on [t0, t1] (local maxima refined by brentq on its rate)."""
    n = max(int(np.ceil((t1 - t0) / dt)), 4)
    t = np.linspace(t0, t1, n + 1)
    q, v = modal.propagate(t0, q0, v0, t)
    val, rate = out(modal, t, q), out.rate(modal, t, v)

    def rate_at(s: float) -> float:
        return float(out.rate(modal, s, modal.propagate(t0, q0, v0, [s])[1])[0])

    def value_at(s: float) -> float:
        return float(out(modal, s, modal.propagate(t0, q0, v0, [s])[0])[0])

    best = val.max()
    # Candidate maxima: rate changes sign from + to - between samples, value within 30 % of the
    # sampled maximum (the sampling error of a peak on this grid is far below that).
    for i in np.flatnonzero((rate[:-1] > 0) & (rate[1:] <= 0)):
        if max(val[i], val[i + 1]) < 0.7 * best:
            continue
        s = brentq(rate_at, t[i], t[i + 1], xtol=_XTOL, rtol=4 * np.finfo(float).eps)
        best = max(best, value_at(s))
    return best


def fe_spring_contacts(
    params,
    k: float,
    c: float = 0.0,
    F0: float | None = None,
    Omega: float | None = None,
    t_max: float = 1.0,
    n_elements: tuple[int, int] = (40, 40),
    n_contacts: int | None = 5,
    samples_per_period: float = 8.0,
    mode_rtol: float = 1e-12,
    t_out: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Event-driven exact FE simulation of the spring contact law; the first n_contacts.

    Args:
        params: geometry, clearance, uplifts (and default F0, Omega) as in impactbeams Params.
        k: contact stiffness (N/m). c: dashpot (N s/m); only c = 0 is implemented.
        F0, Omega: forcing (N, rad/s); default params.force_amplitude, params.omega.
        t_max: end time (s). n_elements: elements per beam.
        n_contacts: stop after this many complete contacts (None: run to t_max).
        samples_per_period, mode_rtol: event grid (see fe_reference._grid_step).
        t_out: optional output times (s) for "energy", "gap", "contact_force".

    Returns:
        dict: "onset", "release", "duration", "impulse" (N s, int R dt), "peak" (N),
        "onset_rate" (dg/dt at onset, m/s), "count" (number of onsets by the end), and if
        t_out is given, "t", "energy" (J), "gap" (m), "contact_force" (N) there.
    """
    if c != 0.0:
        raise NotImplementedError("the FE spring reference implements c = 0 only")
    F0 = params.force_amplitude if F0 is None else F0
    Omega = params.omega if Omega is None else Omega
    sys = SpringFE.build(params, k, F0, Omega, n_elements)
    pair = sys.pair
    n1 = pair.n1
    x0 = static_tip_shape(pair.F[:n1, :n1], params.uplift1)
    if pair.tip2 is not None:
        x0 = np.concatenate([x0, static_tip_shape(pair.F[n1:, n1:], params.uplift2)])
    q, v = sys.free.phi.T @ pair.M @ x0, np.zeros(x0.size)
    t0, in_contact, at_zero = 0.0, False, False
    segments = []  # (in_contact, t_start, t_end, q0, v0)
    out = {key: [] for key in ("onset", "release", "impulse", "peak", "onset_rate")}
    while n_contacts is None or len(out["release"]) < n_contacts:
        modal, output = (sys.contact, sys.force) if in_contact else (sys.free, sys.gap)
        dt = _grid_step(modal, output, t0, q, v, samples_per_period, mode_rtol)
        t1 = _first_negative(modal, output, t0, q, v, t_max, dt, starts_at_zero=at_zero)
        t_end = t_max if t1 is None else t1
        segments.append((in_contact, t0, t_end, q, v))
        if t1 is None:
            break
        q1, v1 = (a[0] for a in modal.propagate(t0, q, v, [t1]))
        if in_contact:
            out["release"].append(t1)
            out["impulse"].append(_impulse(modal, output, t0, t1, v, v1))
            out["peak"].append(_peak(modal, output, t0, q, v, t1, dt))
            q, v = sys.to_contact.T @ q1, sys.to_contact.T @ v1
        else:
            out["onset"].append(t1)
            out["onset_rate"].append(float(v1 @ sys.gap.r))
            q, v = sys.to_contact @ q1, sys.to_contact @ v1
        t0, in_contact, at_zero = t1, not in_contact, True
    result = {key: np.array(val) for key, val in out.items()}
    n_done = len(result["release"])
    result["onset"] = result["onset"][: n_done] if n_contacts is not None else result["onset"]
    result["count"] = len(result["onset"])
    result["duration"] = result["release"] - result["onset"][:n_done]
    if t_out is not None:
        t_out = np.asarray(t_out, dtype=float)
        energy, gap, force = (np.full(t_out.shape, np.nan) for _ in range(3))
        for i, (seg_contact, ta, tb, qa, va) in enumerate(segments):
            last = i == len(segments) - 1
            mask = (t_out >= ta) & ((t_out < tb) | (last & (t_out <= tb)))
            if not mask.any():
                continue
            modal = sys.contact if seg_contact else sys.free
            qs, vs = modal.propagate(ta, qa, va, t_out[mask])
            energy[mask] = sys.energy(seg_contact, qs, vs)
            qf = qs @ sys.to_contact if seg_contact else qs
            gap[mask] = sys.gap.c0 + qf @ sys.gap.r
            force[mask] = sys.force(modal, t_out[mask], qs) if seg_contact else 0.0
        result.update(t=t_out, energy=energy, gap=gap, contact_force=force)
    return result


def mesh_deviations(got: dict[str, np.ndarray], coarse: dict[str, np.ndarray],
                    fine: dict[str, np.ndarray]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per quantity of ``got``: its deviation from the ``fine`` mesh's values and the FE's own
    error estimate |fine - coarse|, both relative (onsets to the shortest contact duration)."""
    out = {}
    for key, values in got.items():
        count = values.size
        norm = fine["duration"][:count].min() if key == "onset" else np.abs(fine[key][:count])
        out[key] = (np.abs(values - fine[key][:count]) / norm,
                    np.abs(fine[key][:count] - coarse[key][:count]) / norm)
    return out


@dataclass(frozen=True)
class _ActiveSet:
    """One contact phase of several contacts: the set ``active`` closed, the others open.

    modal: the phase's FE modes (K + sum_a k_a e_a e_a^T, its flexibility by Woodbury on the
    closed-form F); outputs: per contact, its gap c_b + e_b . x if open, its force
    -k_a (c_a + e_a . x) if closed (an event when either falls through 0).
    """

    active: frozenset
    modal: _Modal
    outputs: tuple


def _active_set(pair: _Pair, gaps: np.ndarray, clearances: np.ndarray, stiffnesses: np.ndarray,
                active: frozenset, F0: float, Omega: float) -> _ActiveSet:
    closed = sorted(active)
    E, k, c = gaps[:, closed], stiffnesses[closed], clearances[closed]
    F = pair.F
    if closed:
        FE = F @ E
        F = F - FE @ np.linalg.solve(np.diag(1.0 / k) + E.T @ FE, FE.T)
    x_static = F @ (-(E @ (k * c))) if closed else np.zeros(F.shape[0])
    omega, phi = _eig(F, pair.M)
    p1 = -F0 * pair.unit(pair.tip1)
    modal = _Modal(omega, phi, phi.T @ pair.M @ x_static, phi.T @ p1, Omega)
    outputs = tuple(
        _Output(c0=-stiffnesses[j] * clearances[j], c_sin=0.0,
                r=-stiffnesses[j] * (gaps[:, j] @ phi))
        if j in active else _Output(c0=clearances[j], c_sin=0.0, r=gaps[:, j] @ phi)
        for j in range(gaps.shape[1]))
    return _ActiveSet(active, modal, outputs)


def fe_several_contacts(runs, t_max: float, n_elements: tuple[int, int] = (40, 40),
                        n_events: int = 2, samples_per_period: float = 8.0,
                        mode_rtol: float = 1e-12) -> list[dict]:
    """Event-driven exact FE simulation of several spring contacts (c = 0, zeta = 0).

    ``runs``: each contact as a run of one contact (impactbeams' ``Params.each_contact()``, or
    any objects with its attributes: the geometry, drive and uplifts shared, each its own
    ``contact_position1``/``2``, ``contact_side``, ``clearance``, ``contact_stiffness``). The
    contacts act at FE nodes. Each phase is one active set, with its own FE modes (cached);
    the event is the first root among the open gaps and the closed contacts' forces
    (`fe_reference._first_negative` per output, the earliest). Stops after ``n_events``
    releases or at t_max.

    Returns one dict per contact episode, in order of onset: "contact" (its index), "onset",
    "release" (s; NaN if still closed at t_max), "impulse" (N s), "peak" (N), integrated over
    the phases it spans.
    """
    p = runs[0]
    pairs = [build_pair(run, n_elements) for run in runs]
    pair = pairs[0]
    gaps = np.column_stack([_gap_vector(each) for each in pairs])
    clearances = np.array([run.clearance for run in runs])
    stiffnesses = np.array([run.contact_stiffness for run in runs])
    assert all(run.contact_damping == 0.0 for run in runs) and p.damping_ratio == 0.0
    F0, Omega = p.force_amplitude, p.omega
    phases = {}

    def phase(active: frozenset) -> _ActiveSet:
        if active not in phases:
            phases[active] = _active_set(pair, gaps, clearances, stiffnesses, active, F0, Omega)
        return phases[active]

    n1 = pair.n1
    x = static_tip_shape(pair.F[:n1, :n1], p.uplift1)
    if pair.tip2 is not None:
        x = np.concatenate([x, static_tip_shape(pair.F[n1:, n1:], p.uplift2)])
    v = np.zeros(x.size)
    t0, active, switched = 0.0, frozenset(), None
    episodes, open_episode, releases = [], {}, 0
    while releases < n_events:
        now = phase(active)
        modal = now.modal
        q, qd = modal.phi.T @ pair.M @ x, modal.phi.T @ pair.M @ v
        dt = min(_grid_step(modal, out, t0, q, qd, samples_per_period, mode_rtol)
                 for out in now.outputs)
        times = [_first_negative(modal, out, t0, q, qd, t_max, dt, starts_at_zero=j == switched)
                 for j, out in enumerate(now.outputs)]
        found = [(t, j) for j, t in enumerate(times) if t is not None]
        t1, which = min(found) if found else (t_max, None)
        q1, v1 = (a[0] for a in modal.propagate(t0, q, qd, [t1]))
        for j in active:  # the closed contacts' impulses and peaks over this phase
            out = now.outputs[j]
            open_episode[j]["impulse"] += _impulse(modal, out, t0, t1, qd, v1)
            open_episode[j]["peak"] = max(open_episode[j]["peak"],
                                          _peak(modal, out, t0, q, qd, t1, dt))
        x, v = modal.phi @ q1, modal.phi @ v1
        if which is None:
            break
        if which in active:
            open_episode.pop(which)["release"] = t1
            releases += 1
        else:
            open_episode[which] = {"contact": which, "onset": t1, "release": np.nan,
                                   "impulse": 0.0, "peak": 0.0}
            episodes.append(open_episode[which])
        t0, active, switched = t1, active ^ {which}, which
    return episodes
