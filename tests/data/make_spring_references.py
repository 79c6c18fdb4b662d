"""Regenerate tests/data/spring_fig3_fe.json (FE and modal references of the spring law).

Run from the repository root:  OPENBLAS_NUM_THREADS=1 PYTHONPATH=tests python
tests/data/make_spring_references.py   (about 3 minutes on one core).

Fig. 3 case: default beams, F0 = 1 mN, Omega = 50 rad/s, clearance 1.1e-5 m, zero uplifts,
k = 1e4 N/m, c = 0: the first 5 contacts by the exact-in-time FE model (fe_spring.py) at 40, 80
and 160 elements per beam. Reference values: 160 elements. Error estimate of the 160-element
values: the Richardson estimate |f_160 - f_80| / 15 (h^4), and, since the FE's convergence in
these contact quantities is erratic at 40-80 elements, the larger of that and the distance to
the modal reference at 80 modes per beam with static correction (spring_modal_reference.py,
itself converged to ~1e-6: 40 -> 80 modes changes it by <= 5e-6).

Free-vibration case: F0 = 0, uplift1 = 3e-5 m, k = 1e5 N/m, c = 0: contacts of the first
interaction (micro-contacts until the tips stay apart for more than 5 ms) and their total
impulse, FE at 80 and 160 elements, modal at 40 and 80 modes per beam.
"""

import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fe_spring import fe_spring_contacts  # noqa: E402
from impactbeams.params import Params  # noqa: E402
from spring_modal_reference import spring_modal_contacts  # noqa: E402

KEYS = ("onset", "duration", "impulse", "peak")
OUT = Path(__file__).with_name("spring_fig3_fe.json")
SEPARATION = 5e-3  # s: a free flight longer than this ends an interaction


def first_interaction(r) -> int:
    """Number of contacts in the first interaction (gaps between them shorter than 5 ms)."""
    flights = r["onset"][1:] - r["release"][:-1]
    long = np.flatnonzero(flights > SEPARATION)
    return int(long[0] + 1) if long.size else len(r["release"])


def run_fe(params, k, n, **kw):
    t = time.time()
    r = fe_spring_contacts(params, k, n_elements=(n, n), mode_rtol=1e-9, **kw)
    return r, time.time() - t


def run_modal(params, k, n, **kw):
    t = time.time()
    r = spring_modal_contacts(params, n, k, **kw)
    return r, time.time() - t


def table(r, count=None):
    return {key: r[key][:count].tolist() for key in KEYS}


def main():
    data = {"description": __doc__}
    # Fig. 3 case.
    p = Params()
    fe = {n: run_fe(p, 1e4, n, t_max=0.1, n_contacts=5) for n in (40, 80, 160)}
    modal, modal_time = run_modal(p, 1e4, 80, t_max=0.1, n_contacts=5)
    ref = {key: np.asarray(fe[160][0][key]) for key in KEYS}
    richardson = {key: np.abs(ref[key] - fe[80][0][key]) / 15 for key in KEYS}
    to_modal = {key: np.abs(ref[key] - modal[key]) for key in KEYS}
    scale = {"onset": ref["duration"], "duration": ref["duration"], "impulse": ref["impulse"],
             "peak": ref["peak"]}
    data["fig3"] = {
        "params": {"k": 1e4, "c": 0.0, "F0": 1e-3, "Omega": 50.0, "clearance": 1.1e-5,
                   "uplift1": 0.0, "uplift2": 0.0, "beams": "impactbeams Params() defaults"},
        "n_elements": 160,
        "reference": {key: ref[key].tolist() for key in KEYS},
        "error_estimate": {key: np.maximum(richardson[key], to_modal[key]).tolist()
                           for key in KEYS},
        "richardson_error_estimate": {key: richardson[key].tolist() for key in KEYS},
        "relative_error_estimate_note": "onset errors relative to the duration",
        "relative_error_estimate": {
            key: (np.maximum(richardson[key], to_modal[key]) / scale[key]).tolist()
            for key in KEYS},
        "fe_by_mesh": {str(n): table(r) for n, (r, _) in fe.items()},
        "modal_80": table(modal),
        "run_time_s": {**{f"fe_{n}": dt for n, (_, dt) in fe.items()}, "modal_80": modal_time},
    }
    # Free-vibration case.
    q = Params(force_amplitude=0.0, uplift1=3e-5)
    case = {"params": {"k": 1e5, "c": 0.0, "F0": 0.0, "uplift1": 3e-5, "clearance": 1.1e-5},
            "separation_s": SEPARATION}
    for label, (r, dt) in {
        "fe_80": run_fe(q, 1e5, 80, t_max=0.02, n_contacts=None),
        "fe_160": run_fe(q, 1e5, 160, t_max=0.02, n_contacts=None),
        "modal_40": run_modal(q, 1e5, 40, t_max=0.02, n_contacts=None),
        "modal_80": run_modal(q, 1e5, 80, t_max=0.02, n_contacts=None),
    }.items():
        m = first_interaction(r)
        case[label] = {**table(r, m), "count": m,
                       "total_impulse": float(np.sum(r["impulse"][:m])), "run_time_s": dt}
    data["free_vibration_k1e5"] = case
    OUT.write_text(json.dumps(data, indent=1) + "\n")
    print(json.dumps({k: v for k, v in data.items() if k != "description"}, indent=1))


if __name__ == "__main__":
    main()
