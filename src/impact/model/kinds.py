"""The kinds of damper: one entry each, read by the model's checks, the engine, the command line and the rules.

A kind is what its units are made of, not a name the engine branches on: a mass between walls a gap apart
(the CID), held by a spring tuned to the building (the PID's pendulum, the TMD's spring), with a dashpot, on a
floor it may slide on.  The engine builds a unit's arrays from these properties alone, so a new kind made of
the same parts (a tuned mass between walls, a damped pendulum) is one entry here; one with new physics is an
entry and that physics in the engine.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class DamperKind:
    """What a kind of damper unit is made of.

    name      the kind's key (Damper.kind, the command line's --damper, the rules' {damper})
    title     its name in words, for labels and help
    walls     its mass strikes walls a gap apart (an impact damper: gap and restitution apply)
    spring    its mass hangs on a spring tuned to the building (tuning applies; else tuning is ignored)
    dashpot   its spring has a dashpot (damping applies)
    slides    its mass rests on its floor and may slide there (Coulomb friction nu applies)
    paper     the paper's loop runs it (a one-unit damper alone on the paper's structure: model.params.System)
    tuning_flag  the command line's name of its spring's tuning (the paper's r' for a pendulum)
    """

    name: str
    title: str
    walls: bool
    spring: bool
    dashpot: bool
    slides: bool
    paper: bool
    tuning_flag: str = "tuning"


#: every kind, by name, in the order the study lists them
KINDS: dict[str, DamperKind] = {
    k.name: k
    for k in (
        DamperKind("cid", "classical impact damper", walls=True, spring=False, dashpot=False, slides=True,
                   paper=True),
        DamperKind("pid", "pendulum impact damper", walls=True, spring=True, dashpot=True, slides=False,
                   paper=True, tuning_flag="rp"),
        DamperKind("tmd", "tuned mass damper", walls=False, spring=True, dashpot=True, slides=False, paper=False),
    )
}


def _registered(name: str) -> str:
    return KINDS[name].name


#: The kinds the study compares, by name: the paper's two impact dampers and the tuned mass damper they are judged
#: against.  A plan that names one of them (the paper's figures, Table 1's columns, the study's designs) reads it
#: here; a branch on what a kind is made of reads its parts (``KINDS[name].walls``, ...), never its name, so a new
#: kind needs an edit of neither.
CID, PID, TMD = _registered("cid"), _registered("pid"), _registered("tmd")


def damper_kinds() -> tuple[str, ...]:
    """The kinds' names, in the registry's order (read at call time: a kind registered later is listed)."""
    return tuple(KINDS)


def kinds_with(part: str) -> tuple[str, ...]:
    """The kinds made with `part` ('walls', 'spring', 'dashpot', 'slides', 'paper'), in the registry's order."""
    return tuple(name for name, k in KINDS.items() if getattr(k, part))


def either(names) -> str:
    """Names as a message offers them: 'a', 'a or b', 'a or b or c'."""
    return " or ".join(names)


def impact_kinds() -> tuple[str, ...]:
    """The kinds with walls, whose units strike."""
    return kinds_with("walls")


def sliding_kinds() -> str:
    """The kinds whose mass may slide on its floor, as a message names them ('cid', or 'cid' or 'x')."""
    return either(map(repr, kinds_with("slides")))


def is_free_mass(name: str) -> bool:
    """Whether the kind is Masri's: a free mass between walls, with no spring (the CID), the one kind whose 2-EIPC
    steady state the closed form (impact.closed_form) knows."""
    k = KINDS[name]
    return k.walls and not k.spring


def kind_of(name: str) -> DamperKind:
    """The kind named `name`, which the Damper's check has found in the registry."""
    return KINDS[name]
