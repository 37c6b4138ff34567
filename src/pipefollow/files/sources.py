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


# A line that starts an import of the package, and the statement's continuation lines: parsing
# these few statements instead of whole files makes the code stamp ~10x cheaper (tests hold the
# result equal to a walk of each file's full syntax tree).
_IMPORT_LINE = re.compile(rf"^[ \t]*(?:import|from)[ \t]+{PACKAGE}\b.*$", re.MULTILINE)


def _continues(statement: str) -> bool:
    """Whether an import statement goes on: an open bracket or a trailing backslash (comments aside)."""
    code = re.sub(r"#[^\n]*", "", statement)  # an import holds no strings, so # starts a comment
    return code.count("(") > code.count(")") or code.rstrip().endswith("\\")


def _import_statements(source: str) -> list[str]:
    """The import statements of ``pipefollow`` in ``source``, each dedented."""
    statements = []
    for m in _IMPORT_LINE.finditer(source):
        end = m.end()
        text = m.group(0)
        # a parenthesised or backslash-continued name list goes on over the next lines
        while _continues(text) and end < len(source):
            nxt = source.find("\n", end + 1)
            nxt = len(source) if nxt < 0 else nxt
            text += source[end:nxt]
            end = nxt
        statements.append(text.strip())
    return statements


def _imports_of(module: str) -> set[str]:
    """The ``pipefollow`` modules one module imports, at its top or inside its functions."""
    found: set[str] = set()
    for statement in _import_statements(module_path(module).read_text(encoding="utf-8")):
        try:
            tree = ast.parse(statement)
        except SyntaxError:  # a line of a docstring that only looks like an import
            continue
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


def package_modules() -> tuple[str, ...]:
    """Every module of the package (the code stamp of a result computed by any of it)."""
    names = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        names.append(".".join((PACKAGE, *rel.parts)).removesuffix(".__init__"))
    return tuple(names)


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
