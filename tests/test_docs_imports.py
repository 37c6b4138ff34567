"""Every ``pipefollow`` import written in the README, the docs, the examples and the benchmarks resolves."""

from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = [
    ROOT / "README.md",
    ROOT / "CHANGELOG.md",
    *sorted((ROOT / "docs").rglob("*.md")),
    *sorted((ROOT / "examples").glob("*.py")),
    *sorted((ROOT / "benchmarks").glob("*.py")),
]
FROM = re.compile(r"^\s*from (pipefollow[\w.]*) import \(?([\w, \n]+?)\)?\s*(?:#.*)?$", re.MULTILINE)
IMPORT = re.compile(r"^\s*import (pipefollow[\w.]*)", re.MULTILINE)
MOVED_SECTION = re.compile(r"^## .*$", re.MULTILINE)


def written_imports() -> list[tuple[str, str, str]]:
    """(file, module, name) of every import of pipefollow in the sources ('' for ``import module``)."""
    found = []
    for path in SOURCES:
        if not path.exists():
            continue
        text = path.read_text(encoding="utf-8")
        if path.name == "CHANGELOG.md":  # its old paths are meant to be gone: check only the new ones
            text = "\n".join(line.split("→")[-1] for line in text.splitlines())
        rel = path.relative_to(ROOT).as_posix()
        for m in FROM.finditer(text):
            names = [n.strip().split(" as ")[0] for n in m.group(2).replace("\n", " ").split(",")]
            found += [(rel, m.group(1), n) for n in names if n]
        found += [(rel, m.group(1), "") for m in IMPORT.finditer(text)]
    return found


IMPORTS = written_imports()


def test_the_sources_write_imports_at_all():
    files = {f for f, _, _ in IMPORTS}
    assert "README.md" in files and any(f.startswith("examples/") for f in files)


def is_module(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ImportError:  # a parent is a module, not a package
        return False


def import_or_skip(module: str):
    """The module; a skip where it needs an optional extra that is not installed (its error names it)."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        if "pip install 'pipefollow[" in str(e):
            pytest.skip(str(e))
        raise


@pytest.mark.parametrize(("where", "module", "name"), IMPORTS, ids=[f"{f}:{m}:{n}" for f, m, n in IMPORTS])
def test_a_written_import_resolves(where, module, name):
    mod = import_or_skip(module)
    if name:
        assert hasattr(mod, name) or is_module(f"{module}.{name}"), (
            f"{where}: 'from {module} import {name}' names nothing"
        )


DOTTED = re.compile(r"`(pipefollow(?:\.\w+)+)")


def dotted_names() -> list[tuple[str, str]]:
    """(file, name) of every ``pipefollow.a.b`` name the README and the docs write in backticks."""
    found = []
    for path in SOURCES:
        if path.suffix == ".md" and path.exists() and path.name != "CHANGELOG.md":
            rel = path.relative_to(ROOT).as_posix()
            found += [(rel, n) for n in sorted(set(DOTTED.findall(path.read_text(encoding="utf-8"))))]
    return found


DOTTED_NAMES = dotted_names()


@pytest.mark.parametrize(("where", "name"), DOTTED_NAMES, ids=[f"{f}:{n}" for f, n in DOTTED_NAMES])
def test_a_dotted_name_in_the_docs_exists(where, name):
    parts = name.split(".")
    for i in range(len(parts), 0, -1):  # the longest importable prefix, then attributes
        if not is_module(".".join(parts[:i])):
            continue
        obj = import_or_skip(".".join(parts[:i]))
        for attr in parts[i:]:
            assert hasattr(obj, attr), f"{where}: {name} does not exist"
            obj = getattr(obj, attr)
        return
    pytest.fail(f"{where}: {name} does not exist")
