"""The learners by name: ``--algorithm NAME`` on the command line, ``algorithm = "NAME"`` in experiments.

Each entry is the :class:`~pipefollow.learners.protocol.LearnerKind` of one learner module; a new
learner is one module, one entry here and one in ``pipefollow.readings.apply.LEARNER_INPUTS`` (its
parameter record and grids under the readings).
"""

from __future__ import annotations

from pipefollow.learners import actor_critic, cacla, sarsa
from pipefollow.learners.protocol import OPTIONS, LearnerKind

LEARNERS: dict[str, LearnerKind] = {
    kind.name: kind for kind in (sarsa.LEARNER, cacla.LEARNER, actor_critic.LEARNER)
}
NAMES = tuple(LEARNERS)


def learner(name: str) -> LearnerKind:
    """The learner called ``name``.

    Raises:
        ValueError: no learner of that name.
    """
    try:
        return LEARNERS[name]
    except (KeyError, TypeError):
        raise ValueError(f"algorithm must be one of {', '.join(NAMES)}, got {name!r}") from None


def learner_of(agent) -> LearnerKind | None:
    """The learner of ``agent`` (by its ``algorithm`` and class), or None for other controllers."""
    kind = LEARNERS.get(getattr(agent, "algorithm", None))
    return kind if kind is not None and isinstance(agent, kind.agent_class) else None


def taking(option: str) -> tuple[str, ...]:
    """Names of the learners that take a shared option (:data:`~pipefollow.learners.protocol.OPTIONS`)."""
    return tuple(name for name, kind in LEARNERS.items() if option in kind.options)


def check_options(name: str, **options) -> None:
    """Refuse a shared option that is set for a learner that does not take it.

    Raises:
        ValueError: e.g. ``skew_deg applies to algorithm cacla only``.
    """
    kind = learner(name)
    for option, off in OPTIONS.items():
        if options.get(option, off) != off and option not in kind.options:
            raise ValueError(f"{option} applies to algorithm {' and '.join(taking(option))} only")


def options_for(name: str, **options) -> dict:
    """``options`` (shared options and step sizes) as learner ``name`` takes them.

    Options left at their off value (0, False, ``delta``) are dropped for learners that do not take them.

    Raises:
        ValueError: an unknown learner, or an option set for a learner that does not take it.
    """
    check_options(name, **options)
    kind = learner(name)
    return {k: v for k, v in options.items() if k not in OPTIONS or k in kind.options}
