"""What the commands of the ``pipefollow`` command line share: errors, options, checks.

Bad input is a one-line error naming the input (``pipefollow: error: …``) with exit status 2
(:class:`~pipefollow.cli.group.UserError`, :func:`guard`); click's own usage errors are printed the
same way by the group (:mod:`pipefollow.cli.group`). The commands live in the modules beside this
one, by subject.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from pathlib import Path

import click

from pipefollow.cli.group import UserError, main  # noqa: F401 - main: for modules that register on it

# The library's input errors, by module: an error can only be raised once its module is imported,
# so the check needs (and imports) none of them
_USER_ERRORS = (
    ("pipefollow.sim.pipeline", "PipelineError"),
    ("pipefollow.training.policy_files", "PolicyError"),
    ("pipefollow.experiments.config", "ConfigError"),
    ("pipefollow.experiments.store", "StoreError"),
    ("pipefollow.sim.disturbance", "DisturbanceError"),
    ("pipefollow.files.output_paths", "OutputError"),
)


def user_errors() -> tuple[type[Exception], ...]:
    """The classes of the library's input errors whose modules are loaded."""
    return tuple(getattr(sys.modules[m], name) for m, name in _USER_ERRORS if m in sys.modules)


# Seeds: what NumPy's SeedSequence takes, any non-negative integer (no upper bound).
SEED = click.IntRange(min=0)


def is_path_error(e: OSError) -> bool:
    """An error about a file or folder the user named (not an internal failure)."""
    import errno

    path_errors = (PermissionError, IsADirectoryError, NotADirectoryError, FileNotFoundError, FileExistsError)
    return isinstance(e, path_errors) or e.errno in (errno.ENOSPC, errno.EROFS, errno.ENAMETOOLONG)


def guard(fn):
    """Turn the library's input errors into one-line CLI errors (exit 2, no traceback)."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except user_errors() as e:
            raise UserError(str(e)) from None
        except OSError as e:
            if not is_path_error(e):
                raise
            name = e.filename2 or e.filename  # for a failed rename, the target
            where = f"'{name}': " if name else ""
            raise UserError(f"{where}{e.strerror or e}") from None

    return wrapper


def finite(ctx, param, value):
    """Reject NaN and infinity, which click's ranges let through."""
    import math

    if value is not None and not math.isfinite(value):
        raise click.BadParameter(f"{value} is not a finite number", ctx=ctx, param=param)
    return value


def writable_folder(path: str, option: str) -> Path:
    """Create the folder and check that files can be written there, before any long work."""
    import os
    import tempfile

    folder = Path(path)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".pipefollow-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise UserError(f"{option} '{path}': cannot write there ({e.strerror or e})") from None
    return folder


# The longest episode an option takes: experiments.schema.MAX_SECONDS, kept here so that the
# command line imports no experiment machinery to build its options (a test holds them equal)
MAX_EPISODE_SECONDS = 86_400.0
MAX_EPISODES = 10_000_000  # experiments.schema.MAX_EPISODES, likewise


SUITE_HELP = (
    "A suite (see 'pipefollow suites'), or pipeline JSON files: folders, files, glob patterns "
    "(repeatable) [default: heldout]."
)


def json_option(help_text: str = "Print one JSON object instead of a table."):
    """``--json`` (``as_json``): print the result as one JSON object (see :func:`echo_result`)."""
    return click.option("--json", "as_json", is_flag=True, help=help_text)


def echo_result(result, as_json: bool, text: Callable[[], str], **dumps) -> None:
    """Print ``result`` as one JSON object under ``--json``, else the lines ``text()`` formats."""
    import json

    click.echo(json.dumps(result, **dumps) if as_json else text())


def suite_option(help_text: str = SUITE_HELP):
    """``--suite SUITE|PATH`` (``suite_specs``, repeatable): a suite or pipeline files."""
    return click.option(
        "--suite", "suite_specs", multiple=True, metavar="SUITE|PATH", shell_complete=complete_suite,
        help=help_text,
    )  # fmt: skip


def pipes_option(
    help_text: str = "Number of pipes [default: all of a held-out suite, 100 of a training family].",
):
    """``--pipes N``: how many pipes of a suite (None: its default, see :func:`pipe_count`)."""
    return click.option("--pipes", type=click.IntRange(min=1, max=100_000), default=None, help=help_text)


def pipe_count(suite, pipes: int | None) -> int:
    """The pipes ``--pipes`` asks of ``suite`` (its default if None); a one-line error past its end."""
    n = pipes if pipes is not None else (suite.count or 100)
    if suite.count is not None and n > suite.count:
        raise UserError(f"--pipes {n}: suite '{suite.name}' has {suite.count} pipes")
    return n


def seconds_option(help_text: str = "Episode length in seconds.", default: float | None = 60.0):
    """``--seconds S``: the episode length, 1 s to :data:`MAX_EPISODE_SECONDS`, finite."""
    return click.option(
        "--seconds", type=click.FloatRange(min=1.0, max=MAX_EPISODE_SECONDS), callback=finite,
        default=default, show_default=default is not None, help=help_text,
    )  # fmt: skip


def episodes_option(default: int, help_text: str):
    """``--episodes N``: how many episodes, 1 to :data:`MAX_EPISODES`."""
    return click.option(
        "--episodes", default=default, show_default=True, type=click.IntRange(min=1, max=MAX_EPISODES),
        help=help_text,
    )  # fmt: skip


def pipeline_option(help_text: str):
    """``--pipeline NAME|FILE`` (``paper-left`` by default), completed with the pipelines' names."""
    return click.option(
        "--pipeline", default="paper-left", show_default=True, shell_complete=complete_pipeline,
        help=help_text,
    )  # fmt: skip


def offset_option(name: str, help_text: str):
    """A start offset's bound (``--start-noise``, ``--heading-noise``): finite, ≥ 0, 0 by default."""
    return click.option(
        name, default=0.0, show_default=True, type=click.FloatRange(min=0.0), callback=finite, help=help_text
    )


def seed_option(help_text: str):
    """``--seed N``: a non-negative seed, 0 by default."""
    return click.option("--seed", default=0, show_default=True, type=SEED, help=help_text)


def plot_option(help_text: str):
    """``--plot FILE`` (``plot_path``): a figure file (check it with :func:`check_plot_path`)."""
    return click.option("--plot", "plot_path", type=click.Path(dir_okay=False), default=None, help=help_text)


def out_option(help_text: str):
    """``--out FOLDER`` (``out_dir``, required): where a command writes its files."""
    return click.option("--out", "out_dir", type=click.Path(file_okay=False), required=True, help=help_text)


def reading_option(help_text: str):
    """``--reading ID`` (repeatable): readings of the paper's open points, ``key=value[,key=value]``."""
    return click.option("--reading", "readings", multiple=True, metavar="ID", help=help_text)


def apply_readings(ids, base: str = "default"):
    """The readings ``base`` (an id) changed by the ``--reading`` ids; a one-line error if malformed."""
    from pipefollow import readings as rd

    try:
        return rd.parse(ids, rd.parse(base, source="policy readings"), source="--reading")
    except rd.ReadingError as e:
        raise UserError(str(e)) from None


def policy_file(spec: str, option: str) -> str:
    """A policy file, or the ``policy.npz`` inside a folder (what ``train --out`` writes)."""
    path = Path(spec)
    if path.is_dir():
        inside = path / "policy.npz"
        if not inside.is_file():
            raise UserError(f"{option} '{spec}': a folder without policy.npz")
        return str(inside)
    return spec


def load_controller(spec: str, seed: int, lookahead: float | None = None):
    """``heuristic``, ``los`` (lookahead Δ in m), a policy file or a folder holding one → an agent."""
    from pipefollow.evaluation.benchmark import CONTROLLERS
    from pipefollow.evaluation.benchmark import load_controller as load
    from pipefollow.sim.pipe_names import did_you_mean

    if spec not in CONTROLLERS:
        spec = policy_file(spec, "--controller")
        if not Path(spec).exists() and Path(spec).suffix.lower() != ".npz":
            names = ", ".join(CONTROLLERS)
            raise UserError(
                f"controller '{spec}': not {names} nor a policy file{did_you_mean(spec, list(CONTROLLERS))}"
            )
    try:
        return load(spec, seed, lookahead)
    except ValueError as e:
        if isinstance(e, user_errors()):
            raise
        raise UserError(str(e)) from None


def controller_options(fn):
    """``--controller heuristic|los|POLICY_FILE`` and ``--lookahead`` (LOS only)."""
    fn = click.option(
        "--lookahead",
        type=click.FloatRange(min=0.0, min_open=True),
        callback=finite,
        default=None,
        help="Lookahead distance Δ (m) of --controller los [default: 1.5].",
    )(fn)
    return click.option(
        "--controller",
        default="heuristic",
        show_default=True,
        shell_complete=complete_controller,
        help="'heuristic', 'los' (line-of-sight guidance), or a policy file (.npz) from 'pipefollow train' "
        "or the folder holding it.",
    )(fn)


def disturbance_options(fn):
    """Decorate a command with ``--current``, ``--camera-noise`` and ``--miss-prob``.

    The command receives one keyword argument ``disturbance`` (a
    :class:`~pipefollow.sim.disturbance.Disturbance`). Bad values are click usage errors that name the
    option (exit status 2).
    """
    import functools

    def checked(name):
        def callback(ctx, param, value):
            if value is None:
                return None
            from pipefollow.sim import disturbance

            try:
                return getattr(disturbance, name)(value)
            except disturbance.DisturbanceError as e:
                raise click.BadParameter(str(e), ctx=ctx, param=param) from None

        return callback

    @functools.wraps(fn)
    def wrapper(*args, current, camera_noise, miss_prob, **kwargs):
        from pipefollow.sim.disturbance import make_disturbance

        speed, direction = current if current is not None else (0.0, 0.0)
        d = make_disturbance(speed, direction, camera_noise=camera_noise or 0.0, miss_prob=miss_prob or 0.0)
        return fn(*args, disturbance=d, **kwargs)

    options = [
        click.option(
            "--current",
            metavar="SPEED,DIR_DEG",
            default=None,
            callback=checked("parse_current"),
            help="Ocean current: SPEED m/s flowing towards DIR_DEG degrees clockwise from north.",
        ),
        click.option(
            "--camera-noise",
            type=float,
            default=None,
            metavar="M",
            callback=checked("check_camera_noise"),
            help="Standard deviation (m) of Gaussian noise on the camera's pipe end points. [default: 0]",
        ),
        click.option(
            "--miss-prob",
            type=float,
            default=None,
            metavar="P",
            callback=checked("check_miss_prob"),
            help="Probability per decision that the camera misses the pipe. [default: 0]",
        ),
    ]
    for option in reversed(options):
        wrapper = option(wrapper)
    return wrapper


def check_plot_path(plot_path: str | None) -> None:
    """Refuse a ``--plot`` file whose suffix is not an image format, before any work is done."""
    if plot_path:
        from pipefollow.files.output_paths import check_output_file, image_formats

        check_output_file(plot_path, "--plot", tuple(image_formats()))


# Readings that act in a deterministic evaluation of a saved policy: those of the simulation
# (readings.sim_params); the others act in training only, and a policy file keeps its features.
EVALUATION_READINGS = ("start_speed",)


def inert_readings(ids) -> list[str]:
    """Warnings for the ``--reading`` ids that cannot change an evaluation (the others act in training)."""
    keys = [part.split("=", 1)[0].strip() for i in ids for part in str(i).split(",") if "=" in part]
    inert = [k for k in dict.fromkeys(keys) if k not in EVALUATION_READINGS]
    return [
        f"--reading {k}: acts in training only; it cannot change the evaluation of a saved policy or "
        f"a fixed controller (evaluation readings: {', '.join(EVALUATION_READINGS)})"
        for k in inert
    ]


def disturbance_text(d, prefix: str = "; disturbances: ") -> str:
    """The disturbances of a run in words, for the head of a text report; ``""`` without any."""
    from pipefollow.sim import disturbance as dist

    if d == dist.NO_DISTURBANCE:
        return ""
    t = dist.to_dict(d)
    parts = []
    if t["current_speed"]:
        parts.append(f"current {t['current_speed']:g} m/s towards {t['current_direction_deg']:g}°")
    if t["camera_noise"]:
        parts.append(f"camera noise {t['camera_noise']:g} m")
    if t["miss_prob"]:
        parts.append(f"missed detections {t['miss_prob']:.0%}")
    if t["buried"]:
        parts.append(f"{len(t['buried'])} buried stretch(es)")
    return prefix + (", ".join(parts) or "varying current")


def _complete(names, incomplete: str, files: bool = True):
    from click.shell_completion import CompletionItem

    items = [CompletionItem(n) for n in names if n.startswith(incomplete)]
    return items + ([CompletionItem(incomplete, type="file")] if files else [])


def complete_pipeline(ctx, param, incomplete: str):
    """Shell completion of ``--pipeline``: built-ins, ``random:FAMILY``, then files."""
    from pipefollow.sim.pipe_names import pipeline_names

    return _complete(pipeline_names(), incomplete)


def complete_controller(ctx, param, incomplete: str):
    """Shell completion of ``--controller``: the built-in controllers, then policy files and folders."""
    from pipefollow.evaluation.benchmark import CONTROLLERS

    return _complete(list(CONTROLLERS), incomplete)


def complete_suite(ctx, param, incomplete: str):
    """Shell completion of ``--suite``: the suites, then folders and files."""
    from pipefollow.sim.suites import SUITES

    return _complete(list(SUITES), incomplete)


def camera_options(fn):
    """Decorate a command with ``--camera``, ``--water``, ``--turbidity``, ``--burial`` and ``--growth``.

    The command receives one keyword argument ``camera``: ``None`` for the ideal camera, else the
    environment's camera arguments (``camera``, ``water``). A bad value is a one-line error naming
    the setting (exit status 2).
    """

    @functools.wraps(fn)
    def wrapper(*args, camera, water, turbidity, burial, growth, **kwargs):
        settings = {
            k: v
            for k, v in (("turbidity", turbidity), ("burial", burial), ("growth", growth))
            if v is not None
        }
        if camera == "ideal":
            if settings or water is not None:
                raise UserError("--water, --turbidity, --burial and --growth need --camera vision")
            return fn(*args, camera=None, **kwargs)
        from pipefollow.perception.camera import camera_settings

        try:
            chosen = camera_settings("vision", water={"preset": water or "clear", **settings})
        except (ValueError, ImportError) as e:
            raise UserError(str(e)) from None
        return fn(*args, camera={"camera": "vision", "water": chosen.water}, **kwargs)

    number = click.FloatRange(min=0.0)
    options = [
        click.option(
            "--camera",
            type=click.Choice(["ideal", "vision"]),
            default="ideal",
            show_default=True,
            help="ideal: the exact visible piece (the paper's); vision: a pipe detector on the camera image.",
        ),
        click.option(
            "--water", default=None, metavar="PRESET", help="Water preset: clear, moderate, turbid [clear]."
        ),
        click.option(
            "--turbidity",
            type=number,
            callback=finite,
            default=None,
            metavar="C",
            help="Beam attenuation (1/m).",
        ),
        click.option(
            "--burial",
            type=number,
            callback=finite,
            default=None,
            help="Share of the pipe's width under sand.",
        ),
        click.option(
            "--growth",
            type=number,
            callback=finite,
            default=None,
            help="Share of the pipe under marine growth.",
        ),
    ]
    for option in reversed(options):
        wrapper = option(wrapper)
    return wrapper
