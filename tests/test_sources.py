"""The import walk behind the code stamp (``files.sources``), against each file's full syntax tree."""

from __future__ import annotations

import ast

import pytest

from pipefollow.files import sources


def _imports_by_syntax_tree(source: str) -> set[str]:
    """The independent answer: every absolute import of ``pipefollow`` in the whole syntax tree."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "pipefollow")
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module.startswith("pipefollow"):
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
    return found


def _imports_by_statements(source: str) -> set[str]:
    found = set()
    for statement in sources._import_statements(source):
        try:
            tree = ast.parse(statement)
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                found.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                found.add(node.module)
                found.update(f"{node.module}.{a.name}" for a in node.names)
    return found


TRICKY = '''"""A docstring that mentions
from pipefollow the package, and
import pipefollow.sim.decision as an example.
"""
import numpy as np
from pipefollow.sim import (
    camera,
    reward,  # a comment ) with a bracket
)
from pipefollow.learners.rbf import \\
    RBFGrid


def f():
    if True:
        from pipefollow.training import compiled as c, phases
        import pipefollow.evaluation.stats
    return "from pipefollow.cli import nothing"
'''


def test_the_statements_of_a_tricky_file_name_what_its_syntax_tree_names():
    expected = {
        "pipefollow.sim",
        "pipefollow.sim.camera",
        "pipefollow.sim.reward",
        "pipefollow.learners.rbf",
        "pipefollow.learners.rbf.RBFGrid",
        "pipefollow.training",
        "pipefollow.training.compiled",
        "pipefollow.training.phases",
        "pipefollow.evaluation.stats",
    }
    assert _imports_by_syntax_tree(TRICKY) == expected
    # the docstring's look-alike line parses as an import: a superset at worst, never a miss
    assert expected <= _imports_by_statements(TRICKY) <= expected | {"pipefollow.sim.decision"}


MODULES = [
    ".".join(("pipefollow", *p.relative_to(sources.ROOT).with_suffix("").parts)).removesuffix(".__init__")
    for p in sorted(sources.ROOT.rglob("*.py"))
]


@pytest.mark.parametrize("module", MODULES)
def test_every_module_of_the_package_imports_what_its_syntax_tree_says(module):
    text = sources.module_path(module).read_text(encoding="utf-8")
    expected = {n for n in _imports_by_syntax_tree(text) if sources.module_path(n).is_file()}
    for name in list(expected):
        parts = name.split(".")
        expected.update(".".join(parts[:i]) for i in range(1, len(parts)))
    expected.discard(module)
    assert sources._imports_of(module) == expected


def test_the_walk_follows_imports_to_the_modules_a_trial_runs():
    walked = set(sources.imported_modules("pipefollow.experiments.trial"))
    assert {"pipefollow.sim.decision", "pipefollow.learners.cacla", "pipefollow.training.phases"} <= walked
    assert not any(m.startswith("pipefollow.cli") for m in walked)
