"""Benchmark: what checkpointing every step costs a continuation (issue 32).

The shipped continuation (sweeps/continuation-stop-fold.toml) followed in one process, warm,
without an output (no checkpoint) and with one (a checkpoint at the top of every step, the
lock, the netCDF file written at the end), ``--rounds`` times each, alternately: the CPU time
per branch point of each, and the wall time of the checkpoints themselves (each call of
`CourseLog`, timed apart). Writes docs/benchmarks/continuation_checkpoint.json, with the load.

    python benchmarks/bench_continuation_checkpoint.py [--rounds 3]
"""

import argparse
import json
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path

from impactbeams.continuation import checkpoint, continue_orbits, load_continuation

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "sweeps" / "continuation-stop-fold.toml"
OUTPUT = ROOT / "docs" / "benchmarks" / "continuation_checkpoint.json"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    continuation = load_continuation(EXAMPLE)
    continue_orbits(continuation)  # compiled, warm
    spent = {"seconds": 0.0, "calls": 0}
    save = checkpoint.CourseLog.__call__

    def timed(log, course):
        start = time.perf_counter()
        save(log, course)
        spent["seconds"] += time.perf_counter() - start
        spent["calls"] += 1

    checkpoint.CourseLog.__call__ = timed
    plain, kept, points, log_bytes = [], [], 0, 0
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "fold.nc"
        for _ in range(args.rounds):
            start = time.process_time()
            points = continue_orbits(continuation).branch_point.size
            plain.append((time.process_time() - start) / points)
            start = time.process_time()
            continue_orbits(continuation, None, out)
            kept.append((time.process_time() - start) / points)
            shutil.rmtree(out.with_name(out.name + ".partial"), ignore_errors=True)
        per_checkpoint, checkpoints = spent["seconds"] / spent["calls"], spent["calls"]
        # the log's size at the end of the branch: a run interrupted at its last point
        last = {"seen": 0}

        def stop(branch, point):
            last["seen"] += 1
            if last["seen"] == points - 1:
                last["bytes"] = sum(path.stat().st_size for path in
                                    out.with_name(out.name + ".partial").glob("course_*"))
                raise KeyboardInterrupt

        out.unlink()
        try:
            continue_orbits(continuation, stop, out)
        except KeyboardInterrupt:
            log_bytes = last.get("bytes", 0)
    result = {"date": time.strftime("%Y-%m-%d %H:%M"),
              "machine": f"{platform.machine()}, {os.cpu_count()} cores",
              "load_average": os.getloadavg()[0],
              "points": int(points), "rounds": args.rounds,
              "cpu_seconds_per_point": min(plain),
              "cpu_seconds_per_point_checkpointed": min(kept),
              "seconds_per_checkpoint": per_checkpoint,
              "checkpoints": checkpoints // args.rounds, "log_bytes": log_bytes}
    OUTPUT.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
