// MathJax configuration for pymdownx.arithmatex (generic mode). MathJax itself (pinned in
// package.json) is served by the site, loaded right after this file, and typesets each page
// when it loads: the site uses full page loads (no navigation.instant), so nothing else is needed.
window.MathJax = {
  tex: {
    inlineMath: [["\\(", "\\)"]],
    displayMath: [["\\[", "\\]"]],
    processEscapes: true,
    processEnvironments: true,
    // an unknown macro is an error, not red text, and every TeX error is logged to the console
    // (tests/test_docs_site.py fails on any console message)
    packages: {"[-]": ["noundefined"]},
    formatError: (jax, error) => {
      console.error("TeX error: " + error.message);
      return jax.formatError(error);
    }
  },
  options: {
    ignoreHtmlClass: ".*|",
    processHtmlClass: "arithmatex"
  }
};
