"""The package's own source files: which modules a module imports, and hashes of their code.

Two stamps are derived from the code itself rather than from hand-kept lists: the code stamp of
a run folder (the modules whose code decides a trial's numbers, found by walking the imports of
:mod:`pipefollow.experiments.trial`) and the key of numba's on-disk cache (the modules that hold
compiled code, so that editing the command line or the report recompiles nothing).
"""

from __future__ import annotations

import ast
import hashlib
import re
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent  # the pipefollow package folder
PACKAGE = "pipefollow"


def module_path(module: str) -> Path:
    """The source file of a ``pipefollow`` module (``pipefollow.sim.decision`` → ``sim/decision.py``)."""
    parts = module.split(".")[1:]
    base = ROOT.joinpath(*parts) if parts else ROOT
    return base / "__init__.py" if base.is_dir() else base.with_suffix(".py")


def _imports_of(module: str) -> set[str]:
    """The ``pipefollow`` modules one module imports, at its top or inside its functions."""
    tree = ast.parse(module_path(module).read_text(encoding="utf-8"))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            # ``from pipefollow.sim import decision`` imports the module pipefollow.sim.decision
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        for name in names:
            if name.split(".")[0] == PACKAGE and module_path(name).is_file():
                found.add(name)
    # importing a module runs the __init__ of each package above it
    for name in list(found):
        parts = name.split(".")
        found.update(".".join(parts[:i]) for i in range(1, len(parts)))
    found.discard(module)
    return found


@cache
def imported_modules(module: str) -> tuple[str, ...]:
    """Every ``pipefollow`` module that importing ``module`` and calling its functions can import."""
    seen = {module}
    todo = [module]
    while todo:
        for name in _imports_of(todo.pop()):
            if name not in seen:
                seen.add(name)
                todo.append(name)
    return tuple(sorted(seen))


def compiled_modules() -> tuple[str, ...]:
    """The modules that define numba-compiled functions."""
    names = []
    for path in sorted(ROOT.rglob("*.py")):
        if re.search(r"^@njit\b", path.read_text(encoding="utf-8"), re.MULTILINE):
            rel = path.relative_to(ROOT).with_suffix("")
            names.append(".".join((PACKAGE, *rel.parts)).removesuffix(".__init__"))
    return tuple(names)


@cache
def source_hash(modules: tuple[str, ...]) -> str:
    """A short hash of the named modules' source files (their paths and bytes)."""
    digest = hashlib.sha1()
    for name in sorted(modules):
        path = module_path(name)
        digest.update(path.relative_to(ROOT).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]
