"""The options several commands share, each built in one place, with their shell completion.

Each builder takes the command's own help text where the meaning differs between commands; the
ranges and checks are the same everywhere. Decorators that turn several options into one argument
(``disturbance``, ``camera``) check the values and raise one-line errors naming the option.
"""

from __future__ import annotations

import functools

import click

from pipefollow.cli import parsing
from pipefollow.cli.common import SEED, UserError, finite
from pipefollow.files.limits import MAX_EPISODE_SECONDS, MAX_EPISODES
from pipefollow.files.paper_training import TEST_EPISODE_SECONDS

SUITE_HELP = (
    "A suite (see 'pipefollow suites'), or pipeline JSON files: folders, files, glob patterns "
    "(repeatable) [default: heldout]."
)


def json_option(help_text: str = "Print one JSON object instead of a table."):
    """``--json`` (``as_json``): print the result as one JSON object (see :func:`echo_result`)."""
    return click.option("--json", "as_json", is_flag=True, help=help_text)


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


def seconds_option(
    help_text: str = "Episode length in seconds.", default: float | None = TEST_EPISODE_SECONDS
):
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
    """Decorate a command with the disturbance options (the current, the camera's and the sensors' faults).

    They are ``--current``, ``--camera-noise``, ``--miss-prob``, ``--dvl-noise`` and ``--gyro-noise``.

    The command receives one keyword argument ``disturbance`` (a
    :class:`~pipefollow.sim.disturbance.Disturbance`). Bad values are click usage errors that name the
    option (exit status 2).
    """

    def checked(parse):
        def callback(ctx, param, value):
            if value is None:
                return None
            from pipefollow.sim.disturbance import DisturbanceError

            try:
                return parse(value)
            except DisturbanceError as e:
                raise click.BadParameter(str(e), ctx=ctx, param=param) from None

        return callback

    @functools.wraps(fn)
    def wrapper(*args, current, camera_noise, miss_prob, dvl_noise, gyro_noise, **kwargs):
        from pipefollow.sim.disturbance import make_disturbance

        speed, direction = current if current is not None else (0.0, 0.0)
        d = make_disturbance(speed, direction, camera_noise=camera_noise or 0.0, miss_prob=miss_prob or 0.0,
                             dvl_noise=dvl_noise or 0.0, gyro_noise_deg=gyro_noise or 0.0)  # fmt: skip
        return fn(*args, disturbance=d, **kwargs)

    options = [
        click.option(
            "--current",
            metavar="SPEED,DIR_DEG",
            default=None,
            callback=checked(parsing.parse_current),
            help="Ocean current: SPEED m/s flowing towards DIR_DEG degrees clockwise from north.",
        ),
        click.option(
            "--camera-noise",
            type=float,
            default=None,
            metavar="M",
            callback=checked(parsing.parse_camera_noise),
            help="Standard deviation (m) of Gaussian noise on the camera's pipe end points. [default: 0]",
        ),
        click.option(
            "--miss-prob",
            type=float,
            default=None,
            metavar="P",
            callback=checked(parsing.parse_miss_prob),
            help="Probability per decision that the camera misses the pipe. [default: 0]",
        ),
        click.option(
            "--dvl-noise",
            type=float,
            default=None,
            metavar="M/S",
            callback=checked(parsing.parse_sensor_noise("dvl noise")),
            help="Standard deviation (m/s) of the DVL's sway velocity over ground, which --state "
            "paper+drift observes. [default: 0]",
        ),
        click.option(
            "--gyro-noise",
            type=float,
            default=None,
            metavar="DEG/S",
            callback=checked(parsing.parse_sensor_noise("gyro noise")),
            help="Standard deviation (°/s) of the gyro's yaw rate, which --state paper+yaw observes. "
            "[default: 0]",
        ),
    ]
    for option in reversed(options):
        wrapper = option(wrapper)
    return wrapper


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
    """Decorate a command with ``--camera``, ``--sensor`` and the water's options.

    The water's: ``--water``, ``--turbidity``, ``--burial`` and ``--growth``.

    The command receives one keyword argument ``camera``: ``None`` for the ideal camera alone, else
    the environment's camera arguments (``camera``, ``water`` and, unless it is ``camera``,
    ``sensor``). A bad value is a one-line error naming the setting (exit status 2).
    """

    @functools.wraps(fn)
    def wrapper(*args, camera, sensor, water, turbidity, burial, growth, **kwargs):
        settings = {
            k: v
            for k, v in (("turbidity", turbidity), ("burial", burial), ("growth", growth))
            if v is not None
        }
        if camera == "ideal" and sensor == "camera":
            if settings or water is not None:
                raise UserError(
                    "--water, --turbidity, --burial and --growth need --camera vision (or vision-raw) "
                    "or --sensor sonar (fused, fls or fused-fls)"
                )
            return fn(*args, camera=None, **kwargs)
        from pipefollow.perception.camera import camera_settings

        try:
            chosen = camera_settings(camera, water={"preset": water or "clear", **settings}, sensor=sensor)
        except (ValueError, ImportError) as e:
            raise UserError(str(e)) from None
        chosen_args = {"camera": camera, "water": chosen.water}
        if sensor != "camera":  # the camera alone keeps its arguments as they were
            chosen_args["sensor"] = sensor
        return fn(*args, camera=chosen_args, **kwargs)

    number = click.FloatRange(min=0.0)
    options = [
        # the cameras and sensors are perception.camera's CAMERAS and SENSORS (not imported here: it
        # loads numba); tests/test_cli.py checks that these are they
        click.option(
            "--camera",
            type=click.Choice(["ideal", "vision", "vision-raw"]),
            default="ideal",
            show_default=True,
            help="ideal: the exact visible piece (the paper's); vision: a pipe detector on the camera image "
            "and a tracker over the frames; vision-raw: the detector alone, frame by frame.",
        ),
        click.option(
            "--sensor",
            type=click.Choice(["camera", "sonar", "fused", "fls", "fused-fls"]),
            default="camera",
            show_default=True,
            help="camera: the --camera alone; sonar: a forward-tilted multibeam sonar alone (with --camera "
            "ideal; turbidity does not reach it); fused: the camera's detections, the sonar's where the "
            "camera finds no pipe, in one track; fls, fused-fls: the same with a forward-looking imaging "
            "sonar and its map instead of the multibeam sonar.",
        ),
        click.option(
            "--water",
            default=None,
            metavar="PRESET",
            # the presets and the fields they set are perception.water's WATER_PRESETS and PRESET_FIELDS
            # (not imported here: it loads numba); tests/test_results_pages.py checks that this names them
            help="Water preset: clear, moderate, turbid [clear]. A preset sets turbidity, blur, noise and "
            "snow (marine snow) together; --turbidity, --burial and --growth change it.",
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


def learner_options(fn):
    """Decorate a command with one option per entry of the learners' table, generated from it.

    :data:`pipefollow.learners.options.LEARNER_OPTIONS` gives each option's flag (``--critic-lambda``),
    type, allowed values and help; the command receives one keyword argument ``learner_options``:
    option name → value of those given on the command line. A bad value is a usage error naming
    the option (exit status 2).
    """
    from pipefollow.learners.options import LEARNER_OPTIONS
    from pipefollow.learners.registry import taking

    def checked(option):
        def callback(ctx, param, value):
            if value is None or (option.kind is bool and not value):
                return None
            try:
                return option.check(value)
            except ValueError as e:
                raise click.BadParameter(str(e), ctx=ctx, param=param) from None

        return callback

    def option_of(o):
        learners = " and ".join(taking(o.name))
        default = "" if o.kind is bool else f"; default: {o.default:g}" if o.kind is float else ""
        default = f"; default: {o.default}" if o.kind is str else default
        allowed = f"; {o.allowed()}" if o.kind is float else ""
        text = f"{o.help[0].upper()}{o.help[1:]} [{learners}{allowed}{default}]."
        kwargs = dict(callback=checked(o), help=text, expose_value=True)
        if o.kind is bool:
            return click.option(o.option, o.name, is_flag=True, default=None, **kwargs)
        if o.kind is str:
            return click.option(o.option, o.name, type=click.Choice(o.choices), default=None, **kwargs)
        return click.option(o.option, o.name, type=float, default=None, metavar="X", **kwargs)

    names = [o.name for o in LEARNER_OPTIONS]

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        given = {name: kwargs.pop(name) for name in names}
        return fn(*args, learner_options={k: v for k, v in given.items() if v is not None}, **kwargs)

    for o in reversed(LEARNER_OPTIONS):
        wrapper = option_of(o)(wrapper)
    return wrapper
