"""The package's layers: every import goes down the table of docs/design.md, never up."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pipefollow

ROOT = Path(pipefollow.__file__).parent
DESIGN = ROOT.parents[1] / "docs" / "design.md"


def layer_table() -> list[str]:
    """The layer folders in the order of docs/design.md's table, bottom first."""
    text = DESIGN.read_text(encoding="utf-8")
    section = text[text.index("## Layers") : text.index("## Units and frames")]
    return re.findall(r"^\| `(\w+)` \|", section, flags=re.MULTILINE)


def imports(path: Path) -> list[tuple[int, str, list[str]]]:
    """(line, module, imported names) of every absolute import of pipefollow in a file."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name, []) for a in node.names if a.name.startswith("pipefollow")]
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("pipefollow"):
            found.append((node.lineno, node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.ImportFrom) and node.level:
            found.append((node.lineno, "<relative>", []))
    return found


def folder_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def test_every_layer_is_a_folder_of_the_design_table():
    layers = layer_table()
    assert layers[:2] == ["files", "sim"] and layers[-1] == "cli"
    folders = {p.name for p in ROOT.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert folders == set(layers)
    loose = {p.name for p in ROOT.glob("*.py")} - {"__init__.py", "__main__.py"}
    assert loose == set(), f"modules outside a layer folder: {sorted(loose)}"
    # `python -m pipefollow` is the command line's entry point and imports nothing else
    assert [m for _, m, _ in imports(ROOT / "__main__.py")] == ["pipefollow.cli"]


def test_no_import_goes_up_a_layer_or_takes_a_private_name_across_folders():
    layers = layer_table()
    rank = {name: i for i, name in enumerate(layers)}
    wrong = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT)
        if len(rel.parts) == 1:  # pipefollow/__init__.py: the version and the registration only
            continue
        own = rel.parts[0]
        for line, module, names in imports(path):
            where = f"{rel}:{line}"
            if module == "<relative>":
                wrong.append(f"{where}: relative import")
                continue
            target = folder_of(module)
            if target is None:  # ``from pipefollow import X``: X a folder, or the version
                up = [n for n in names if rank.get(n, -1) > rank[own]]
                wrong += [f"{where}: {own} imports the higher layer {n}" for n in up]
                continue
            if target not in rank:
                wrong.append(f"{where}: {module} is in no layer")
            elif rank[target] > rank[own]:
                wrong.append(f"{where}: {own} imports the higher layer {target} ({module})")
            elif target != own:
                private = [n for n in names if n.startswith("_")] + [
                    p for p in module.split(".") if p.startswith("_") and p != "__init__"
                ]
                if private:
                    wrong.append(f"{where}: {own} takes the private {private} of {module}")
    assert wrong == []


def test_the_walk_catches_an_upward_and_a_private_import(tmp_path):
    # the checker itself: a sim module importing the environment, and a private name across folders
    bad = tmp_path / "bad.py"
    bad.write_text(
        "from pipefollow.envs.env import PipelineFollowingEnv\nfrom pipefollow.files.atomic import _x\n"
    )
    found = imports(bad)
    assert [(m, n) for _, m, n in found] == [
        ("pipefollow.envs.env", ["PipelineFollowingEnv"]),
        ("pipefollow.files.atomic", ["_x"]),
    ]
    rank = {name: i for i, name in enumerate(layer_table())}
    assert rank[folder_of(found[0][1])] > rank["sim"]


def test_every_package_with_compiled_code_sets_numba_s_cache_before_compiling():
    # numba picks a function's cache folder when it is decorated: the package's __init__ must set it
    for folder in sorted(p for p in ROOT.iterdir() if (p / "__init__.py").exists()):
        texts = [m.read_text(encoding="utf-8") for m in folder.glob("*.py")]
        if any(re.search(r"^@njit\b", text, re.MULTILINE) for text in texts):
            init = (folder / "__init__.py").read_text(encoding="utf-8")
            assert "configure_numba_cache()" in init, folder.name


def test_only_the_command_line_imports_click():
    wrong = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT)
        if rel.parts[0] == "cli":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            if isinstance(node, ast.ImportFrom) and not node.level:
                names = [node.module or ""]
            wrong += [f"{rel}:{node.lineno}: {n}" for n in names if n.split(".")[0] == "click"]
    assert wrong == []
