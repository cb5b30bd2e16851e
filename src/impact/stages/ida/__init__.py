"""Incremental dynamic analysis on the FEMA P695 record suites: which damper limits the drift, and under which records.

The buildings are the earthquake study's (:mod:`impact.stages.loads`): uniform shear buildings of 1, 3 and 5 storeys
with fundamental periods T1 of 0.5, 1 and 2 s and 2 % modal damping, each storey `storey_height_m` high.  On the roof,
nothing (bare), a CID, a PID (r' = 1) or a TMD (Den Hartog, first mode) of each of the earthquake study's mass ratios.

Every ground motion of the FEMA P695 far-field set (44) and near-field set (56: 28 pulse-like, 28 not) is scaled,
one by one, so that its 5 %-damped spectral acceleration at the building's T1, Sa(T1) (computed exactly on the core,
:mod:`impact.engine.spectra`), takes each value of a ladder (Vamvatsikos & Cornell 2002).  Each run lasts the record's
length and measures the peak inter-storey drift ratio (drift over the storey height), the peak roof displacement, the
peak absolute roof acceleration, the damper's stroke, its impacts and the run's energy balance.

The impact dampers' clearance is sized as the earthquake study sizes it: d = g x (the bare building's peak roof
displacement at the design level), with g that study's design gap ratio for this building, damper and mass ratio
(the best of its swept ratios under its records), and the design level's peak taken as the median over the suite's
ground motions at Sa(T1) = `design_sa_g`.  One clearance per building, damper and mass ratio, as a built damper has.

The bare building and the TMD are linear: each ground motion runs once, at Sa(T1) = 1 g, and every level is that run
times the level (exact; tested).  The impact dampers are not: they run at every level.

The verdicts read the drift ratio of each damped run over the bare building's under the same ground motion and level,
as a distribution over the ground motions of each record group (far-field, near-field pulse, near-field no pulse):
its median reduction with a bootstrap interval that resamples records (both components of a record together, as they
are not independent), and the shares of ground motions where the damper lowers the peak drift by at least 10 % or
raises it by more than 5 %.  The probability of exceeding each drift limit against Sa(T1) is read empirically per
level and fitted by a lognormal distribution (maximum likelihood on the counts, Baker 2015).

Three modules: :mod:`.plan` (what runs, from the configuration), :mod:`.runs` (the runs on the engine) and
:mod:`.tables` (the collected dataset, verdicts and fragility fits; no simulation).
"""
