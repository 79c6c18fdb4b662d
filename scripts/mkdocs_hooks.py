"""MkDocs hooks: the math renderer served by the site itself, the examples run apart.

MathJax is pinned in package.json / package-lock.json and installed by `npm ci` into
node_modules/; `on_files` adds its single-file TeX-to-SVG build to the site, so the equations
render without network (the SVG output embeds its glyphs: no font files to fetch).

The pages' examples (markdown-exec) write their outputs where they say, `results/...`, relative
to the folder they run in: building the docs in the repository rewrote `results/fig5a.nc`, the
main job's output, and left more files there (issue 32). They run in a temporary folder
instead (`on_pre_build`), which sees the repository's inputs through links (`EXAMPLE_INPUTS`)
and is removed after the build (`on_post_build`, `on_build_error`): a docs build writes only
into its site folder.
"""

import os
import shutil
import tempfile
from pathlib import Path

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

# The "full" build holds every TeX extension, so no extension is loaded lazily (a lazy load
# would be a request for a file the site does not have).
MATHJAX_BUILD = Path("node_modules/mathjax/es5/tex-svg-full.js")
MATHJAX_URI = "javascripts/mathjax/tex-svg-full.js"
# What the examples (and the API reference, `paths: [src]`) read from the repository: sweep
# files, results files, figures' data, the benchmarks' pages, the sources; linked into the
# examples' folder, where everything they write stays.
EXAMPLE_INPUTS = ("sweeps", "docs", "benchmarks", "scripts", "src")

_examples: list[tuple[str, str]] = []  # (the examples' folder, the folder the build started in)


def on_files(files: Files, config: MkDocsConfig) -> Files:
    """Add the pinned MathJax build from node_modules/ to the site's files."""
    source = Path(config.config_file_path).parent / MATHJAX_BUILD
    if not source.is_file():
        raise PluginError(
            f"the math renderer {MATHJAX_BUILD} is missing: run `npm ci` in the repository "
            "(package.json pins MathJax) before building the docs"
        )
    files.append(File.generated(config, MATHJAX_URI, abs_src_path=str(source)))
    return files


def on_pre_build(config: MkDocsConfig) -> None:
    """Run the examples in a new temporary folder that links the repository's inputs."""
    repository = Path(config.config_file_path).resolve().parent
    folder = tempfile.mkdtemp(prefix="impactbeams-docs-examples-")
    for name in EXAMPLE_INPUTS:
        if (repository / name).exists():
            os.symlink(repository / name, Path(folder) / name)
    _examples.append((folder, os.getcwd()))
    os.chdir(folder)


def on_post_build(config: MkDocsConfig) -> None:
    """Back to the folder the build started in; the examples' outputs are removed."""
    while _examples:
        folder, started_in = _examples.pop()
        os.chdir(started_in)
        shutil.rmtree(folder, ignore_errors=True)


def on_build_error(error: Exception) -> None:
    """As after a build: a failed example leaves nothing behind either."""
    on_post_build(None)  # type: ignore[arg-type]
