"""The learners by name: ``--algorithm NAME`` on the command line, ``algorithm = "NAME"`` in experiments.

Each entry is the :class:`~pipefollow.learners.protocol.LearnerKind` of one learner module; a new
learner is one module, one entry here and one in ``pipefollow.readings.apply.LEARNER_INPUTS`` (its
parameter record and grids under the readings). Their options are the one table
:data:`~pipefollow.learners.options.LEARNER_OPTIONS` (given here as :data:`LEARNER_OPTIONS`);
:func:`agent_options` turns the values of that table into what ``make_agent`` takes, the one way
the command line and experiment files do.
"""

from __future__ import annotations

from pipefollow.learners import actor_critic, cacla, sarsa
from pipefollow.learners.options import LEARNER_OPTIONS, OPTION, SWITCHES, check_value
from pipefollow.learners.protocol import LearnerKind

__all__ = ["LEARNERS", "LEARNER_OPTIONS", "NAMES", "agent_options", "check_options", "learner", "taking"]

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


def takes(kind: LearnerKind, option: str) -> bool:
    """Whether learner ``kind`` takes ``option``: its switches and step sizes; every learner σ and state."""
    group = OPTION[option].group
    if group == "switch":
        return option in kind.options
    if group == "step":
        return option in kind.step_sizes
    return True


def taking(option: str) -> tuple[str, ...]:
    """Names of the learners that take ``option`` of :data:`LEARNER_OPTIONS`."""
    return tuple(name for name, kind in LEARNERS.items() if takes(kind, option))


def agent_options(name: str, values: dict, strict: bool = True) -> dict:
    """What ``make_agent(name, ...)`` takes for the table's ``values`` (option name → value).

    Each value is checked (:meth:`~pipefollow.learners.options.LearnerOption.check`); the step
    sizes become the keywords of the learner's record, the σ schedule is left out (training takes
    it). A value other than its default for a learner that does not take it is refused — with
    ``strict=False`` (an experiment file's ``[defaults]`` serve every learner) only a switch.

    Raises:
        ValueError: a bad value (``critic_lambda must be in [0, 1], got 1.5``) or one the learner
            does not take (``critic_lambda applies to algorithm cacla and ac only``).
    """
    kind = learner(name)
    out = {}
    for option, value in values.items():
        o = OPTION[option]
        value = check_value(option, value)
        if not takes(kind, option):
            if value != o.default and (strict or o.group == "switch"):
                raise ValueError(f"{option} applies to algorithm {' and '.join(taking(option))} only")
            continue
        if o.group == "step":
            out[kind.step_sizes[option]] = value
        elif o.group != "schedule":
            out[option] = value
    return out


def check_options(name: str, **options) -> None:
    """Refuse a shared option that is set for a learner that does not take it.

    Raises:
        ValueError: e.g. ``skew_deg applies to algorithm cacla only``.
    """
    kind = learner(name)
    for option, off in SWITCHES.items():
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
    return {k: v for k, v in options.items() if k not in SWITCHES or k in kind.options}
