"""The command line imports a command's module only when it runs; the package imports nothing heavy."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import click
import pytest

from pipefollow import cli

HEAVY = ("numpy", "numba", "gymnasium", "matplotlib", "scipy", "pandas", "torch")


def loaded_after(code: str, env: dict | None = None) -> dict:
    """Run ``code`` in a fresh interpreter; the top-level packages and pipefollow modules it loaded."""
    probe = (
        f"import sys, json\n{code}\n"
        "print(json.dumps({'top': sorted({m.split('.')[0] for m in sys.modules}),"
        " 'pipefollow': sorted(m for m in sys.modules if m.startswith('pipefollow'))}))"
    )
    env = env or os.environ.copy()
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, env=env)
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_cli(args: list[str]) -> str:
    return (
        "from pipefollow.cli import main\n"
        "import contextlib, io\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n"
        f"        main({args!r})\n"
        "    except SystemExit:\n"
        "        pass\n"
    )


@pytest.mark.parametrize("args", [["--help"], ["--version"], []])
def test_help_and_version_import_no_heavy_package_and_no_command(args):
    loaded = loaded_after(run_cli(args))
    assert set(HEAVY).isdisjoint(loaded["top"])
    commands = [m for m in loaded["pipefollow"] if m.startswith("pipefollow.cli.")]
    assert commands == ["pipefollow.cli.group"]


def test_a_command_imports_its_own_module_only():
    loaded = loaded_after(run_cli(["trials", "--help"]))
    assert "pipefollow.cli.experiments" in loaded["pipefollow"]
    others = {"pipefollow.cli.run", "pipefollow.cli.evaluate", "pipefollow.cli.suites"}
    assert others.isdisjoint(loaded["pipefollow"])
    assert {"matplotlib", "scipy", "gymnasium"}.isdisjoint(loaded["top"])


def test_evaluate_help_loads_no_plotting_no_gymnasium_and_no_experiment_runner():
    loaded = loaded_after(run_cli(["evaluate", "--help"]))
    assert {"matplotlib", "gymnasium"}.isdisjoint(loaded["top"])
    assert {"pipefollow.experiments.runner", "pipefollow.experiments.store"}.isdisjoint(loaded["pipefollow"])


def _first_paragraph(command: click.Command) -> str:
    return " ".join(command.help.split("\n\n")[0].split())


@pytest.mark.parametrize("name", sorted(cli.COMMANDS))
def test_every_listed_command_loads_and_its_short_help_is_its_docstring(name):
    command = cli.main.get_command(click.Context(cli.main), name)
    assert isinstance(command, click.Command)
    assert command.name == name
    assert cli.COMMANDS[name][1] == _first_paragraph(command)


def test_help_lists_every_command_with_its_short_help():
    from click.testing import CliRunner

    out = CliRunner().invoke(cli.main, ["--help"], terminal_width=200).output
    for name, (_, short) in cli.COMMANDS.items():
        assert f"{name}  " in out and short[:40] in out


def test_an_unknown_command_is_a_one_line_error():
    from click.testing import CliRunner

    result = CliRunner().invoke(cli.main, ["evalute"])
    assert result.exit_code == 2
    assert "No such command 'evalute'" in result.output


@pytest.mark.parametrize(
    "imports",
    [
        "import gymnasium\nimport pipefollow",  # Gymnasium loaded: the package registers at import
        "import pipefollow.envs\nimport gymnasium",  # the environments register when imported
        "import pipefollow.envs.env\nimport gymnasium",
    ],
)
def test_the_environment_is_registered_by_the_package_after_gymnasium_or_by_its_envs(imports):
    loaded_after(f"{imports}\nassert pipefollow.ENV_ID in gymnasium.registry")


@pytest.mark.slow  # fresh interpreters (≈ 3 s)
def test_gymnasiums_module_form_of_the_id_registers_the_environment_whatever_came_first():
    # the package imported before Gymnasium registers nothing; the module form imports pipefollow.envs
    code = (
        "import pipefollow, gymnasium\n"
        "assert pipefollow.ENV_ID not in gymnasium.registry\n"
        "env = gymnasium.make('pipefollow.envs:' + pipefollow.ENV_ID, episode_seconds=2)\n"
        "assert env.spec.id == pipefollow.ENV_ID\n"
        "env = gymnasium.make(pipefollow.ENV_ID)"
    )
    loaded_after(code)
    loaded_after("import gymnasium\ngymnasium.make('pipefollow:pipefollow/PipelineFollowing-v0')")


def test_importing_a_compiled_module_points_numba_at_the_source_hashed_cache(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    code = (
        "import pipefollow.learners.rbf, numba\n"
        "from pipefollow.files.sources import compiled_modules, source_hash\n"
        "assert numba.config.CACHE_DIR == str(__import__('pathlib').Path("
        f"{str(tmp_path)!r}) / ('numba-' + source_hash(compiled_modules()))), numba.config.CACHE_DIR"
    )
    loaded_after(code, env)


def test_version_is_the_package_attribute_that_pyproject_reads():
    import tomllib
    from pathlib import Path

    from click.testing import CliRunner

    import pipefollow

    data = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" in data["project"]["dynamic"]
    assert data["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "pipefollow.__version__"}
    out = CliRunner().invoke(cli.main, ["--version"]).output
    assert out.strip() == f"pipefollow, version {pipefollow.__version__}"


def test_python_dash_m_pipefollow_is_the_command():
    """``python -m pipefollow`` runs the same command line as the console script."""
    out = subprocess.run(
        [sys.executable, "-m", "pipefollow", "--version"], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip().startswith("pipefollow, version ")
