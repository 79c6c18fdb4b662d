"""Results do not depend on BLAS's thread count (issue 32).

OpenBLAS splits a product among its threads, in an order that follows
``OPENBLAS_NUM_THREADS``: before `impactbeams.blas`, the tied law's overlaps at 40 modes and
the damped spring law's complex modes came out different in the last bits with 2 threads
than with 1, and a run's contacts then differed (1539 against 1686 impacts in 0.3 s of the
tied case below). The same runs in two processes, one BLAS thread against two, must give the
same bits.
"""

import json
import os
import subprocess
import sys

RUNS = """
import hashlib, json
import numpy as np
import impactbeams as ib

def digest(dataset):
    h = hashlib.sha256()
    for name in sorted(dataset.data_vars):
        h.update(np.ascontiguousarray(dataset[name].values).tobytes())
    return h.hexdigest()

cases = {"tied": ib.Params(contact_law="tied"),
         "damped spring": ib.Params(damping_ratio=0.01, contact_damping=0.5)}
print(json.dumps({name: digest(ib.simulate(params, t_max=0.3, n_modes=40, dt_output=1e-3))
                  for name, params in cases.items()}))
"""


def _digests(threads: int) -> dict[str, str]:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": str(threads)}
    result = subprocess.run([sys.executable, "-c", RUNS], env=env, check=True,
                            capture_output=True, text=True)
    return json.loads(result.stdout.splitlines()[-1])


def test_runs_are_bitwise_the_same_on_one_and_on_two_blas_threads():
    assert _digests(2) == _digests(1)


def test_every_result_function_holds_blas_to_one_thread():
    # the functions that build a result with NumPy's or SciPy's products and solvers
    from impactbeams import periodic_orbit, simulate
    from impactbeams.contact.spring import spring_contact
    from impactbeams.contact.tied import build_tied_model
    from impactbeams.orbits.period_map import PeriodMap

    held = [simulate, periodic_orbit, spring_contact, build_tied_model, PeriodMap.__call__,
            PeriodMap.jacobian]
    assert all(getattr(function, "__wrapped__", None) for function in held)


def test_blas_is_one_thread_inside_and_the_users_setting_after():
    from threadpoolctl import threadpool_info, threadpool_limits

    from impactbeams.blas import one_blas_thread

    def blas_threads():
        return {info["filepath"]: info["num_threads"] for info in threadpool_info()
                if info["user_api"] == "blas"}

    with threadpool_limits(limits=2, user_api="blas"):  # the tests' BLAS has one (conftest)
        before = blas_threads()
        inside = one_blas_thread(lambda: one_blas_thread(blas_threads)())()
        after = blas_threads()
    assert set(before.values()) == {2}
    assert set(inside.values()) == {1}
    assert after == before
