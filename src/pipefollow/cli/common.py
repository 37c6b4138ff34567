"""What every command of the ``pipefollow`` command line shares: the group, errors, options.

Bad input is a one-line error naming the input (``pipefollow: error: …``) with exit status 2
(:class:`UserError`, :func:`guard`); click's own usage errors are printed the same way
(:class:`OneLineErrors`). The commands live in the modules beside this one, by subject.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from pipefollow.experiments.config import ConfigError
from pipefollow.experiments.store import StoreError
from pipefollow.files.output_paths import OutputError
from pipefollow.sim import disturbance as _disturbance
from pipefollow.sim.disturbance import DisturbanceError
from pipefollow.sim.pipeline import PipelineError
from pipefollow.training.policy_files import PolicyError

USER_ERRORS: tuple[type[Exception], ...] = (
    PipelineError,
    PolicyError,
    ConfigError,
    StoreError,
    DisturbanceError,
    OutputError,
)

# Seeds: what NumPy's SeedSequence takes, any non-negative integer (no upper bound).
SEED = click.IntRange(min=0)


class UserError(click.ClickException):
    """A one-line error about the user's input, exit status 2."""

    exit_code = 2

    def show(self, file=None) -> None:  # noqa: D102
        click.echo(f"pipefollow: error: {self.message}", err=True)


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
        except USER_ERRORS as e:
            raise UserError(str(e)) from None
        except OSError as e:
            if not is_path_error(e):
                raise
            name = e.filename2 or e.filename  # for a failed rename, the target
            where = f"'{name}': " if name else ""
            raise UserError(f"{where}{e.strerror or e}") from None

    return wrapper


# click ≥ 8.2 raises this for a bare group; older versions print the help and exit 0 themselves
_NO_ARGS_IS_HELP = getattr(click.exceptions, "NoArgsIsHelpError", ())


class OneLineErrors(click.Group):
    """Click's own usage errors (a bad option value, a missing option) on one line, exit 2."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):  # noqa: D102
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.Abort:  # Ctrl-C: the shell's convention, 128 + SIGINT
            click.echo("pipefollow: interrupted", err=True)
            sys.exit(130)
        except _NO_ARGS_IS_HELP as e:  # the bare command asks for help; it is not an error
            click.echo(e.ctx.get_help() if e.ctx else self.get_help(click.Context(self)))
            sys.exit(0)
        except click.ClickException as e:
            if isinstance(e, UserError):
                e.show()
            else:
                click.echo(f"pipefollow: error: {e.format_message()}", err=True)
            sys.exit(e.exit_code)
        sys.exit(rv if isinstance(rv, int) else 0)


def finite(ctx, param, value):
    """Reject NaN and infinity, which click's ranges let through."""
    import math

    if value is not None and not math.isfinite(value):
        raise click.BadParameter(f"{value} is not a finite number", ctx=ctx, param=param)
    return value


@click.group(
    cls=OneLineErrors,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)
@click.version_option(package_name="pipefollow")
def main() -> None:
    """Learn and evaluate AUV pipeline-following controllers (Fjerdingen et al., 2010)."""


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


def load_controller(spec: str, seed: int, lookahead: float | None = None):
    """``heuristic``, ``los`` (lookahead Δ in m) or a policy file → an agent."""
    from pipefollow.evaluation.benchmark import load_controller as load

    try:
        return load(spec, seed, lookahead)
    except ValueError as e:
        if isinstance(e, USER_ERRORS):
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
        help="'heuristic', 'los' (line-of-sight guidance) or a policy file (.npz) from 'pipefollow train'.",
    )(fn)


def disturbance_options(fn):
    """Decorate a command with ``--current``, ``--camera-noise`` and ``--miss-prob``.

    The command receives one keyword argument ``disturbance`` (a
    :class:`~pipefollow.sim.disturbance.Disturbance`). Bad values are click usage errors that name the
    option (exit status 2).
    """
    import functools

    def checked(convert):
        def callback(ctx, param, value):
            if value is None:
                return None
            try:
                return convert(value)
            except DisturbanceError as e:
                raise click.BadParameter(str(e), ctx=ctx, param=param) from None

        return callback

    @functools.wraps(fn)
    def wrapper(*args, current, camera_noise, miss_prob, **kwargs):
        speed, direction = current if current is not None else (0.0, 0.0)
        d = _disturbance.make_disturbance(
            speed, direction, camera_noise=camera_noise or 0.0, miss_prob=miss_prob or 0.0
        )
        return fn(*args, disturbance=d, **kwargs)

    options = [
        click.option(
            "--current",
            metavar="SPEED,DIR_DEG",
            default=None,
            callback=checked(_disturbance.parse_current),
            help="Ocean current: SPEED m/s flowing towards DIR_DEG degrees clockwise from north.",
        ),
        click.option(
            "--camera-noise",
            type=float,
            default=None,
            metavar="M",
            callback=checked(_disturbance.check_camera_noise),
            help="Standard deviation (m) of Gaussian noise on the camera's pipe end points. [default: 0]",
        ),
        click.option(
            "--miss-prob",
            type=float,
            default=None,
            metavar="P",
            callback=checked(_disturbance.check_miss_prob),
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
