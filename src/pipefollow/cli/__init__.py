"""The ``pipefollow`` command line: the group in :mod:`.group`, the commands by subject.

Each command wires options to the library; the work is done in the modules it calls. A command
is known by name in :data:`COMMANDS` and its module is imported only when it runs, so that
``pipefollow --help`` imports click alone. To add one: write it with ``@click.command()`` (or
``@click.group()``) in a module of this folder and add a row here; ``tests/test_cli_lazy.py``
checks that the row's short help is the first paragraph of the command's docstring.
"""

from pipefollow.cli.group import main

# name → ("module:attribute", short help shown by ``pipefollow --help``)
COMMANDS: dict[str, tuple[str, str]] = {
    "benchmark": (
        "pipefollow.cli.suites:benchmark",
        "Run a controller deterministically on every pipe of a suite, beside the heuristic.",
    ),
    "compare": (
        "pipefollow.cli.compare:compare",
        "Compare learners over training seeds × pipes: IQM, mean, probability of improvement.",
    ),
    "docs": (
        "pipefollow.cli.docs:docs",
        "The documentation site's generated pages: results pages rendered from the stored outputs.",
    ),
    "evaluate": (
        "pipefollow.cli.evaluate:evaluate",
        "Evaluate a controller deterministically (σ = 0) on a pipeline.",
    ),
    "pipelines": ("pipefollow.cli.suites:pipelines", "List the named pipelines."),
    "plot": (
        "pipefollow.cli.experiments:plot",
        "Redraw all figures and REPORT.md of a run folder from its stored results.",
    ),
    "reproduce": (
        "pipefollow.cli.experiments:reproduce",
        "Reproduce the paper's experiments: train every trial × seed, store results, draw the figures.",
    ),
    "robustness": (
        "pipefollow.cli.robustness:robustness",
        "Success rate and mean return against current speed, and on fixed scenario sets.",
    ),
    "rollouts": (
        "pipefollow.cli.rollouts:rollouts",
        "Write a controller's episodes on a suite as a Minari dataset (offline RL, behaviour cloning).",
    ),
    "suites": (
        "pipefollow.cli.suites:suites",
        "List the pipeline suites: training families and held-out test suites.",
    ),
    "train": ("pipefollow.cli.run:train", "Train a learner; writes the policy and its learning curve."),
    "trials": ("pipefollow.cli.experiments:trials", "List the trials of an experiment."),
    "vision": (
        "pipefollow.cli.vision:vision",
        "The vision camera: how good its pipe detector is, and a camera model calibrated from it.",
    ),
}

for _name, (_path, _short) in COMMANDS.items():
    main.add_lazy_command(_name, _path, _short)

__all__ = ["COMMANDS", "main"]
