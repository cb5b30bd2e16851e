"""The exact event-driven core for scenes: shear buildings, damper units, loads.

A *scene* is a linear shear building of N storeys with any number of damper
units on its floors (CID, PID, TMD) under one load (a harmonic force, a
piecewise-linear force record or a piecewise-linear ground acceleration).
Between events the motion is linear with harmonic or polynomial forcing, so
every coordinate is known in closed form on a segment:

    q_i(tau) = Re sum_k C[i, k] exp(kap[k] tau) + P[i, 0] + P[i, 1] tau + P[i, 2] tau^2 + P[i, 3] tau^3

The package is split by concern:

- :mod:`.layout`   index constants shared by the kernels and the Python side
- :mod:`.segment`  closed-form flow: configurations (eigen-data), segments, evaluation, exact integrals
- :mod:`.events`   the certified contact search and the certified peak search
- :mod:`.contact`  simultaneous impacts (an LCP on each floor), sticking, release
- :mod:`.modal`    per-configuration tables: energy terms and monitors in a few multiply-adds per mode
- :mod:`.run`      the loop, calling the named steps of the other modules
- :mod:`.sampler`  dense output: the state at requested times

The one-storey, one-unit harmonic case keeps its specialised kernel
(:mod:`impact._kernels`); :mod:`impact.scene` dispatches.
"""
