"""What there is to choose from: the pipelines and the trials of an experiment, as rows.

``pipefollow pipelines`` and ``pipefollow trials`` print these rows as a table or as JSON. The
pipeline listing is open: a module that brings more named pipelines (a suite of layouts, say)
adds a source with :func:`add_pipeline_source`, and its entries appear after the built-ins.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass

from pipefollow.experiments.config import ExperimentConfig
from pipefollow.experiments.schema import learner_values
from pipefollow.learners.options import describe
from pipefollow.sim.pipeline import BUILTIN_NAMES, Pipeline, builtin


@dataclass(frozen=True)
class PipelineEntry:
    """One named pipeline.

    Attributes:
        name: what ``--pipeline`` and experiment files accept.
        group: where it comes from (``built-in``, or a suite's name).
        segments: number of straight segments.
        length_m: total length (m).
        description: one line.
    """

    name: str
    group: str
    segments: int
    length_m: float
    description: str


BUILTIN_DESCRIPTIONS = {
    "paper-left": "2 m, 2.5 m, 8 m with two 90° left turns (paper §4.1, training)",
    "paper-right": "mirror image of paper-left: two 90° right turns (paper §4.2, training)",
    "paper-validation": "±45° and ±90° turns, segments 3.5-6 m, an 8-m run-out (paper §4.2, validation)",
}


def entry(pipeline: Pipeline, group: str, description: str = "", name: str | None = None) -> PipelineEntry:
    """The listing entry of ``pipeline`` (under ``name``, default its own)."""
    return PipelineEntry(
        name=pipeline.name if name is None else name,
        group=group,
        segments=len(pipeline.points) - 1,
        length_m=round(pipeline.length, 6),
        description=description,
    )


def _builtins() -> list[PipelineEntry]:
    return [entry(builtin(n), "built-in", BUILTIN_DESCRIPTIONS.get(n, "")) for n in BUILTIN_NAMES]


def _random_families() -> list[PipelineEntry]:
    """``random:FAMILY`` for every training family: a new pipe each episode (its first pipe shown)."""
    from pipefollow.sim.suites import SUITES

    return [
        entry(
            s.pipe(0),
            "random family",
            f"{s.description} — a new pipe every episode; first: {s.pipe(0).name}",
            name=f"random:{s.name}",
        )
        for s in SUITES.values()
        if s.is_training
    ]


_SOURCES: list[Callable[[], Iterable[PipelineEntry]]] = [_builtins, _random_families]


def add_pipeline_source(source: Callable[[], Iterable[PipelineEntry]]) -> None:
    """Add a function that returns more pipeline entries (idempotent)."""
    if source not in _SOURCES:
        _SOURCES.append(source)


def pipelines() -> list[PipelineEntry]:
    """Every named pipeline: the built-ins first, then those of the added sources."""
    return [e for source in _SOURCES for e in source()]


def _phase_row(p) -> dict:
    """A phase as ``trials`` lists it: pipeline, episodes and its own learner options if any."""
    row = {"pipeline": p.pipeline, "episodes": p.episodes}
    return row | {"learner": dict(p.learner)} if p.learner else row


def trials(exp: ExperimentConfig) -> list[dict]:
    """One row per trial of ``exp``: name, label, algorithm, options, phases, episodes, repeats.

    ``options`` names the learner options (:data:`~pipefollow.learners.options.LEARNER_OPTIONS`)
    set away from their defaults, the readings, and the evaluation's camera, sensor and water
    away from the paper's; a phase with its own options lists them (``learner``).
    """
    rows = []
    for t in exp.trials:
        options = [describe(learner_values(t))] if describe(learner_values(t)) else []
        options += [f"readings {t.reading.id}"] * (t.reading.id != "default")
        options += _seeing(t)
        rows.append(
            {
                "name": t.name,
                "label": t.title,
                "algorithm": t.algorithm,
                "options": ", ".join(options),
                "phases": [_phase_row(p) for p in t.phases],
                "episodes": t.episodes,
                "repeats": exp.repeats,
                "evaluate_on": t.evaluate_on,
                "camera": t.camera,
                "sensor": t.sensor,
                "water": t.water,
                "figures": list(t.figures),
            }
        )
    return rows


def _seeing(t) -> list[str]:
    """The evaluation's camera, sensor and water where a trial sets them (``camera vision``, ...)."""
    seeing = [f"camera {t.camera}"] * (t.camera != "ideal") + [f"sensor {t.sensor}"] * (t.sensor != "camera")
    if isinstance(t.water, dict):
        seeing.append("water " + " ".join(f"{k}={v}" for k, v in t.water.items()))
    elif t.water:
        seeing.append(f"water {t.water}")
    return seeing


def pipeline_rows(entries: Sequence[PipelineEntry]) -> list[dict]:
    """Plain-data form of pipeline entries (for JSON)."""
    return [asdict(e) for e in entries]


def table(rows: Sequence[dict], columns: Sequence[tuple[str, str]]) -> str:
    """A plain text table of ``rows``: ``columns`` are (key, heading); numbers align right."""
    cells = [[_cell(r[k]) for k, _ in columns] for r in rows]
    widths = [max([len(h)] + [len(c[i]) for c in cells]) for i, (_, h) in enumerate(columns)]
    numeric = [all(isinstance(r[k], (int, float)) for r in rows) and rows for k, _ in columns]

    def line(values):
        return "  ".join(
            v.rjust(w) if num else v.ljust(w) for v, w, num in zip(values, widths, numeric, strict=True)
        ).rstrip()

    return "\n".join([line([h for _, h in columns])] + [line(c) for c in cells])


def _learner(values: dict | None) -> str:
    """A phase's own learner options as ``trials`` shows them (`` (actor_repeats var)``)."""
    return f" ({describe(values)})" if values else ""


def _cell(value) -> str:
    if isinstance(value, float):
        return f"{value:.2f}"
    if isinstance(value, list):
        return " then ".join(f"{p['pipeline']} ×{p['episodes']}" + _learner(p.get("learner")) for p in value)
    return str(value)
