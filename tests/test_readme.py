"""The commands of the README and its guides (docs/guides/): what they write is ignored by git (that
they exist and parse: tests/test_docs_snippets.py)."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs" / "guides").glob("*.md"))]
README = "\n".join(page.read_text(encoding="utf-8") for page in PAGES)
OUTPUT_OPTIONS = ("--out", "--plot", "--animate")


def _commands() -> list[list[str]]:
    """Every ``pipefollow ...`` line of the README's and the guides' bash blocks (continuations joined)."""
    blocks = re.findall(r"```bash\n(.*?)```", README, flags=re.DOTALL)
    lines = "\n".join(blocks).replace("\\\n", " ").splitlines()
    found = []
    for line in lines:
        for part in line.split("&&"):
            words = shlex.split(part, comments=True)
            if words and words[0].endswith("pipefollow"):
                found.append(words[1:])
    return found


def _outputs() -> list[str]:
    out = []
    for words in _commands():
        for opt, value in zip(words, words[1:], strict=False):
            if opt in OUTPUT_OPTIONS:
                out.append(value)
        if words[:1] == ["reproduce"] and "--out" not in words:
            out.append("reproduction-quick" if "--quick" in words else "reproduction")
    return out


def test_the_readme_has_commands_that_write_files():
    assert len(_outputs()) >= 8


@pytest.mark.skipif(shutil.which("git") is None or not (ROOT / ".git").exists(), reason="not a git checkout")
@pytest.mark.parametrize("path", sorted(set(_outputs())))
def test_what_the_readme_commands_write_is_ignored_by_git(path):
    probe = path.rstrip("/") + ("/x" if not Path(path).suffix else "")
    res = subprocess.run(["git", "check-ignore", "-q", probe], cwd=ROOT)
    assert res.returncode == 0, f"{path} is not in .gitignore"
