"""Numerics shown, not assumed: error against run time, and stability on extreme cases.

Work-precision: every integrator (the exact core and the baselines of
:mod:`impact.baselines`) runs the same cases over a ladder of its own setting
(tolerance, step, contact stiffness); its errors are measured against the
exact core, and its wall time is the minimum of several repeats after a
warm-up (one timed run is enough for a run longer than a second).  Every run
has a budget of CPU time (the machine's other load is no slowness): over it,
the run is recorded as failed, "too slow at this setting".  The work splits into one piece per case and method family
(:data:`FAMILIES`), which the workflow runs as parallel jobs and
:func:`combine_work_precision` joins.  For the irregular (chaotic) case the predictability horizon is
measured first (runs perturbed at round-off diverge) and errors are compared
only inside it.

Stability: every method on extreme inputs (e -> 0 and 1, gap -> 0, no or tiny
damping, extreme mass ratios, a very stiff pendulum, grazing forcing, large
friction): finished or failed, finite or not, penetration, impacts per
period, wall time.  A baseline's failure is recorded, never hidden.

The stage in three modules: :mod:`.plan` (cases, ladders, budgets, pieces), :mod:`.runs` (the timed runs
on the engine and the baselines) and :mod:`.tables` (tables and verdicts, no simulation).
"""
