"""The documentation site (mkdocs.yml): it builds with ``--strict``, and its own pages' code runs.

The build needs the extra ``docs`` and is skipped without it; it writes to a temporary folder,
never into the repository. The code blocks of every page run in tests/test_docs_snippets.py.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from pipefollow import cli

pytestmark = pytest.mark.docs

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
HAS_MKDOCS = all(importlib.util.find_spec(m) is not None for m in ("mkdocs", "mkdocstrings", "mkdocs_click"))


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built with ``mkdocs build --strict`` into a temporary folder."""
    if not HAS_MKDOCS:
        pytest.skip("needs the extra 'docs' (mkdocs, mkdocstrings, mkdocs-click)")
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}  # Material's banner about MkDocs 2
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(ROOT / "mkdocs.yml")]
    res = subprocess.run(
        [*cmd, "--site-dir", str(out)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600
    )
    assert res.returncode == 0, res.stdout + res.stderr
    return out


def test_the_site_builds_strictly(site):
    for page in ("index.html", "getting-started/index.html", "reference/environment/index.html"):
        assert (site / page).is_file(), page


def test_the_cli_page_has_every_command(site):
    html = (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8")
    missing = [name for name in cli.COMMANDS if f'id="pipefollow-{name}"' not in html]
    assert missing == []


def test_the_reference_pages_show_no_raw_sphinx_roles(site):
    for page in ("environment", "api"):
        html = (site / "reference" / page / "index.html").read_text(encoding="utf-8")
        assert re.search(r":(class|func|mod|data|meth|attr):<code>", html) is None, page
