"""Every code block of the README and of the documentation site runs, as a reader would paste it.

*Python blocks* (```` ```python ````) of README.md and docs/**/*.md (the generated ``REPORT.md`` files
of the result folders aside) run each in a fresh interpreter, in an empty temporary folder, with a
timeout. Two HTML comments on the line just before a block's fence change that, visibly in the
Markdown source and invisibly on the site:

* ``<!-- continues -->``: the block continues the page's previous Python block (it runs after it,
  in the same interpreter, and after the block that one continues, and so on);
* ``<!-- no-run: REASON -->``: the block is not run (a cluster address, say); the reason is shown
  in the skip. Such blocks are counted (:data:`MAX_NO_RUN`): they must stay rare.

A block that imports an optional extra gets that extra's marker and is skipped without it (torch,
Stable-Baselines3, TorchRL, ``pipefollow.training.deep``: ``deep``; Minari: ``rollouts``; TensorBoard:
``tensorboard``); one that needs OpenCV (``cv2``, ``camera="vision"``, the image observation) is
skipped without it (the README's test command installs the extra ``vision``). A training in a block
is kept short (a few thousand steps, the text saying what a real one takes): none needs ``slow``.

*Bash blocks* (```` ```bash ````): every ``pipefollow ...`` command (continuation lines joined, ``&&``
and ``;`` split) names a command that exists and parses with the command's own options, types and
choices (click's parser; a file an earlier command writes need not exist). A cheap subset runs for
real (:func:`_cheap`): ``--help``, ``pipelines``, and ``evaluate`` of a built-in controller on a
built-in or suite pipe (a few seconds each); trainings, reproductions, benchmarks and files of
earlier commands are only parsed.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import click
import pytest

from pipefollow import cli

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md"] + sorted(
    p
    for p in (ROOT / "docs").rglob("*.md")
    if p.name != "REPORT.md"  # REPORT.md: generated results
)
FENCE = re.compile(  # a fence may be indented (in a list item): its code is dedented
    r"^(?P<indent>[ \t]*)```(?P<lang>\w*)[^\n]*\n(?P<code>.*?)^(?P=indent)```[ \t]*$",
    flags=re.DOTALL | re.MULTILINE,
)
DIRECTIVE = re.compile(r"<!--\s*(continues|no-run:\s*(?P<reason>.*?))\s*-->\s*\Z")
MAX_NO_RUN = 3  # blocks that do not run: each justified beside it in the Markdown
TIMEOUT_S = 600

# the optional extras a block may need: (pattern in the code, marker, module that must be importable)
EXTRAS = [
    (
        r"^\s*(import|from)\s+(torch|torchrl|stable_baselines3|pipefollow\.training\.deep)\b",
        "deep",
        ("torch", "stable_baselines3"),
    ),
    (r"^\s*(import|from)\s+torchrl\b", None, ("torchrl",)),
    (r"^\s*(import|from)\s+minari\b", "rollouts", ("minari",)),
    (r"^\s*(import|from)\s+tensorboard\b|tensorboard=", "tensorboard", ("tensorboard",)),
    (r'^\s*(import|from)\s+cv2\b|camera="vision"|observation="image"|PipelineFollowingImage', None, ("cv2",)),
]


@dataclass(frozen=True)
class Block:
    """One fenced block: its page, language, number among the page's blocks, line, code, directive."""

    page: Path
    lang: str
    index: int
    line: int
    code: str
    continues: bool
    no_run: str | None

    @property
    def name(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def _blocks(page: Path, lang: str | None = None) -> list[Block]:
    """The page's fenced blocks of one language (all when None), numbered among those."""
    text = page.read_text(encoding="utf-8")
    found = []
    for m in FENCE.finditer(text):
        if lang is not None and m.group("lang") != lang:
            continue
        before = text[: m.start()].rstrip("\n")
        d = DIRECTIVE.search(before.splitlines()[-1].strip() if before else "")
        found.append(
            Block(
                page=page,
                lang=m.group("lang"),
                index=len(found),
                line=text.count("\n", 0, m.start()) + 1,
                code=textwrap.dedent(m.group("code")),
                continues=bool(d and d.group(1) == "continues"),
                no_run=d.group("reason") if d and d.group("reason") is not None else None,
            )
        )
    return found


BLOCKS = [b for page in PAGES for b in _blocks(page)]
PYTHON = [b for b in BLOCKS if b.lang == "python"]
BASH = [b for b in BLOCKS if b.lang == "bash"]


def _chain(block: Block) -> list[Block]:
    """The block and the blocks it continues (any language: a Python block may continue a bash one)."""
    chain = [block]
    page_blocks = _blocks(block.page)
    while chain[0].continues:
        assert chain[0].index > 0, f"{chain[0].name}: 'continues' on the page's first block"
        chain.insert(0, page_blocks[chain[0].index - 1])
    return chain


def _program(block: Block) -> str:
    """The Python code a block runs: the Python blocks it continues first."""
    return "\n".join(b.code for b in _chain(block) if b.lang == "python")


def _shell(block: Block) -> list[str]:
    """The bash blocks a Python block continues: they run first (a reader's earlier commands)."""
    chain = _chain(block)
    langs = [b.lang for b in chain]
    assert langs == sorted(langs, key=lambda lang: lang != "bash"), f"{block.name}: bash after Python"
    return [b.code for b in chain if b.lang == "bash"]


def _marks(block: Block) -> list:
    code = _program(block) + "\n".join(_shell(block))
    marks = []
    for pattern, marker, modules in EXTRAS:
        if re.search(pattern, code, flags=re.MULTILINE):
            if marker and marker not in {m.name for m in marks}:
                marks.append(getattr(pytest.mark, marker))
            missing = [m for m in modules if importlib.util.find_spec(m) is None]
            if missing:
                marks.append(pytest.mark.skip(reason=f"needs {', '.join(missing)}"))
    if block.no_run is not None:
        marks.append(pytest.mark.skip(reason=f"no-run in the Markdown: {block.no_run}"))
    return marks


def _clean_env(tmp_path: Path) -> dict[str, str]:
    """A reader's environment: the venv's bin first on the PATH, Minari's default root empty."""
    path = f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"
    minari_root = str(tmp_path.parent / f"{tmp_path.name}-minari-home")  # not ~/.minari: tests write no home
    return {**os.environ, "PATH": path, "MINARI_DATASETS_PATH": minari_root, "MPLBACKEND": "Agg"}


# the modules of each extra: a block not marked for an extra runs as if they were not installed, so a
# block that needs an extra without its marker fails here, not only in CI's first stage without extras
EXTRA_MODULES = {"deep": ("torch", "torchrl", "stable_baselines3"), "rollouts": ("minari",),
                 "tensorboard": ("tensorboard",)}  # fmt: skip
ABSENT = """
import sys
class _Absent:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {absent}:
            raise ModuleNotFoundError(f"No module named {{name!r}} (the block lacks the marker of its extra)")
sys.meta_path.insert(0, _Absent())
"""


def _as_without_extras(block: Block) -> str:
    """The block's program, the modules of the extras it is not marked for made absent."""
    marked = {m.mark.name for m in _marks(block)}
    absent = {mod for extra, mods in EXTRA_MODULES.items() if extra not in marked for mod in mods}
    return ABSENT.format(absent=sorted(absent)) + _program(block)


@pytest.mark.parametrize("block", [pytest.param(b, marks=_marks(b), id=b.name) for b in PYTHON])
def test_the_python_block_runs(block, tmp_path):
    for code in _shell(block):
        res = subprocess.run(
            ["bash", "-eu", "-c", code],
            cwd=tmp_path,
            env=_clean_env(tmp_path),
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
        )
        assert res.returncode == 0, f"{block.name}, the bash block it continues:\n{res.stderr[-3000:]}"
    res = subprocess.run(
        [sys.executable, "-c", _as_without_extras(block)],
        cwd=tmp_path,
        env=_clean_env(tmp_path),
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )
    assert res.returncode == 0, f"{block.name}:\n{res.stderr[-3000:]}"


def test_the_pages_have_python_blocks_and_few_skips():
    pages = {b.page.relative_to(ROOT).as_posix() for b in PYTHON}
    assert {"README.md", "docs/index.md", "docs/getting-started.md", "docs/guides/deep-rl.md"} <= pages
    assert sum(b.no_run is not None for b in PYTHON + BASH) <= MAX_NO_RUN


def test_the_directives_are_understood():
    """A misspelt directive would silently run a block alone or run a cluster's block."""
    bad = []
    for page in PAGES:
        for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            line = re.sub(r"`[^`]*`", "", line)  # inline code names the comments, it is none
            if re.search(r"<!--\s*(continue|no-?run)", line) and not DIRECTIVE.search(line.rstrip()):
                bad.append(f"{page.relative_to(ROOT)}:{n}: {line}")
    assert bad == []


def test_a_directive_is_read_only_just_before_its_block(tmp_path):
    page = tmp_path / "p.md"
    page.write_text(
        "```python\na = 1\n```\n<!-- continues -->\n```python\nprint(a)\n```\n"
        "<!-- no-run: needs a cluster -->\n\ntext\n```python\nb = 2\n```\n"
        "<!-- no-run: a cluster -->\n```python\nray.init('ray://x')\n```\n",
        encoding="utf-8",
    )
    blocks = _blocks(page)
    assert [(b.continues, b.no_run) for b in blocks] == [
        (False, None), (True, None), (False, None), (False, "a cluster")
    ]  # fmt: skip
    assert _program(blocks[1]) == "a = 1\n\nprint(a)\n"


# ---------------------------------------------------------------------------------------- bash


def _commands(block: Block) -> list[list[str]]:
    """The ``pipefollow ...`` commands of a bash block, each as its arguments after ``pipefollow``."""
    found = []
    for line in block.code.replace("\\\n", " ").splitlines():
        for part in re.split(r"&&|;|\|", line):
            try:
                words = shlex.split(part, comments=True)
            except ValueError:  # a quote that spans a split point: not a pipefollow command here
                continue
            while words and re.fullmatch(r"\w+=\S*", words[0]):  # VAR=value before the command
                words = words[1:]
            if words[:3] in (["python", "-m", "pipefollow"], [".venv/bin/python", "-m", "pipefollow"]):
                words = ["pipefollow", *words[3:]]
            if words and words[0] in ("pipefollow", ".venv/bin/pipefollow") and len(words) > 1:
                found.append(words[1:])
    return found


COMMANDS = [(b, words) for b in BASH if b.no_run is None for words in _commands(b)]


def _resolve(words: list[str]) -> tuple[click.Command, list[str], str]:
    """The click command the words name, the arguments left for it, and its name."""
    cmd, name = cli.main, "pipefollow"
    while isinstance(cmd, click.Group) and words and not words[0].startswith("-"):
        sub = cmd.get_command(click.Context(cmd), words[0])
        assert sub is not None, f"{name} has no command {words[0]!r}"
        cmd, name, words = sub, f"{name} {words[0]}", words[1:]
    return cmd, words, name


READ_ONLY = ("trials",)  # commands that only read the repository's files: they run in its root


def _cheap(words: list[str]) -> bool:
    """Commands that run for real, in seconds: help, listings, the export of a few suite pipes, and
    an evaluation of a built-in controller on a built-in or suite pipe (its plot or animation too)."""
    if "--help" in words or "-h" in words or words in (["pipelines"], ["suites"]) or words[:1] == ["trials"]:
        return True
    opts = dict(zip(words[1::2], words[2::2], strict=False))
    if words[:2] == ["suites", "export"]:
        return int(opts.get("--pipes", "100")) <= 10
    if words[:1] != ["evaluate"]:
        return False
    return opts.get("--controller", "heuristic") in ("heuristic", "los") and not opts.get(
        "--pipeline", "paper-left"
    ).endswith(".json")


@pytest.mark.parametrize(
    "block, words", [pytest.param(b, w, id=f"{b.name}:{' '.join(w)[:60]}") for b, w in COMMANDS]
)
def test_the_command_and_its_options_exist(block, words):
    error = _parse_error(words)
    assert error is None, f"{block.name}: pipefollow {' '.join(words)}: {error}"


def _parse_error(words: list[str]) -> str | None:
    """Why click rejects ``pipefollow WORDS`` (None: it takes them); files need not exist yet."""
    cmd, args, name = _resolve(words)
    known = {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)} | {"--help", "-h"}
    unknown = [w for w in args if w.startswith("-") and not w[1:2].isdigit() and w.split("=")[0] not in known]
    if unknown:
        return f"{name} has no option {unknown}"
    if "--help" in args or "-h" in args:
        return None
    # click parses the arguments: types, choices, counts; a path an earlier command writes may be missing
    ctx = click.Context(cmd, info_name=name, resilient_parsing=False)
    try:
        with ctx:
            cmd.parse_args(ctx, list(args))
    except click.UsageError as err:
        if not (isinstance(err, click.BadParameter) and "does not exist" in str(err)):
            return err.format_message()
    return None


def test_the_parse_check_tells_bad_commands():
    assert _parse_error(["evaluate", "--controller", "heuristic", "--pipeline", "paper-left"]) is None
    assert _parse_error(["evaluate", "--controller", "runs/none/policy.npz"]) is None  # written earlier
    assert "no option" in _parse_error(["evaluate", "--no-such-option"])
    assert "'nonsense'" in _parse_error(["train", "--algorithm", "nonsense"])
    assert _parse_error(["train", "--episodes", "many"]) is not None
    with pytest.raises(AssertionError, match="no command"):
        _parse_error(["no-such-command"])


def _first_of_each(commands):
    seen, out = set(), []
    for block, words in commands:
        if tuple(words) not in seen:
            seen.add(tuple(words))
            out.append((block, words))
    return out


@pytest.mark.parametrize(
    "block, words",
    [pytest.param(b, w, id=f"{b.name}:{' '.join(w)[:60]}") for b, w in _first_of_each(COMMANDS) if _cheap(w)],
)
def test_the_cheap_commands_run(block, words, tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "pipefollow", *words],
        cwd=ROOT if words[0] in READ_ONLY else tmp_path,
        env=_clean_env(tmp_path),
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )
    assert res.returncode == 0, f"{block.name}: pipefollow {' '.join(words)}\n{res.stderr[-3000:]}"
    assert res.stdout.strip()
    written = [v for o, v in zip(words, words[1:], strict=False) if o in ("--plot", "--animate", "--out")]
    assert [w for w in written if not (tmp_path / w).exists()] == []


def test_the_pages_have_commands_and_some_run():
    assert len(COMMANDS) >= 40
    assert sum(_cheap(w) for _, w in COMMANDS) >= 5


COMPLETION = [
    (b, line.split("#")[0].strip())
    for b in BASH
    for line in b.code.splitlines()
    if "_PIPEFOLLOW_COMPLETE=" in line
]


@pytest.mark.skipif(shutil.which("pipefollow", path=_clean_env(ROOT)["PATH"]) is None, reason="no script")
@pytest.mark.parametrize("block, line", [pytest.param(b, line, id=line[:45]) for b, line in COMPLETION])
def test_the_shell_completion_lines_give_a_script(block, line, tmp_path):
    """The completion lines; the bash one is evaluated in bash, which then completes pipefollow."""
    shell = re.search(r"_PIPEFOLLOW_COMPLETE=(\w+)_source", line).group(1)
    if shell == "bash":
        code = f"{line}\ncomplete -p pipefollow"
    else:  # zsh and fish may not be installed: the script the line feeds to them
        code = line.split("|")[0].removeprefix('eval "$(').removesuffix(')"')
    env = _clean_env(tmp_path)
    res = subprocess.run(["bash", "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert res.returncode == 0, f"{block.name}: {line}\n{res.stderr}"
    assert "_pipefollow_completion" in res.stdout


def test_the_completion_lines_are_found():
    assert {re.search(r"=(\w+)_source", line).group(1) for _, line in COMPLETION} == {"bash", "zsh", "fish"}


def _scripts() -> list[tuple[Block, list[str]]]:
    """The ``python examples/NAME.py ...`` commands of the bash blocks, as the script and its arguments."""
    found = []
    for b in BASH:
        for line in b.code.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            python = words[:1] in (["python"], [".venv/bin/python"])
            if python and words[1:2] and words[1].startswith("examples/"):
                found.append((b, words[1:]))
    return found


# parses the arguments with the script's own parser, then stops: nothing runs
PARSE_ONLY = """
import argparse, runpy, sys
parse = argparse.ArgumentParser.parse_args
def parse_and_stop(self, args=None, namespace=None):
    parse(self, args, namespace)
    print("parsed")
    raise SystemExit(0)
argparse.ArgumentParser.parse_args = parse_and_stop
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
"""


@pytest.mark.parametrize("block, words", [pytest.param(b, w, id=f"{b.name}:{w[0]}") for b, w in _scripts()])
def test_the_example_scripts_take_the_arguments_given(block, words):
    cmd = [sys.executable, "-c", PARSE_ONLY, *words]
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert res.returncode == 0, f"{block.name}:\n{res.stderr[-2000:]}"
    assert res.stdout.strip().endswith("parsed")


def test_the_example_script_commands_are_found():
    assert len(_scripts()) >= 4


TRIALS = [b for page in PAGES for b in _blocks(page, "toml") if "[[trial]]" in b.code]


@pytest.mark.parametrize("block", [pytest.param(b, id=b.name) for b in TRIALS])
def test_the_experiment_files_are_valid(block, tmp_path):
    """An experiment's TOML on a page: ``pipefollow trials`` reads and lists it."""
    (tmp_path / "experiment.toml").write_text(block.code, encoding="utf-8")
    res = subprocess.run(
        [sys.executable, "-m", "pipefollow", "trials", "--experiment", "experiment.toml"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )
    assert res.returncode == 0, f"{block.name}:\n{res.stderr}"
    names = re.findall(r'^name\s*=\s*"([^"]+)"', block.code, flags=re.MULTILINE)
    assert names and all(n in res.stdout for n in names)
