"""Impact episodes: clusters of contacts that make one impact event.

A stiff contact touches, lets go and touches again within one collision of the beams
(micro-contacts). Their number and single forces depend on the contact stiffness; the totals of
the cluster hardly do. The clustering rule: a contact belongs to the episode of the previous
one when the free interval between them (release to onset) is shorter than the episode
separation, by default a quarter period of the slowest free mode of the two beams, the time the
beams' own motion takes to turn around.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.polynomial.legendre import leggauss

from impactbeams.kernels.layout import CONTACT, ROW_FREQUENCY
from impactbeams.packing import Packed
from impactbeams.trajectory.fields import energy_integrals
from impactbeams.trajectory.observables import gap_rate, observables
from impactbeams.trajectory.phases import Trajectory, sample

_PANELS_PER_HALF_PERIOD = 4  # Gauss panels per half period of the fastest mode in contact
_NODES, _WEIGHTS = leggauss(12)


def default_separation(packed: Packed) -> float:
    """A quarter period (s) of the slowest free mode of the two beams."""
    return 0.5 * math.pi / float(np.min(packed.dynamics.free.frequencies))


def episode_labels(onset: np.ndarray, release: np.ndarray, separation: float) -> np.ndarray:
    """Episode number of each contact (onset, release times in s; release NaN if open).

    A contact opens a new episode unless it follows the release before it by less than
    ``separation`` (s).
    """
    if onset.size == 0:
        return np.zeros(0, dtype=int)
    free_interval = onset[1:] - release[:-1]
    return np.concatenate([[0], np.cumsum(~(free_interval < separation))]).astype(int)


def episode_count(onset: Sequence[float], release: Sequence[float], separation: float) -> int:
    """How many episodes the contacts make (`episode_labels`' last label + 1; 0 without any).

    On plain sequences, for a few contacts at a time (a periodic orbit's, at every run).
    """
    return sum(1 for k in range(len(onset)) if k == 0 or not onset[k] - release[k - 1]
               < separation)


def _contact_work(packed: Packed, trajectory: Trajectory, k: int) -> tuple[float, float]:
    """Work of R on the approach (g' < 0) and on the separation (g' > 0) in contact k (J).

    Gauss-Legendre quadrature of R g' split by its sign, on panels of an eighth of the fastest
    contact period: the sign change inside a panel limits it to ~1e-6 relative.
    """
    t0, t1 = trajectory.time[k], trajectory.segment_end[k]
    fastest = max(float(np.max(packed.tables[CONTACT, ROW_FREQUENCY])), packed.params.omega)
    panels = max(4, math.ceil((t1 - t0) * fastest / math.pi * _PANELS_PER_HALF_PERIOD))
    edges = np.linspace(t0, t1, panels + 1)
    half = 0.5 * np.diff(edges)[:, None]
    times = (0.5 * (edges[:-1] + edges[1:])[:, None] + half * _NODES).ravel()
    weights = (half * _WEIGHTS).ravel()
    phase, q, v = sample(packed, trajectory, times)
    phase[:] = CONTACT  # within the contact, also at its closing instant
    obs = observables(packed, phase, times, q, v)
    power = obs["contact_force"] * gap_rate(obs, packed.dynamics.free.side)
    return float(np.sum(weights * np.minimum(power, 0.0))), float(np.sum(weights *
                                                                          np.maximum(power, 0.0)))


def episode_table(packed: Packed, trajectory: Trajectory, impacts: dict[str, np.ndarray],
                  separation: float, energy: bool = True,
                  report: Callable[[float], None] | None = None) -> dict[str, np.ndarray]:
    """Per-episode quantities from the per-contact table ``impacts`` (see the module doc).

    ``energy``: also the dissipated energy and the energetic restitution (quadratures over
    the contacts and the run, costly with many modes; ``report`` as in
    `impactbeams.trajectory.fields.energy_integrals`).
    """
    k = np.flatnonzero(trajectory.phase == CONTACT)
    onset = impacts["impact_onset_time"]
    release = onset + impacts["impact_duration"]
    labels = episode_labels(onset, release, separation)
    count = int(labels[-1]) + 1 if labels.size else 0
    first = np.searchsorted(labels, np.arange(count))
    last = np.searchsorted(labels, np.arange(count), side="right") - 1
    closed = np.isfinite(release[last]) if count else np.zeros(0, dtype=bool)
    table = {
        "episode_onset_time": onset[first],
        "episode_duration": np.where(closed, release[last] - onset[first], np.nan),
        "episode_contact_count": (last - first + 1).astype(np.int32),
        "episode_impulse": np.add.reduceat(impacts["impact_impulse"], first) if count else
        np.empty(0),
        "episode_peak_force": np.maximum.reduceat(impacts["impact_peak_force"], first) if count
        else np.empty(0),
        "episode_restitution": np.where(
            closed, -impacts["separation_velocity"][last] / impacts["impact_velocity"][first],
            np.nan),
    }
    if energy:
        table.update(_episode_energetics(packed, trajectory, k, labels, onset[first],
                                         release[last], closed, report))
    return table


def _episode_energetics(packed: Packed, trajectory: Trajectory, k: np.ndarray,
                        labels: np.ndarray, start: np.ndarray, end: np.ndarray,
                        closed: np.ndarray, report: Callable[[float], None] | None,
                        ) -> dict[str, np.ndarray]:
    """Dissipated energy (J) and energetic restitution of each episode."""
    count = start.size
    approach, separation_work = np.zeros(count), np.zeros(count)
    for j, contact in enumerate(k):
        if contact + 1 < trajectory.time.size:  # released
            compression, restitution = _contact_work(packed, trajectory, contact)
            approach[labels[j]] -= compression
            separation_work[labels[j]] += restitution
    bounds = np.sort(np.concatenate([start, np.where(closed, end, trajectory.t_end)]))
    _, dissipation = energy_integrals(packed, trajectory, bounds, report)
    at = dict(zip(bounds, dissipation, strict=True))
    return {
        "episode_dissipated_energy": np.array(
            [at[e] - at[s] if c else np.nan for s, e, c in zip(start, end, closed,
                                                               strict=True)]),
        "episode_energetic_restitution": np.where(
            closed & (approach > 0), np.sqrt(separation_work / np.where(approach > 0, approach,
                                                                        1.0)), np.nan),
    }
