"""How it is simulated: the exact event-driven engine (numba).

Between events every model of the study is linear with harmonic or polynomial forcing, so every coordinate is
known in closed form on a segment:

    q_i(tau) = Re sum_k C[i, k] exp(kap[k] tau) + P[i, 0] + P[i, 1] tau + P[i, 2] tau^2 + P[i, 3] tau^3

Events (impacts, releases, stops of a slide) are the certified first exits of such functions from a band, so none
is missed, and integrals over a segment (work, dissipation, the square of a response) are exact.

By concern:

- :mod:`.layout`       index constants of both loops' arrays (one layout)
- :mod:`.segment`      closed-form flow: configurations (eigen-data), segments, evaluation, exact integrals
- :mod:`.events`       the certified contact search and the certified peak search
- :mod:`.contact`      simultaneous impacts (an LCP on each floor), sticking, release
- :mod:`.modal`        per-configuration tables: energy terms and monitors in a few multiply-adds per mode
- :mod:`.scene_loop`   the loop for scenes, calling the named steps of the modules above
- :mod:`.paper_loop`   the paper's one-storey, one-unit harmonic case, a specialised loop on the shared search
- :mod:`.sampler`      dense output: the state at requested times
- :mod:`.diagnostics`  a run's diagnostics as named numbers and its energy balance
- :mod:`.jitcache`     numba's on-disk cache kept honest, and the compile lock
- :mod:`.paper`        the paper loop's side of the paper's system (:class:`impact.model.params.System`)
- :mod:`.scenes`       runs of scenes (:class:`impact.model.scene.Scene`) on the scene loop
- :mod:`.run`          the one entry point, :func:`.run.simulate`: its table LOOPS picks the loop a scene needs;
                       :func:`.run.simulate_system` and :func:`.run.sweep` run the paper's system through it

See ``docs/architecture.md`` for where the engine sits and ``docs/model.md`` for what it solves.

The public names (:func:`simulate`, :func:`simulate_system`, :func:`sweep`, the result types, :func:`spectral_acceleration`) load on first use (``__init__.pyi`` lists them): importing one module of the engine does not import the rest.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
