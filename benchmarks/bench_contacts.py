"""Benchmark: the cost of several contacts against one (issue 33), by contacts and by modes.

Beam 1 against stops, forced at its tip (F0 = 1 mN, Omega = 400 rad/s, k = 1e4 N/m): one
contact under its tip (the baseline), two (a stop under mid-span, one under the tip) and four
(a two-sided stop at mid-span and one at the tip), each at 8, 16 and 32 modes. Two costs, each
as a ratio against the one-contact run of the same modes measured in the same process, right
before it (a shared machine's load hits both alike):

* a contact evaluation: `impactbeams.first_contact` (each contact's run packed, then the event
  kernel from the same free state, the earliest kept), wall time per call;
* a first-impact map cell: `compute_chunk` of a 48 x 48 map over (Omega, F0), columns along
  F0 (the plan built beforehand: compute only), serial kernel, wall time per cell.

Best of ``--repeats`` (alternating the cases); kernels loaded before timing; BLAS on one
thread. Writes contacts.json to ``--out`` (default docs/benchmarks).

    python benchmarks/bench_contacts.py [--repeats 5] [--out DIR]
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from impactbeams import Contact, Params, first_contact, two_sided_stop  # noqa: E402
from impactbeams.sweep import sweep_from_mapping  # noqa: E402
from impactbeams.sweep.plan import build_plan, compute_chunk  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "benchmarks"
FORCED = {"counterpart": "stop", "force_amplitude": 1e-3, "omega": 400.0,
          "contact_stiffness": 1e4}
MID = 0.05  # m, half beam 1's length
CONTACTS = {  # the contacts of each case, by count
    1: (Contact(clearance=6e-6),),
    2: (Contact(MID, clearance=2e-6), Contact(clearance=6e-6)),
    4: (*two_sided_stop(MID, 2e-6, 3e-6), *two_sided_stop(None, 6e-6, 8e-6)),
}
MODES = (8, 16, 32)
T_MAX = 0.05  # s
GRID = 64  # cells along each axis of the map


def _params(count: int) -> Params:
    return Params(**FORCED, contacts=CONTACTS[count])


def _sweep(count: int, n_modes: int):
    tables = [{name: value for name, value in vars(contact).items() if value is not None}
              for contact in CONTACTS[count]]
    fixed = {key: value for key, value in FORCED.items()
             if key not in ("omega", "force_amplitude")}
    return sweep_from_mapping({"t_max": T_MAX, "n_modes": n_modes,
                               "params": {**fixed, "contacts": tables},
                               "axes": {"omega": {"min": 100.0, "max": 600.0, "num": GRID},
                                        "force_amplitude": {"min": 1e-4, "max": 3e-3,
                                                            "num": GRID}}})


def _seconds(call, *arguments) -> float:
    """Wall time (s) of ``call(*arguments)``."""
    start = time.perf_counter()
    call(*arguments)
    return time.perf_counter() - start


def measure(repeats: int) -> list[dict]:
    """Each (contacts, modes) case's best times, and its ratios to one contact's."""
    cases = {(count, n): {"params": _params(count), "sweep": _sweep(count, n)}
             for count in CONTACTS for n in MODES}
    for case in cases.values():
        case["plan"] = build_plan(case["sweep"])
    best = {key: {"evaluation": float("inf"), "map": float("inf")} for key in cases}
    for round_ in range(repeats + 1):  # the first round loads the kernels: not timed
        for (count, n), case in cases.items():
            evaluation = _seconds(first_contact, case["params"], T_MAX, n)
            chunk = _seconds(compute_chunk, case["sweep"], 0, case["sweep"].size, False,
                             case["plan"])
            if round_ > 0:
                best[count, n]["evaluation"] = min(best[count, n]["evaluation"], evaluation)
                best[count, n]["map"] = min(best[count, n]["map"], chunk)
    rows = []
    for (count, n), times in best.items():
        one = best[1, n]
        cells = cases[count, n]["sweep"].size
        rows.append({"contacts": count, "n_modes": n,
                     "evaluation_s": times["evaluation"],
                     "map_s_per_cell": times["map"] / cells,
                     "evaluation_over_one_contact": times["evaluation"] / one["evaluation"],
                     "map_cell_over_one_contact": times["map"] / one["map"]})
    return rows


def main() -> None:
    from run_all import machine  # run_all imports this module for its page's section

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", default=str(OUT))
    args = parser.parse_args()
    rows = measure(args.repeats)
    report = {"t_max_s": T_MAX, "map_cells": GRID * GRID, "repeats": args.repeats,
              "case": "beam 1 against stops, F0 = 1 mN, Omega = 400 rad/s (maps: 100-600 "
                      "rad/s x 0.1-3 mN), k = 1e4 N/m",
              "contacts": {str(count): [repr(contact) for contact in contacts]
                           for count, contacts in CONTACTS.items()},
              "rows": rows, "load_average": os.getloadavg()[0], **machine()}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "contacts.json").write_text(json.dumps(report, indent=1) + "\n")
    print(section(report))


def section(report: dict, heading: str = "##") -> str:
    """The results as markdown (the benchmarks page's section, `run_all.py`)."""
    lines = [f"{heading} Several contacts", "",
             f"`bench_contacts.py` ({report['date']}; {report['machine']}; load average "
             f"{report['load_average']:.1f} at the end): {report['case']}. A contact "
             "evaluation is `first_contact` (each contact's run packed, the event kernel from "
             "the same free state, the earliest kept); a map cell is a first-impact map's "
             f"compute ({report['map_cells']} cells, columns along F0, one thread, plan "
             "built beforehand). Wall times, best of "
             f"{report['repeats']}; ratios against one contact at the same modes in the same "
             "process.", "",
             "| contacts | modes | evaluation | over 1 contact | map, per cell | over 1 contact |",
             "|---|---|---|---|---|---|"]
    for row in sorted(report["rows"], key=lambda r: (r["n_modes"], r["contacts"])):
        lines.append(f"| {row['contacts']} | {row['n_modes']} | "
                     f"{1e3 * row['evaluation_s']:.2f} ms | "
                     f"{row['evaluation_over_one_contact']:.2f} | "
                     f"{1e9 * row['map_s_per_cell']:.0f} ns | "
                     f"{row['map_cell_over_one_contact']:.2f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
