// MathJax configuration for pymdownx.arithmatex (generic mode). MathJax itself (pinned in
// package.json) is served by the site, loaded right after this file, and typesets each page
// when it loads: the site uses full page loads (no navigation.instant), so nothing else is needed.
window.MathJax = {
  tex: {
    inlineMath: [["\\(", "\\)"]],
    displayMath: [["\\[", "\\]"]],
    processEscapes: true,
    processEnvironments: true
  },
  options: {
    ignoreHtmlClass: ".*|",
    processHtmlClass: "arithmatex"
  }
};
