"""The sweep curves a stage plans, one way: the design charts' and the robustness designs' curves are both every
damper kind, restitution and mass ratio, and a tuning each for a kind with a spring.

A module of its own below both stages (not the model's params, which every rule reads: a rule's ``library`` digest
would then rerun the whole study for a planning helper that changes none of its numbers)."""

from __future__ import annotations

from impact.model.kinds import KINDS


def curve_specs(kinds, mus, es, tunings) -> list[dict]:
    """The sweep curves of every damper kind, restitution e and mass ratio mu (in that order), and of every tuning r'
    for a kind with a spring (sweeps.curve_system reads them; model.params.curve_id names them)."""
    return [{"damper": kind, "mu": mu, "e": e, **tuning} for kind in kinds for e in es for mu in mus
            for tuning in ([{"rp": rp} for rp in tunings] if KINDS[kind].spring else [{}])]
