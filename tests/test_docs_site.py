"""The built docs site in a real browser: equations rendered offline, no console message.

Checks a site already built by `mkdocs build --strict`, named by the environment variable
IMPACTBEAMS_SITE (.ci/run builds the site, installs Debian's chromium and runs this file with
IMPACTBEAMS_SITE=site); without it the tests are skipped. The site is served on loopback and
each page is loaded by headless Chromium, which writes the page's DOM after its scripts ran,
its console messages and a screenshot into SITE/_screenshots/.
"""

import functools
import html.parser
import http.server
import os
import re
import shutil
import subprocess
import threading
from pathlib import Path

import pytest

SITE = os.environ.get("IMPACTBEAMS_SITE")
pytestmark = pytest.mark.skipif(SITE is None, reason="set IMPACTBEAMS_SITE to a built site")

# Headless flags as this machine needs them: no sandbox as root, and no background network
# (the machine has none: Chromium's own connections would fail and log).
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--hide-scrollbars",
                  "--enable-logging=stderr", "--v=0", "--window-size=1280,2000",
                  # virtual time runs every timer and script to completion (MathJax typesets
                  # asynchronously) before the DOM is written
                  "--virtual-time-budget=20000"]
CONSOLE = re.compile(r":CONSOLE[^\]]*\] (.*)")
# What TeX left untypeset looks like in a page's text: a delimiter or a control word.
RAW_TEX = re.compile(r"\\[()\[\]]|\\[a-zA-Z]+|\$\$")
SPHINX_ROLE = re.compile(r":(meth|class|func|attr|mod|data|exc|obj):")
PAGES = {"model": "model/", "tutorial": "tutorials/fig5-map/", "api": "api/"}


class _Recorder(http.server.SimpleHTTPRequestHandler):
    """Serves the site and records every request's status."""

    statuses: list[tuple[str, int]] = []

    def log_request(self, code="-", size="-"):
        self.statuses.append((self.path, int(code)))

    def log_message(self, format, *args):  # quiet: the statuses are asserted instead
        pass


@pytest.fixture(scope="module")
def served_site():
    site = Path(SITE)
    assert (site / "index.html").is_file(), f"IMPACTBEAMS_SITE={SITE} is not a built site"
    handler = functools.partial(_Recorder, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield site, f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    server.server_close()


class _VisibleText(html.parser.HTMLParser):
    """The text a reader sees as prose: no code, scripts or MathJax's hidden MathML copy."""

    SKIP = {"script", "style", "pre", "code", "mjx-assistive-mml", "svg"}

    def __init__(self):
        super().__init__()
        self.depth, self.parts = 0, []

    def handle_starttag(self, tag, attrs):
        self.depth += tag in self.SKIP

    def handle_endtag(self, tag):
        self.depth -= tag in self.SKIP

    def handle_data(self, data):
        if not self.depth:
            self.parts.append(data)


def visible_text(dom: str) -> str:
    parser = _VisibleText()
    parser.feed(dom)
    return " ".join(parser.parts)


def load(site: Path, url: str, name: str, tmp_path: Path) -> tuple[str, list[str]]:
    """(DOM after the scripts ran, console messages) of one page; saves its screenshot."""
    chromium = shutil.which("chromium")
    assert chromium, "Debian's chromium is not installed (.ci/run installs it)"
    shots = site / "_screenshots"
    shots.mkdir(exist_ok=True)
    done = subprocess.run(
        [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}",
         f"--screenshot={shots / (name + '.png')}", "--dump-dom", url],
        capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout, CONSOLE.findall(done.stderr)


@pytest.mark.parametrize("name", PAGES)
def test_page_renders_its_math_with_no_console_message(served_site, name, tmp_path):
    site, root = served_site
    _Recorder.statuses.clear()
    dom, console = load(site, root + PAGES[name], name, tmp_path)
    assert console == []
    assert [(path, code) for path, code in _Recorder.statuses if code >= 400] == []
    # every equation of the built page (arithmatex's wrapper) is typeset, none in error
    source = (site / PAGES[name] / "index.html").read_text()
    equations = source.count('class="arithmatex"')
    assert dom.count("<mjx-container") == equations
    assert '<g data-mml-node="merror"' not in dom  # a TeX error, typeset in red
    text = visible_text(dom)
    assert RAW_TEX.findall(text) == []
    assert SPHINX_ROLE.findall(text) == []
    if name != "api":
        assert equations > 0, "the check needs a page with equations"
