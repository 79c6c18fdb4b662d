"""A newcomer's first hour, scripted: the README's main job, then the getting-started tasks.

    python scripts/newcomer.py [--output FILE.json]

Runs, in a new temporary folder and with an empty Numba cache (as on a fresh install), the
`impactbeams` commands of the README's main job and of the three tasks of
docs/getting-started.md (natural frequencies, the first map, the first trajectory), read from
those files, not copied here. For each command it prints the compile announced (the range the
command states for this machine) beside the compile it then reports, with the wall time of
the whole command. A command that fails stops the script (exit 1); an actual compile outside
its announced range is printed as such. CI runs it (`.ci/run`); ``--output`` writes the table
as JSON, with the machine and load.
"""

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# the tasks of docs/getting-started.md, by their section titles
TASKS = ("First look: natural frequencies", "First map", "First trajectory")
ANNOUNCED = re.compile(r"compiling the kernels of this kind of run .*?expected (\d+)-(\d+) s "
                       r"here \((.*?); measured")
ACTUAL = re.compile(r"compiled (\d+) kernels in ([\d.]+) s")


def readme_commands() -> list[str]:
    """The `impactbeams` steps of the README's main job (after its install steps)."""
    readme = (ROOT / "README.md").read_text()
    job = next(block for block in re.findall(r"```bash\n(.*?)```", readme, re.S)
               if "impactbeams run" in block and block.startswith("python3 -m venv"))
    return [step.strip() for step in job.split("&&") if step.strip().startswith("impactbeams")]


def task_commands() -> list[tuple[str, str, int]]:
    """(task, command, exit code the page expects) of the getting-started tasks' transcripts."""
    page = (ROOT / "docs" / "getting-started.md").read_text()
    commands = []
    for task in TASKS:
        section = page.split(f"\n## {task}\n", 1)[1].split("\n## ", 1)[0]
        for options, body in re.findall(r"```console([^\n]*)\n(.*?)```", section, re.S):
            code = re.search(r'returncode="(\d+)"', options)
            commands += [(task, line[2:].strip(), int(code[1]) if code else 0)
                         for line in body.splitlines() if line.startswith("$ impactbeams")]
    return commands


def run(command: str, folder: Path, env: dict) -> dict:
    """Run ``command`` in ``folder``: its exit code, wall time and compile lines."""
    start = time.perf_counter()
    result = subprocess.run(shlex.split(command), cwd=folder, env=env, capture_output=True,
                            text=True)
    wall = time.perf_counter() - start
    announced, actual = ANNOUNCED.search(result.stderr), ACTUAL.findall(result.stderr)
    return {"command": command, "exit": result.returncode, "wall_s": round(wall, 1),
            "announced_s": [int(announced[1]), int(announced[2])] if announced else None,
            "machine": announced[3] if announced else None,
            "compiled_s": float(actual[-1][1]) if actual else None,
            "stderr": result.stderr}


def main() -> int:
    """Run every step; 1 if a command exits otherwise than its page says."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", type=Path, help="write the table as JSON")
    args = parser.parse_args()
    steps = ([("README, main job", command, 0) for command in readme_commands()]
             + task_commands())
    rows = []
    with tempfile.TemporaryDirectory(prefix="impactbeams-newcomer-") as folder:
        work = Path(folder)
        (work / "sweeps").symlink_to(ROOT / "sweeps")
        env = {**os.environ, "NUMBA_CACHE_DIR": str(work / "numba-cache")}
        print(f"{'step':<32} {'command':<62} {'announced':>10} {'compiled':>9} {'wall':>7}")
        for task, command, expected_exit in steps:
            row = {"task": task, **run(command, work, env)}
            rows.append(row)
            low_high = row["announced_s"]
            announced = "-" if low_high is None else f"{low_high[0]}-{low_high[1]} s"
            compiled = "-" if row["compiled_s"] is None else f"{row['compiled_s']:.1f} s"
            outside = (low_high is not None and row["compiled_s"] is not None
                       and not low_high[0] <= row["compiled_s"] <= low_high[1])
            print(f"{task:<32} {command[:62]:<62} {announced:>10} {compiled:>9} "
                  f"{row['wall_s']:>5.1f} s" + ("  (outside the announced range)" if outside
                                                else ""), flush=True)
            if row["exit"] != expected_exit:
                print(f"newcomer: `{command}` exited {row['exit']}:\n{row['stderr']}",
                      file=sys.stderr)
                return 1
    print(f"machine: {os.uname().machine}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f} at the end")
    if args.output:
        report = {"date": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
                  "machine": os.uname().machine, "cores": os.cpu_count(),
                  "load_average_end": round(os.getloadavg()[0], 2),
                  "steps": [{k: v for k, v in row.items() if k != "stderr"} for row in rows]}
        args.output.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
