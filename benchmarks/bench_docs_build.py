"""Time the strict build of the documentation site, which runs every example of docs/.

    python benchmarks/bench_docs_build.py [--output docs/benchmarks/docs_build.json]

Two builds in fresh processes, as a user or CI would run them (``mkdocs build --strict``,
the site into a temporary folder): first with an empty Numba cache (every kind of run the
examples make compiles its kernels), then with the cache that build filled. Writes each
build's wall and CPU time (of the build and the commands it ran), with the machine, the cores
and the load average before and after; scripts/update_readme.py quotes them in the README.
"""

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def build(cache: Path, site: Path) -> dict:
    """One strict build with NUMBA_CACHE_DIR=cache: wall and CPU time (s), load average."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "NO_MKDOCS_2_WARNING": "1"}
    load_before = os.getloadavg()
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
                   cwd=ROOT, env=env, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - used.ru_utime) + (after.ru_stime - used.ru_stime)
    return {"wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
            "load_average_before": [round(x, 2) for x in load_before],
            "load_average_after": [round(x, 2) for x in os.getloadavg()]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", type=Path,
                        default=ROOT / "docs" / "benchmarks" / "docs_build.json")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        cache, site = Path(folder) / "numba-cache", Path(folder) / "site"
        report = {"date": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
                  "machine": platform.machine(), "cores": os.cpu_count(),
                  "python": platform.python_version(),
                  "cold": build(cache, site), "warm": build(cache, site)}
    args.output.write_text(json.dumps(report, indent=1) + "\n")
    print(json.dumps(report))


if __name__ == "__main__":
    main()
