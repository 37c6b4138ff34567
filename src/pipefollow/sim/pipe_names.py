"""The pipes a user names: one pipeline, a pipeline or a family of random pipes, a set of pipes.

This module is the one place where what a user gives for a pipe becomes pipes. The forms:

* a :class:`~pipefollow.sim.pipeline.Pipeline`, or its points: ``[[x, y], ...]`` (m, north and
  east) or an (n, 2) array, as in a pipeline file's ``"points"``;
* a built-in name (:data:`~pipefollow.sim.pipeline.BUILTIN_NAMES`);
* a pipeline file (JSON);
* ``random[:FAMILY]``: a new pipe of a training family every episode (``random`` alone is
  ``mixed``; a held-out suite is refused, training on it would spoil the test);
* one pipe of a suite by the name ``suites export`` gives its file, ``SUITE-KKK`` (``heldout-003``);
* for a set of pipes: a suite name, or any number of folders (every ``*.json`` in them), pipeline
  files and glob patterns — what ``pipefollow suites export`` writes reads back as the same
  pipes, in the same order.

The entry points, one for each need, share :func:`parse_random_spec` and the fixed forms
(a pipeline, its points, a built-in name):

* :func:`resolve_fixed`: one fixed pipeline (a pipeline, its points, a built-in name, a file);
* :func:`resolve_training`: that, or a training family (``random[:FAMILY]``) — what training and
  the experiments' trials take; :func:`pipeline_source` adds the pipe an environment shows
  before its first reset;
* :func:`resolve_pipeline`: the command line's one pipeline (``evaluate --pipeline``): a built-in
  name, ``random[:FAMILY]``, a suite pipe or a file;
* :func:`resolve_suite`: the command line's set of pipes (``benchmark --suite``, ``compare
  --suite``).

Unknown names on the command line get a "did you mean" from the names that exist.
"""

from __future__ import annotations

import difflib
import glob
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipefollow.sim.pipeline import BUILTIN_NAMES, Pipeline, PipelineError, _validated_points, builtin, load
from pipefollow.sim.suites import SUITES, Suite, SuiteError, get_suite, min_length_for

RANDOM_PREFIX = "random"
DEFAULT_TRAIN_FAMILY = "mixed"
_SUITE_PIPE = re.compile(r"(?P<suite>[a-z-]+)-(?P<k>\d+)")


def is_points(spec) -> bool:
    """Whether ``spec`` is a polyline given as numbers, shape (n, 2) (``[[0, 0], [5, 0], [5, 5]]``)."""
    if not isinstance(spec, list | tuple | np.ndarray):
        return False
    try:
        arr = np.asarray(spec, dtype=np.float64)
    except (TypeError, ValueError):
        return False
    return arr.ndim == 2 and arr.shape[1] == 2


def parse_random_spec(spec) -> Suite | None:
    """The training family of ``random`` / ``random:NAME``, or ``None`` if ``spec`` is something else.

    ``random`` alone means the ``mixed`` family. A held-out suite is refused: training on it would
    spoil the test.
    """
    if not isinstance(spec, str) or not (spec == RANDOM_PREFIX or spec.startswith(RANDOM_PREFIX + ":")):
        return None
    name = spec.partition(":")[2] or DEFAULT_TRAIN_FAMILY
    suite = get_suite(name)
    if not suite.is_training:
        families = ", ".join(n for n, s in SUITES.items() if s.is_training)
        raise SuiteError(f"pipeline '{spec}': '{name}' is a held-out suite; train on one of {families}")
    return suite


def _fixed(spec) -> Pipeline | None:
    """The pipeline ``spec`` is without files: a pipeline, its points or a built-in name; else None."""
    if isinstance(spec, Pipeline):
        return spec
    if isinstance(spec, list | tuple | np.ndarray):
        return Pipeline(_validated_points(spec, "pipeline points"), "pipeline points")
    if isinstance(spec, str) and spec in BUILTIN_NAMES:
        return builtin(spec)
    return None


def resolve_fixed(spec) -> Pipeline:
    """One fixed pipeline: a :class:`Pipeline`, its points, a built-in name or a pipeline file."""
    pipe = _fixed(spec)
    if pipe is not None:
        return pipe
    path = Path(spec)
    if path.suffix.lower() != ".json" and not path.exists():
        raise PipelineError(
            f"pipeline '{spec}': not a built-in ({', '.join(BUILTIN_NAMES)}) and no such file"
        )
    return load(path)


def resolve_training(spec) -> Pipeline | Suite:
    """A fixed pipeline (:func:`resolve_fixed`) or a training family (``random[:NAME]``).

    A suite pipe's name (``heldout-003``) is refused with the ways to use it: suite pipes are for
    judging a policy (the environments and ``evaluate`` take them, :func:`pipeline_source`).
    """
    family = parse_random_spec(spec)
    if family is not None:
        return family
    if isinstance(spec, str) and not Path(spec).exists():
        m = _SUITE_PIPE.fullmatch(spec)
        if m is not None and m.group("suite") in SUITES:
            raise PipelineError(
                f"pipeline '{spec}': a suite's pipe is for judging a policy (evaluate --pipeline, benchmark "
                "--suite, the environments' pipeline=); train on random:FAMILY, a built-in or a pipeline file"
            )
    return resolve_fixed(spec)


def pipeline_source(spec, seconds: float | None = None) -> tuple[Suite | None, Pipeline]:
    """The training family of ``spec`` (or None) and the pipeline to show before the first reset.

    ``spec`` is what :func:`resolve_training` takes, and with ``seconds`` (the environments' episode)
    a suite pipe ``SUITE-KKK`` too, as long as that episode needs (:func:`suite_pipe_by_name`, as
    ``evaluate --pipeline`` takes it): held-out pipes are there to judge a policy on, and a fixed
    pipe cannot be drawn by training on a family. Until the first reset, a family shows its first pipe.
    """
    if seconds is not None and isinstance(spec, str):
        pipe = suite_pipe_by_name(spec, seconds)
        if pipe is not None:
            return None, pipe
    resolved = resolve_training(spec)
    if isinstance(resolved, Suite):
        return resolved, resolved.pipe(0)
    return None, resolved


def did_you_mean(name: str, choices: Sequence[str]) -> str:
    """``" (did you mean 'x'?)"`` for the closest of ``choices``, or ``""`` if none is close."""
    close = difflib.get_close_matches(name, list(choices), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def pipeline_names() -> list[str]:
    """The names of one pipeline, without files: built-ins, ``random[:FAMILY]``, ``SUITE-KKK`` forms."""
    families = [f"{RANDOM_PREFIX}:{n}" for n, s in SUITES.items() if s.is_training]
    return [*BUILTIN_NAMES, RANDOM_PREFIX, *families]


def suite_pipe_by_name(spec: str, seconds: float) -> Pipeline | None:
    """Pipe ``k`` of suite ``S`` for ``spec`` = ``S-k`` (as ``suites export`` names it), else None.

    The pipe is as long as :func:`~pipefollow.sim.suites.min_length_for` ``seconds`` asks, as in
    ``benchmark``; a shorter one is a prefix of a longer one.
    """
    m = _SUITE_PIPE.fullmatch(spec)
    if m is None or m.group("suite") not in SUITES:
        return None
    suite, k = SUITES[m.group("suite")], int(m.group("k"))
    if suite.count is not None and k >= suite.count:
        raise SuiteError(f"pipeline '{spec}': suite '{suite.name}' has pipes 0 to {suite.count - 1}")
    return suite.pipe(k, min_length_for(seconds))


def resolve_pipeline(spec, seconds: float) -> Pipeline | Suite:
    """The command line's one pipeline: a :class:`Pipeline`, or a training :class:`Suite` for ``random``.

    Besides what :func:`resolve_training` takes, a suite pipe ``SUITE-KKK`` (as long as an episode
    of ``seconds`` needs); a folder or an unknown name is refused with a hint.
    """
    family = parse_random_spec(spec)
    if family is not None:
        return family
    pipe = _fixed(spec)
    if pipe is None:
        pipe = suite_pipe_by_name(spec, seconds)
    if pipe is not None:
        return pipe
    path = Path(spec)
    if path.is_file() or path.suffix.lower() == ".json":
        return load(path)
    if path.is_dir():
        raise PipelineError(f"pipeline '{spec}': a folder; give one pipeline file (a folder is a --suite)")
    hint = did_you_mean(spec, pipeline_names())
    raise PipelineError(
        f"pipeline '{spec}': not a built-in ({', '.join(BUILTIN_NAMES)}), random[:FAMILY], "
        f"a suite pipe (e.g. heldout-003) nor a file{hint}"
    )


@dataclass(frozen=True)
class FileSuite:
    """Pipes read from pipeline files, in the order given (files of a folder or a glob sorted by name).

    Attributes:
        name: the folder's name if all files come from one folder, else ``"files"``.
        files: the pipeline files.
    """

    name: str
    files: tuple[Path, ...]
    is_training = False

    @property
    def count(self) -> int:
        """Number of pipes."""
        return len(self.files)

    def pipes(self, n: int | None = None, min_length: float = 0.0) -> list[Pipeline]:
        """The first ``n`` pipes (all by default), as the files hold them (``min_length`` is not applied)."""
        return [load(f) for f in self.files[: self.count if n is None else n]]


def _files_of(spec: str) -> list[Path]:
    path = Path(spec)
    if path.is_dir():
        files = sorted(path.glob("*.json"))
        if not files:
            raise PipelineError(f"suite '{spec}': a folder without pipeline files (*.json)")
        return files
    if path.is_file():
        return [path]
    if glob.has_magic(spec):
        files = sorted(Path(p) for p in glob.glob(spec) if Path(p).is_file())
        if not files:
            raise PipelineError(f"suite '{spec}': the pattern matches no file")
        return files
    hint = did_you_mean(spec, list(SUITES))
    raise SuiteError(
        f"suite '{spec}': not a suite ({', '.join(SUITES)}), a folder, a pipeline file nor a pattern{hint}"
    )


def resolve_suite(specs: str | Sequence[str]) -> Suite | FileSuite:
    """A set of pipes (module docstring): a suite name alone, or folders, files and patterns."""
    specs = [specs] if isinstance(specs, str) else list(specs)
    if not specs:
        raise SuiteError("no suite given")
    if len(specs) == 1 and specs[0] in SUITES:
        return SUITES[specs[0]]
    named = [s for s in specs if s in SUITES]
    if named:
        raise SuiteError(f"suite '{named[0]}': a suite name cannot be combined with files or folders")
    files = [f for s in specs for f in _files_of(s)]
    folders = {f.parent.resolve() for f in files}
    name = next(iter(folders)).name if len(folders) == 1 and Path(specs[0]).is_dir() else "files"
    return FileSuite(name, tuple(files))
