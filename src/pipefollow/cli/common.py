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


def echo_result(result, as_json: bool, text: Callable[[], str], **dumps) -> None:
    """Print ``result`` as one JSON object under ``--json``, else the lines ``text()`` formats."""
    import json

    click.echo(json.dumps(result, **dumps) if as_json else text())


def pipe_count(suite, pipes: int | None) -> int:
    """The pipes ``--pipes`` asks of ``suite`` (its default if None); a one-line error past its end."""
    n = pipes if pipes is not None else (suite.count or 100)
    if suite.count is not None and n > suite.count:
        raise UserError(f"--pipes {n}: suite '{suite.name}' has {suite.count} pipes")
    return n


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


def check_plot_path(plot_path: str | None) -> None:
    """Refuse a ``--plot`` file whose suffix is not an image format, before any work is done."""
    if plot_path:
        from pipefollow.files.output_paths import check_output_file, image_formats

        check_output_file(plot_path, "--plot", tuple(image_formats()))


def inert_readings(ids) -> list[str]:
    """Warnings for the ``--reading`` ids that cannot change an evaluation (the others act in training).

    A deterministic evaluation of a saved policy reads only the simulation's readings
    (:data:`pipefollow.readings.SIM_READINGS`); a policy file keeps its features.
    """
    from pipefollow.readings import SIM_READINGS

    keys = [part.split("=", 1)[0].strip() for i in ids for part in str(i).split(",") if "=" in part]
    inert = [k for k in dict.fromkeys(keys) if k not in SIM_READINGS]
    return [
        f"--reading {k}: acts in training only; it cannot change the evaluation of a saved policy or "
        f"a fixed controller (evaluation readings: {', '.join(SIM_READINGS)})"
        for k in inert
    ]


def camera_text(camera, prefix: str = "\n") -> str:
    """The camera and its water in one line for the head of a text report; ``""`` for the ideal camera."""
    if not camera:
        return ""
    from pipefollow.perception.water import describe

    sensor = camera.get("sensor", "camera")
    sensor = "" if sensor == "camera" else f"sensor {sensor}, "
    return f"{prefix}{sensor}camera {camera['camera']}, {describe(camera['water'])}"


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
    if t["dvl_noise"] or t["gyro_noise_deg"]:
        parts.append(f"sensor noise {t['dvl_noise']:g} m/s, {t['gyro_noise_deg']:g}°/s")
    if t["buried"]:
        parts.append(f"{len(t['buried'])} buried stretch(es)")
    return prefix + (", ".join(parts) or "varying current")


def camera_record(camera) -> dict:
    """A result's entries for ``--camera``, ``--sensor`` and the water (what :func:`camera_options` gave).

    :func:`pipefollow.perception.camera.camera_record`; ``{}`` for the ideal camera alone.
    """
    if not camera:
        return {}
    from pipefollow.perception.camera import camera_record as record  # loads numba: not at start-up

    return record(camera)


def command_line() -> str:
    """The command as the user gave it (``pipefollow`` and its arguments), for provenance records.

    The arguments the command-line group was called with (also under click's test runner), else
    the process's own.
    """
    import shlex
    import sys

    ctx = click.get_current_context(silent=True)
    root = ctx.find_root().command if ctx is not None else None
    args = getattr(root, "invocation", None)
    return shlex.join(["pipefollow", *(sys.argv[1:] if args is None else args)])
