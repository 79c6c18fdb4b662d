"""Independent Lyapunov estimates from the nonlinear run alone, for the tangent method's tests.

No tangent dynamics here: a perturbed copy of the run is integrated by the event kernel
(``run_events``) and compared with the recorded reference run, whose states at any time come
in closed form from its segments (``sample_states``, in the free coordinates (q, q')).

* :func:`two_trajectory_exponent`: Benettin's two-trajectory estimate. Every ``step`` s the
  perturbed state is put back at distance ``d0`` from the reference along the current
  difference, and the log of the growth of the distance is summed.
* :func:`flow_map_jacobian`: the Jacobian of the flow map between two times by central
  differences of the nonlinear run.

Distances use the energy norm of the free modes, sum omega_n^2 dq_n^2 + dq_n'^2, as the tangent
kernel does (the exponent does not depend on the norm; finite-time estimates do a little).
"""

import math

import numpy as np

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.contact_spring import to_contact, to_free
from impactbeams.kernels.events import event_value, phase_event_function
from impactbeams.kernels.layout import CONTACT, FREE, ROW_FREQUENCY
from impactbeams.kernels.records import SWITCH_DRIVES, SWITCH_SPRING, segments

_CAPACITY = 4096  # segments of one perturbed step, doubled as needed


def energy_norm(packed, dq, dv):
    omega = packed.tables[FREE, ROW_FREQUENCY]
    return math.sqrt(float(np.sum((omega * dq) ** 2 + dv**2)))


def reference_states(packed, trajectory, times):
    """Free coordinates (q, q') of the recorded run at ascending ``times`` (s)."""
    n = trajectory.q.shape[1]
    q, v = np.empty((times.size, n)), np.empty((times.size, n))
    phase = np.empty(times.size, dtype=np.int64)
    dyn.sample_states(packed.tables, packed.forces, packed.switching, packed.settings,
                      trajectory.segments, times, q, v, phase)
    return q, v


def _phase_state(packed, q, v, t):
    """Phase of the physical state (q, q') at t and the state in that phase's coordinates.

    In contact iff the tips overlap (g < 0) and the law's force -k_e g - c_e g' pushes.
    """
    s = packed.settings
    scalars = packed.phase_scalars[FREE]
    gap, gap_rate = event_value(q, v, t, phase_event_function(packed.tables[FREE], scalars,
                                                              s["forcing_frequency"]))
    force = -s["contact_stiffness"] * gap - s["contact_damping"] * gap_rate
    if not (gap < 0.0 and force > 0.0):
        return FREE, q, v
    left, _, modes = packed.switching[SWITCH_SPRING]
    y, y_rate = np.empty_like(q), np.empty_like(v)
    to_contact(q, v, t, left, modes, packed.switching[SWITCH_DRIVES], s["forcing_frequency"], y,
               y_rate)
    return CONTACT, y, y_rate


def run_from(packed, q, v, t0, t1):
    """Nonlinear run from the free-coordinate state (q, q') at t0 to t1 (s): its state at t1."""
    settings = packed.settings.copy()
    settings["t_max"] = t1
    phase, q0, v0 = _phase_state(packed, q, v, t0)
    capacity = _CAPACITY
    while True:
        buffers = segments(capacity, q.size)
        count, status, _ = dyn.run_events(packed.tables, packed.forces, packed.phase_scalars,
                                          packed.switching, settings, q0, v0, buffers, t0,
                                          phase)
        if status != dyn.EVENT_LIMIT:
            break
        capacity *= 2
    assert status == dyn.COMPLETE
    seg_phase, end_q, end_v = buffers.phase, buffers.end_q, buffers.end_v
    q_end, v_end = end_q[count - 1].copy(), end_v[count - 1].copy()
    if seg_phase[count - 1] == CONTACT:
        _, right, modes = packed.switching[SWITCH_SPRING]
        y, y_rate = q_end.copy(), v_end.copy()
        to_free(y, y_rate, t1, right, modes, packed.switching[SWITCH_DRIVES],
                settings["forcing_frequency"], q_end, v_end)
    return q_end, v_end


def two_trajectory_exponent(packed, trajectory, step, t_start, t_stop, relative_distance,
                            batches=16, seed=1):
    """Benettin's two-trajectory estimate of the largest exponent (1/s) over [t_start, t_stop].

    The perturbation starts at t = 0 in a random direction; its growth is counted from
    t_start on. ``relative_distance``: d0 over the reference state's energy norm at t = 0.
    Returns ``(exponent, standard error from batch means)``.
    """
    count = int(round(t_stop / step))
    times = np.arange(count + 1) * step
    ref_q, ref_v = reference_states(packed, trajectory, times)
    rng = np.random.default_rng(seed)
    d0 = relative_distance * energy_norm(packed, ref_q[0], ref_v[0])
    dq, dv = rng.standard_normal(ref_q.shape[1]), rng.standard_normal(ref_q.shape[1])
    logs = []
    for i in range(count):
        scale = d0 / energy_norm(packed, dq, dv)
        q, v = run_from(packed, ref_q[i] + scale * dq, ref_v[i] + scale * dv, times[i],
                        times[i + 1])
        dq, dv = q - ref_q[i + 1], v - ref_v[i + 1]
        if times[i] >= t_start - 0.5 * step:
            logs.append(math.log(energy_norm(packed, dq, dv) / d0))
    logs = np.array(logs) / step
    means = np.array([chunk.mean() for chunk in np.array_split(logs, batches)])
    return float(logs.mean()), float(means.std(ddof=1) / math.sqrt(batches))


def flow_map_jacobian(packed, trajectory, t0, t1, relative_step):
    """Jacobian (4n x 4n, in (q, q')) of the flow map from t0 to t1 by central differences.

    Each coordinate is perturbed by ``relative_step`` times the state's typical size in it
    (the energy norm over omega_n for q_n, over 1 for q_n').
    """
    q_ref, v_ref = reference_states(packed, trajectory, np.array([t0]))
    x_ref = np.concatenate([q_ref[0], v_ref[0]])
    n = q_ref.shape[1]
    omega = packed.tables[FREE, ROW_FREQUENCY]
    size = energy_norm(packed, q_ref[0], v_ref[0])
    steps = relative_step * size * np.concatenate([1.0 / omega, np.ones(n)])
    jacobian = np.empty((2 * n, 2 * n))
    for j in range(2 * n):
        ends = []
        for sign in (1.0, -1.0):
            x = x_ref.copy()
            x[j] += sign * steps[j]
            ends.append(np.concatenate(run_from(packed, x[:n], x[n:], t0, t1)))
        jacobian[:, j] = (ends[0] - ends[1]) / (2.0 * steps[j])
    return jacobian
