"""MkDocs hooks: serve the math renderer from the site itself, never from a CDN.

MathJax is pinned in package.json / package-lock.json and installed by `npm ci` into
node_modules/; this hook adds its single-file TeX-to-SVG build to the site, so the equations
render without network (the SVG output embeds its glyphs: no font files to fetch).
"""

from pathlib import Path

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

# The "full" build holds every TeX extension, so no extension is loaded lazily (a lazy load
# would be a request for a file the site does not have).
MATHJAX_BUILD = Path("node_modules/mathjax/es5/tex-svg-full.js")
MATHJAX_URI = "javascripts/mathjax/tex-svg-full.js"


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
