"""The names a user gives for pipes: one pipeline, or a set of pipes to benchmark on.

One pipeline (``evaluate --pipeline``, ``train --pipeline``): a built-in name, a JSON file,
``random[:FAMILY]`` (a new pipe of a training family every episode), or one pipe of a suite by
the name ``suites export`` gives its file, ``SUITE-KKK`` (``heldout-003``).

A set of pipes (``benchmark --suite``, ``compare --suite``): a suite name, or any number of
folders (every ``*.json`` in them), pipeline files and glob patterns — what ``pipefollow suites
export`` writes reads back as the same pipes, in the same order. Unknown names get a "did you
mean" from the names that exist.
"""

from __future__ import annotations

import difflib
import glob
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from pipefollow.sim.pipeline import BUILTIN_NAMES, Pipeline, PipelineError, load, resolve
from pipefollow.sim.suites import RANDOM_PREFIX, SUITES, Suite, SuiteError, min_length_for, parse_random_spec

_SUITE_PIPE = re.compile(r"(?P<suite>[a-z-]+)-(?P<k>\d+)")


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


def resolve_pipeline(spec: str, seconds: float) -> Pipeline | Suite:
    """One pipeline (module docstring): a :class:`Pipeline`, or a training :class:`Suite` for ``random``."""
    family = parse_random_spec(spec)
    if family is not None:
        return family
    if spec in BUILTIN_NAMES:
        return resolve(spec)
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
