"""The documentation site (mkdocs.yml): it builds with ``--strict``, and its own pages' code runs.

The build needs the extra ``docs`` and is skipped without it; it writes to a temporary folder,
never into the repository. The Python blocks of the home page and of getting started run each in
a fresh interpreter, as a reader would paste them.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import click
import pytest

from pipefollow import cli

pytestmark = pytest.mark.docs

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES_WITH_CODE = ("index.md", "getting-started.md")
HAS_MKDOCS = all(importlib.util.find_spec(m) is not None for m in ("mkdocs", "mkdocstrings", "mkdocs_click"))


def _blocks(page: str, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", (DOCS / page).read_text(encoding="utf-8"), flags=re.DOTALL)


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


@pytest.mark.parametrize(
    "page, index",
    [(page, i) for page in PAGES_WITH_CODE for i in range(len(_blocks(page, "python")))],
)
def test_the_pages_python_blocks_run(page, index, tmp_path):
    code = _blocks(page, "python")[index]
    res = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert res.returncode == 0, f"{page}, block {index}:\n{res.stderr}"
    assert list(tmp_path.iterdir()) == []  # it writes nothing


def test_the_pages_have_python_blocks():
    assert all(_blocks(page, "python") for page in PAGES_WITH_CODE)


def test_every_option_getting_started_uses_exists():
    lines = "\n".join(_blocks("getting-started.md", "bash")).replace("\\\n", " ").splitlines()
    commands = [shlex.split(line, comments=True) for line in lines]
    commands = [words[1:] for words in commands if words[:1] == ["pipefollow"]]
    assert len(commands) >= 5
    unknown = []
    for words in commands:
        assert words[0] in cli.COMMANDS, words
        cmd = cli.main.get_command(click.Context(cli.main), words[0])
        known = {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)} | {"--help", "-h"}
        unknown += [f"{words[0]} {w}" for w in words if w.startswith("--") and w not in known]
    assert unknown == []
