"""The earthquake and wind study: the CID, PID and TMD on shear buildings under real and random loads.

Each building is uniform (equal floors and storeys), with the fundamental period and modal damping asked.
Each damper sits on the roof with a mass that is a fraction of the building's total mass:

* the CID and the PID (tuned to the fundamental, r' = 1) with the restitution asked, and a clearance sized from
  the bare building: d = g x (its peak roof displacement under the design-level load).  For a real record the
  design level is that record scaled to the design PGA; for the random loads, the median over the seeds at
  that level.  The gap ratio g is swept on the real records, and the best one (the lowest mean peak roof
  displacement over the records and intensities) is the design the random loads are run with;
* the TMD tuned to the first mode by Den Hartog's rules, with its mass ratio taken over the first mode's
  modal mass (mode shape 1 at the roof).

A ground-motion run lasts the record's length (the peaks come in the strong phase), a wind run its own
duration.  Every measure of a damped run is divided by the bare building's under the same load: peak and RMS roof
displacement, peak absolute roof acceleration, peak inter-storey drift.  Beside them the damper's stroke, its
impact count and the momentum it exchanges per impact.

Scale: a ground motion scaled by s with the gap d fixed is the motion at 1 with the gap d / s, scaled by s (the
dampers are linear between rigid impacts).  So only ratios of the gap to the response matter, and the wind's
absolute strength does not (its gap is sized from its own bare response).

The stage in three modules: :mod:`.plan` (buildings, dampers and loads from the configuration),
:mod:`.runs` (the runs on the engine) and :mod:`.tables` (datasets and tables, no simulation).
"""
