"""MkDocs hooks of the documentation site (mkdocs.yml ``hooks``): keep the built site free of network fetches.

nbconvert's page template, which mkdocs-jupyter renders the notebooks with, loads MathJax and mermaid from a CDN.
The notebooks use neither (no math, no diagrams), so both loaders are cut out of the notebook pages. When the
template changes and a loader is not found, the build warns, and the strict build fails: the test suite notices
before a page starts fetching from the network.
"""

from __future__ import annotations

import logging
import re
from typing import Any

log = logging.getLogger("mkdocs.hooks.ur3hanoi")

LOADERS = {
    "MathJax": re.compile(r"<!-- Load mathjax -->.*?<!-- End of mathjax configuration -->", re.S),
    "mermaid": re.compile(r"<script type=\"module\">(?:(?!</script>).)*?mermaid.*?"
                          r"<!-- End of mermaid configuration -->", re.S),
}


def on_post_page(output: str, page: Any, config: Any) -> str:
    """Cut the CDN loaders out of a notebook page."""
    if not page.file.src_uri.endswith(".ipynb"):
        return output
    for name, pattern in LOADERS.items():
        output, count = pattern.subn("", output)
        if count != 1:
            log.warning("%s: expected one %s loader of nbconvert's template to remove, found %d",
                        page.file.src_uri, name, count)
    return output
