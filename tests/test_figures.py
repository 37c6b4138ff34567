"""Figures drawn side by side in forked workers equal those drawn one after the other."""

from __future__ import annotations

import os

import numpy as np
import pytest

from pipefollow.experiments.figures import draw_figures, learning_curve_figure

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _curves(seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {"a": rng.normal(size=(3, 60)), "b": rng.normal(size=(2, 60))}


def test_figures_drawn_in_workers_are_the_bytes_drawn_here(tmp_path):
    serial, parallel = tmp_path / "serial", tmp_path / "parallel"
    serial.mkdir()
    parallel.mkdir()
    for i in range(3):
        learning_curve_figure(_curves(i), serial / f"f{i}.png", f"figure {i}", reference=-1.0)
    jobs = [
        (learning_curve_figure, (_curves(i), parallel / f"f{i}.png", f"figure {i}", -1.0)) for i in range(3)
    ]
    draw_figures(jobs, workers=2)
    for i in range(3):
        data = (parallel / f"f{i}.png").read_bytes()
        assert data[:8] == PNG_MAGIC
        assert data == (serial / f"f{i}.png").read_bytes()
    assert sorted(p.name for p in parallel.iterdir()) == ["f0.png", "f1.png", "f2.png"]  # no temporaries


def _fail(path):
    raise ValueError(f"cannot draw {path} in process {os.getpid()}")


def test_an_error_in_a_worker_reaches_the_caller(tmp_path):
    parent = os.getpid()
    with pytest.raises(ValueError, match="cannot draw x in process") as info:
        draw_figures([(_fail, ("x",)), (_fail, ("x",))], workers=2)
    assert f"process {parent}" not in str(info.value)  # raised in a worker, not here


def test_one_worker_draws_here(tmp_path):
    with pytest.raises(ValueError, match=f"in process {os.getpid()}"):
        draw_figures([(_fail, ("x",)), (_fail, ("y",))], workers=1)
