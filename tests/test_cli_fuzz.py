"""Property: whatever the options and input files, the CLI ends with 0 or a one-line error (2).

Random option values (numbers out of range, NaN, text, huge or negative seeds) and random bytes
as pipeline, policy and experiment files never give a traceback or another exit status, and a
failed command leaves none of its outputs behind. Runs in-process with tiny episodes.
"""

import contextlib
import tempfile
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pipefollow.cli import main


# Values that are valid and cheap (drawn more often, so that whole commands succeed too), or
# invalid in the ways users get them wrong.
def _mix(valid, invalid):
    return st.one_of(st.sampled_from(valid), st.sampled_from(valid), st.sampled_from(invalid))


COUNTS = _mix(["1", "2"], ["0", "-3", "abc", "1.5", "", "99999999999", str(2**64)])
SECONDS = _mix(["1", "2.5"], ["0", "-1", "nan", "inf", "-inf", "1e400", "x", "86401"])
SEEDS = st.one_of(
    st.integers(min_value=0, max_value=2**70).map(str),
    st.integers(min_value=0, max_value=2**70).map(str),
    st.integers(max_value=-1).map(str),
    st.sampled_from(["", "s", "1e3", "0x10"]),
)
NOISE = _mix(["0", "0.3"], ["-0.1", "nan", "inf", "z"])
FILE_BYTES = st.one_of(
    st.binary(max_size=64),
    st.sampled_from(
        [
            b'{"points": [[0, 0], [3, 0], [3, 4]]}',
            b'\xef\xbb\xbf{"points": [[0, 0], [5, 0]]}',
            '{"points": [[0, 0], [5, 0]]}'.encode("utf-16"),
            b'{"points": [[0, 0], [0, 0]]}',
            b'[experiment]\nname = "f"\n[[trial]]\nname = "t"\nalgorithm = "sarsa"\n',
            b'[experiment]\nname = "f"\nseed = -4\n[[trial]]\nname = "t"\n',
            b'[[trial]]\nname = "t"\nfigures = ["fig99"]\n',
            b"PK\x03\x04 not a zip",
        ]
    ),
)
NAMES = st.sampled_from(["out", "afile/out", "deep/er/out"])
PLOTS = st.sampled_from(["p.png", "p.jpg", "p.svg", "p.xyz", "p", "afile/p.png"])


@st.composite
def invocations(draw):
    """(command-line arguments, input files to write, the outputs the command would make)."""
    files = {"in.bin": draw(FILE_BYTES)}
    command = draw(st.sampled_from(["evaluate", "train", "reproduce", "trials", "pipelines"]))
    if command == "evaluate":
        pipeline = draw(st.sampled_from(["paper-left", "paper-left", "paper-up", "in.json", "in.bin"]))
        controller = draw(st.sampled_from(["heuristic", "heuristic", "in.npz", "missing.npz"]))
        plot = draw(st.one_of(st.none(), PLOTS))
        args = ["evaluate", "--pipeline", pipeline, "--controller", controller, "--seed", draw(SEEDS)]
        args += ["--episodes", draw(COUNTS), "--seconds", draw(SECONDS), "--start-noise", draw(NOISE)]
        outputs = [plot] if plot else []
        args += ["--plot", plot] if plot else []
    elif command == "train":
        out = draw(NAMES)
        args = ["train", "--algorithm", draw(st.sampled_from(["sarsa", "cacla", "ppo"])), "--out", out]
        args += ["--episodes", draw(COUNTS), "--seconds", draw(SECONDS), "--seed", draw(SEEDS)]
        args += ["--pipeline", draw(st.sampled_from(["paper-right", "paper-right", "in.json"]))]
        args += ["--skew", draw(NOISE)] if draw(st.integers(0, 3)) == 0 else []
        args += ["--init", "in.npz"] if draw(st.integers(0, 3)) == 0 else []
        outputs = [out]
    elif command == "reproduce":
        out = draw(NAMES)
        experiment = draw(st.sampled_from(["paper", "in.toml"]))
        args = ["reproduce", "--experiment", experiment, "--out", out, "--backend", "serial", "--no-figures"]
        args += ["--repeats", "1", "--episodes", draw(st.sampled_from(["1", "2", "0", "-1"]))]
        args += ["--seed", draw(SEEDS)]
        args += ["--trial", "sarsa"] if experiment == "paper" else []
        outputs = [out]
    elif command == "trials":
        args, outputs = (
            ["trials", "--experiment", draw(st.sampled_from(["paper", "in.toml", "none.toml"]))],
            [],
        )
    else:
        args, outputs = ["pipelines"], []
    if draw(st.booleans()):
        args.append("--json")
    return args, files, outputs


@pytest.mark.slow  # hypothesis drives the whole CLI (≈ 2 s)
@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(invocation=invocations())
def test_cli_never_gives_a_traceback_or_partial_output(invocation):
    args, files, outputs = invocation
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        data = files["in.bin"]
        for name in ("in.bin", "in.json", "in.npz", "in.toml"):
            (root / name).write_bytes(data)
        (root / "afile").write_text("")
        inputs = sorted(root.iterdir())
        with contextlib.chdir(root):
            result = CliRunner().invoke(main, args)
        assert result.exception is None or isinstance(result.exception, SystemExit), result.exc_info
        assert result.exit_code in (0, 2), (args, result.output)
        assert "Traceback" not in result.output
        if result.exit_code == 2:
            lines = result.stderr.strip().splitlines()
            assert len(lines) == 1 and lines[0].startswith("pipefollow: error: "), (args, lines)
            assert sorted(root.iterdir()) == inputs, (args, lines)  # no output, no folder made
        else:
            assert all((root / out).exists() for out in outputs), args
