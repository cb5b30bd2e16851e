"""Table 1 of the paper in numbers: how a damper's X_m moves with what its designer does not control.

A :class:`Design` is one damper on the paper's one-storey structure (model units: M = 1, K = 1, so the
structure's frequency is 1), at its design point: the CID and PID at their optimum gap ratio, the TMD at
its equal-peak optimum.  Every measure is the paper's X_m, the largest protocol amplitude over a grid of
forcing frequencies divided by the bare structure's resonant amplitude, taken under changed conditions on
the exact engine (:func:`impact.engine.run.simulate`, which runs the undamped CID and PID, described through an
exact similarity as the paper's system (:func:`paper_system`), on its paper loop):

* the force amplitude scaled by s with the physical gap left as designed (Table 1, row 9);
* the structure's frequency drifted by a factor 1 + delta through its stiffness, the damper left as
  designed, so that its own frequency over the structure's becomes tuning / (1 + delta) (row 6).  X_m is
  then over the drifted structure's own A_max, and the frequency grid is relative to its own frequency,
  so that a damper that loses its tuning shows it, and a stiffer structure is not credited for being stiff;
* the damper's damping ratio (the TMD's beta_t; the PID's pendulum damping, zero in the paper) (row 7);
* the coefficient of restitution (row 10);
* the damper's stroke: its largest displacement relative to the structure over the run (row 5).

The stage in three modules: :mod:`.designs` (the designs, plain data), :mod:`.runs` (their runs on the
engine and datasets) and :mod:`.table` (Table 1 from the datasets).
"""
