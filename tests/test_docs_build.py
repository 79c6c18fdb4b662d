"""A docs build writes only into its site folder (issue 32).

Building the docs ran every example in the repository: `results/fig5a.nc`, the main job's
output, was deleted and rewritten, and more files were left in `results/`. The hooks
(scripts/mkdocs_hooks.py) run the examples in a temporary folder that links the repository's
inputs. Here a one-page site with the same hooks and plugin builds in a copy of that layout.
"""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

PAGE = '''# Probe

```python exec="on"
import os
from pathlib import Path

Path("results").mkdir(exist_ok=True)
Path("results/fig5a.nc").write_text("written by an example")
print(f"sweeps-{Path('sweeps/probe.toml').read_text().strip()}")
```

```console exec="on"
$ mkdir -p results && echo shell > results/shell.txt && cat sweeps/probe.toml
```
'''


def test_the_examples_write_nothing_into_the_repository(tmp_path):
    repository = tmp_path / "repository"
    (repository / "docs").mkdir(parents=True)
    (repository / "docs" / "index.md").write_text(PAGE)
    (repository / "sweeps").mkdir()
    (repository / "sweeps" / "probe.toml").write_text("read")
    (repository / "results").mkdir()
    (repository / "results" / "fig5a.nc").write_text("the main job's output")
    mathjax = repository / "node_modules" / "mathjax" / "es5" / "tex-svg-full.js"
    mathjax.parent.mkdir(parents=True)
    mathjax.write_text("// stand-in")
    (repository / "mkdocs.yml").write_text(
        "site_name: probe\ndocs_dir: docs\nstrict: true\n"
        f"hooks:\n  - {ROOT / 'scripts' / 'mkdocs_hooks.py'}\n"
        "plugins:\n  - markdown-exec\n"
        "markdown_extensions:\n  - pymdownx.superfences\n")
    before = {path: path.read_bytes() for path in repository.rglob("*") if path.is_file()}
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "TMPDIR": str(tmp_path)}
    subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q"],
                   cwd=repository, env=env, check=True, capture_output=True, text=True)
    html = (repository / "site" / "index.html").read_text()
    assert "sweeps-read" in html  # the examples ran, reading the repository's inputs
    after = {path: path.read_bytes() for path in repository.rglob("*")
             if path.is_file() and "site" not in path.relative_to(repository).parts}
    assert after == before  # results/ untouched, nothing new
    leftovers = [path for path in tmp_path.iterdir() if path.name != "repository"]
    assert not leftovers  # the examples' folder is removed
