"""The same seed gives the same numbers on every CPU: the reproduction under numba's generic target.

``learners.sums`` fixes the order of every sum of the learners, and no compiled function of the
simulator or the learners lets the compiler fuse or reorder floating-point operations, so the code
numba compiles for an old CPU (``generic``: no SIMD beyond SSE2, no fused multiply-add) and for the
host (AVX2, AVX-512, …) must compute the same bits. The committed ``docs/reproduction/evaluation.csv``
is the reference: it must come out byte for byte under each target.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

COMMITTED = Path(__file__).resolve().parents[1] / "docs" / "reproduction" / "evaluation.csv"


def _reproduce(out: Path, env: dict) -> bytes:
    cmd = [sys.executable, "-m", "pipefollow.cli", "reproduce", "--out", str(out), "--no-figures"]
    subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    return (out / "evaluation.csv").read_bytes()


@pytest.mark.slow  # the whole reproduction in a fresh interpreter (≈ 9 s)
def test_reproduction_on_the_host_target_equals_the_committed_evaluation(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CPU_NAME"}
    assert _reproduce(tmp_path / "run", env) == COMMITTED.read_bytes()


@pytest.mark.slow  # compiles the simulator and the learners for another target (≈ 1–2 min on 2 cores)
def test_reproduction_under_the_generic_cpu_target_equals_the_committed_evaluation(tmp_path):
    env = dict(os.environ, NUMBA_CPU_NAME="generic", NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    assert _reproduce(tmp_path / "run", env) == COMMITTED.read_bytes()


def test_no_compiled_function_lets_the_compiler_reorder_or_fuse_arithmetic():
    # fastmath's reassoc splits sums by the target's SIMD width and its contract fuses multiply-add
    # where the target has FMA: either makes the numbers depend on the CPU
    import ast

    src = Path(__file__).resolve().parents[1] / "src" / "pipefollow"
    licensed = []
    for path in sorted(src.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and any(k.arg == "fastmath" for k in node.keywords):
                licensed.append(f"{path.relative_to(src)}:{node.lineno}")
    assert licensed == []


FRAMES = """
import hashlib, sys
import numpy as np
from pipefollow.perception.detector import detect_pipe
from pipefollow.perception.image import Renderer
from pipefollow.perception.textures import make_textures
from pipefollow.perception.water import WATER_PRESETS
from pipefollow.sim.suites import get_suite, min_length_for

pipe = get_suite("heldout").pipes(1, min_length_for(200.0))[0]
rng = np.random.default_rng(0)
textures, renderer = make_textures(rng), Renderer(WATER_PRESETS['moderate'])
images, detections = hashlib.sha256(), hashlib.sha256()
x0, y0 = pipe.points[0]
for k in range(40):
    pose = (x0 + 0.05 * k, y0 + 0.01 * k, 0.02 * k)
    image = renderer.render(pipe.points, pipe.cumulative, pose, textures, rng)
    images.update(image.tobytes())
    detections.update(repr(detect_pipe(image)).encode())
print(images.hexdigest(), detections.hexdigest())
"""


def old_cpu(cache: Path) -> dict:
    """The environment of a process that computes as on an old CPU, on this one.

    numba compiles for ``generic``; NumPy's and OpenCV's run-time dispatch to AVX, AVX2 and AVX-512
    kernels is turned off (``NPY_DISABLE_CPU_FEATURES``, ``OPENCV_CPU_DISABLE``): NumPy's float64
    ``exp`` and ``power`` give other last bits with and without AVX-512, and the renderer's lighting
    and the texture bank compute with them before rounding to float32 and to integers.
    """
    env = dict(os.environ, NUMBA_CPU_NAME="generic", NUMBA_CACHE_DIR=str(cache))
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__
    except ImportError:  # another NumPy's layout: its dispatch stays on
        __cpu_dispatch__ = []
    env["NPY_DISABLE_CPU_FEATURES"] = ",".join(__cpu_dispatch__)
    try:
        import cv2

        # "*AVX2" is a feature dispatched at run time, "*AVX2?" one this CPU lacks
        dispatched = [f.strip("*?") for f in cv2.getCPUFeaturesLine().split() if f.startswith("*")]
        env["OPENCV_CPU_DISABLE"] = ",".join(dispatched)
    except (ImportError, AttributeError):
        pass
    return env


@pytest.mark.slow  # compiles the renderer for another target
def test_camera_images_and_detections_are_the_same_under_the_generic_cpu_target(tmp_path):
    pytest.importorskip("cv2")
    host = {k: v for k, v in os.environ.items() if k != "NUMBA_CPU_NAME"}
    generic = old_cpu(tmp_path)
    run = [sys.executable, "-c", FRAMES]
    a = subprocess.run(run, env=host, check=True, capture_output=True, text=True).stdout
    b = subprocess.run(run, env=generic, check=True, capture_output=True, text=True).stdout
    assert a == b and len(a.split()) == 2


PINGS = """
import hashlib
import numpy as np
from pipefollow.perception.sonar import make_sonar
from pipefollow.perception.sonar_track import SonarSensor
from pipefollow.sim.suites import get_suite, min_length_for

pipe = get_suite("heldout").pipes(1, min_length_for(200.0))[0]
rng = np.random.default_rng(0)
sensor = SonarSensor(make_sonar(pitch_deg=45.0, roughness=0.01, dropout=0.05), burial=0.3)
ranges, views = hashlib.sha256(), hashlib.sha256()
x0, y0 = pipe.points[0]
for k in range(40):
    view = sensor.step(pipe.points, pipe.cumulative, (x0 + 0.3 * k, y0 + 0.01 * k, 0.02 * k), rng)
    ranges.update(sensor.ping.ranges.tobytes())
    views.update(repr((sensor.fix, view)).encode())
print(ranges.hexdigest(), views.hexdigest())
"""


@pytest.mark.slow  # compiles the sonar for another target
def test_sonar_pings_and_detections_are_the_same_under_the_generic_cpu_target(tmp_path):
    host = {k: v for k, v in os.environ.items() if k != "NUMBA_CPU_NAME"}
    generic = old_cpu(tmp_path)
    run = [sys.executable, "-c", PINGS]
    a = subprocess.run(run, env=host, check=True, capture_output=True, text=True).stdout
    b = subprocess.run(run, env=generic, check=True, capture_output=True, text=True).stdout
    assert a == b and len(a.split()) == 2


IMAGES = """
import hashlib
import numpy as np
from pipefollow.perception.imaging_track import ImagingSensor
from pipefollow.sim.suites import get_suite, min_length_for

pipe = get_suite("heldout-sharp").pipes(1, min_length_for(200.0))[0]
rng = np.random.default_rng(0)
sensor = ImagingSensor(burial=0.3)
images, views = hashlib.sha256(), hashlib.sha256()
x0, y0 = pipe.points[0]
for k in range(40):
    view = sensor.step(pipe.points, pipe.cumulative, (x0 + 0.3 * k, y0 + 0.01 * k, 0.02 * k), rng)
    images.update(sensor.image.intensity.tobytes())
    views.update(repr((sensor.piece.pieces.tolist(), sensor.fix, view)).encode())
print(images.hexdigest(), views.hexdigest())
"""


@pytest.mark.slow  # compiles the imaging sonar for another target
def test_imaging_sonar_images_and_views_are_the_same_under_an_old_cpu(tmp_path):
    host = {k: v for k, v in os.environ.items() if k != "NUMBA_CPU_NAME"}
    run = [sys.executable, "-c", IMAGES]
    a = subprocess.run(run, env=host, check=True, capture_output=True, text=True).stdout
    b = subprocess.run(run, env=old_cpu(tmp_path), check=True, capture_output=True, text=True).stdout
    assert a == b and len(a.split()) == 2


EPISODES = """
import hashlib
import gymnasium as gym
import numpy as np
import pipefollow
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.suites import get_suite, min_length_for

pipes = get_suite("heldout").pipes(2, min_length_for(60.0))
for kw in (
    dict(camera="vision", water="moderate"),  # the detector and the tracker (navigation, line EKF)
    dict(camera="vision-raw", water="turbid"),
    dict(sensor="sonar", water={"burial": 0.5}),
    dict(sensor="fused", camera="vision", water="turbid"),  # the sonar's fixes on the camera's track
    dict(sensor="fused"),
    dict(sensor="fused-fls", camera="vision", water="turbid"),  # the imaging sonar on the camera's track
    dict(sensor="fls", water={"burial": 0.5}),
):
    returns, seen = [], hashlib.sha256()
    for k, pipe in enumerate(pipes):
        env = gym.make("pipefollow/PipelineFollowing-v0", pipeline=pipe, episode_seconds=60, **kw)
        obs, info = env.reset(seed=k)
        agent, total, done = Heuristic(), 0.0, False
        while not done:
            obs, reward, terminated, truncated, info = env.step([agent.act(obs)])
            seen.update(np.asarray(obs, dtype=np.float64).tobytes())
            seen.update(repr(sorted((key, value.tolist()) for key, value in info.items())).encode())
            total, done = total + reward, terminated or truncated
        returns.append(repr(float(total)))
    print(*returns, seen.hexdigest())
env = gym.make("pipefollow/PipelineFollowingImage-v0", water="turbid")  # observation="image"
image, info = env.reset(seed=3)
images, rng, done = hashlib.sha256(image.tobytes()), np.random.default_rng(1), False
while not done:
    image, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 1))
    images.update(image.tobytes())
    done = terminated or truncated
print(images.hexdigest())
"""


@pytest.mark.slow  # compiles the renderer, the tracker and the sonar for another target (≈ 1 min on 2 cores)
def test_the_environments_through_every_camera_and_sensor_are_the_same_under_an_old_cpu(tmp_path):
    # the heuristic's episodes through each camera, sensor and water: returns to the last bit, every
    # observation and info; one episode's camera images
    pytest.importorskip("cv2")
    host = {k: v for k, v in os.environ.items() if k != "NUMBA_CPU_NAME"}
    run = [sys.executable, "-c", EPISODES]
    a = subprocess.run(run, env=host, check=True, capture_output=True, text=True).stdout
    b = subprocess.run(run, env=old_cpu(tmp_path), check=True, capture_output=True, text=True).stdout
    assert a == b and len(a.splitlines()) == 8


NO_FMA_LIBM = "glibc.cpu.hwcaps=-FMA,-FMA4"  # glibc's math functions as on an x86-64 CPU without FMA


def _libm_differs_without_fma() -> bool:
    """Whether masking FMA changes glibc's ``sin`` here (x86-64 glibc on a CPU with FMA)."""
    probe = "import math; print([math.sin(0.1 * k + 0.01).hex() for k in range(20000)])"
    plain = subprocess.run([sys.executable, "-c", probe], check=True, capture_output=True, text=True).stdout
    env = dict(os.environ, GLIBC_TUNABLES=NO_FMA_LIBM)
    run = [sys.executable, "-c", probe]
    masked = subprocess.run(run, env=env, check=True, capture_output=True, text=True)
    return plain != masked.stdout


@pytest.mark.slow  # the whole reproduction in a fresh interpreter (≈ 13 s)
@pytest.mark.xfail(
    strict=True,
    reason="compiled code calls the C library's exp, sin, cos, atan2, pow; glibc's variants for CPUs "
    "with and without FMA differ in rare last bits (75 of 100,000 exp calls), and training amplifies them: "
    "47 of the 95 rows of evaluation.csv differ (docs/decisions.md, 'Speed and portable numbers')",
)
def test_reproduction_with_the_c_librarys_math_of_a_cpu_without_fma_equals_the_committed_evaluation(
    tmp_path,
):
    if not _libm_differs_without_fma():
        pytest.skip("no glibc FMA variants to mask here (not x86-64 glibc, or a CPU without FMA)")
    env = dict(os.environ, GLIBC_TUNABLES=NO_FMA_LIBM)  # numba's target stays the host's
    assert _reproduce(tmp_path / "run", env) == COMMITTED.read_bytes()
