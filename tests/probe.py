"""A seeded random probe of the scene engine: scenes a new user could draw, and what every run must satisfy.

draw_scene(rng) builds one scene: 1 to 4 storeys (uniform, or explicit with floor-to-floor mass and
stiffness ratios up to 1e2), 0 to 3 dampers of 1 to 6 units (CID, PID, TMD) on random floors, gaps from
1e-6 of the motion's scale to far beyond it, e anywhere in [0, 1], friction under some CIDs, tunings from
1e-2 to 1e3 (mostly 0.1 to 10; beyond MIN_TUNING and MAX_TUNING the model refuses them by name, as a user
would meet it), and one load (harmonic on a floor, a stretch of a real record, a
Kanai-Tajimi motion, or a narrow-band wind force).  violations(scene, result) lists every promise the run broke.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from impact.model.building import Building
from impact.model.records import kanai_tajimi, load_record, narrow_band_force
from impact.model.scene import Damper, ForceRecord, GroundMotion, Harmonic, Scene

RECORDS = ("elcentro", "lomaprieta", "northridge", "sanfernando")
#: the decades the probe's wide tunings are drawn from, wider than the model allows (those are refused by name);
#: fixed here, not read from the model's bounds, so that a scene's reproducer (its seed and index) stays the scene
DRAWN_TUNINGS = (-2.0, 3.0)
ENERGY_TOL = 1e-9        # energy residual over the energy scale ...
SEGMENT_ROUNDOFF = 1e-15  # ... plus this per segment: each one's exact integrals carry a few ulps, and a
                          # run of millions of segments (an elastic unit in a tiny gap) adds them up
PENETRATION_TOL = 1e-9   # beyond a wall and the round-off of the positions read there, over the motion's scale
SAMPLES = 4001           # dense output points per run for the peak check


#: how far the suite's probe draws: up to 4 storeys, 3 dampers, 6 units a damper
REACH = {"storeys": 4, "dampers": 3, "units": (1, 1, 2, 3, 6)}
#: how far the probe at scale (tools/probe_scenes.py) draws: up to 10 storeys, 4 dampers, 12 units
WIDE = {"storeys": 10, "dampers": 4, "units": (1, 1, 2, 3, 4, 6, 9, 12)}


def _building(rng, most_storeys: int) -> Building:
    storeys = int(rng.integers(1, most_storeys + 1))
    zeta = float(rng.uniform(0.005, 0.1))
    period = float(10 ** rng.uniform(-1, 0.5))
    if rng.random() < 0.5:
        return Building.uniform(storeys, period, zeta)
    base = Building.uniform(storeys, period, zeta)
    masses = base.masses * 10 ** rng.uniform(-1, 1, storeys)
    stiffness = base.storey_stiffness * 10 ** rng.uniform(-1, 1, storeys)
    if rng.random() < 0.5:
        return Building.explicit(masses, stiffness, zeta=zeta)
    w1 = Building.explicit(masses, stiffness, zeta=zeta).omega1
    return Building.explicit(masses, stiffness, storey_damping=2 * zeta * stiffness / w1)


def _load(rng, building: Building, seconds: float):
    """A load of about ``seconds`` and the motion's scale it is expected to cause (a static deflection, in m)."""
    w1 = building.omega1
    kind = rng.choice(["harmonic", "record", "kanai-tajimi", "wind"])
    if kind == "harmonic":
        force = building.total_mass * float(rng.uniform(0.05, 1.0))
        floor = int(rng.integers(1, building.storeys + 1))
        load = Harmonic(force, w1 * float(10 ** rng.uniform(-0.5, 0.5)), float(rng.uniform(-3, 3)), floor=floor)
        return load, force / (building.total_mass * w1 * w1)
    if kind == "record":
        record = load_record(str(rng.choice(RECORDS)))
        n = int(seconds / record.dt) + 1
        start = int(rng.integers(0, record.npts - n))
        accel = record.accel_g[start:start + n] * 9.80665
        if not np.any(accel):
            accel = record.accel_g[:n] * 9.80665
        pga = float(rng.uniform(0.05, 0.6)) * 9.80665
        return GroundMotion(accel * pga / np.max(np.abs(accel)), record.dt, record.name), pga / (w1 * w1)
    if kind == "kanai-tajimi":
        pga_g = float(rng.uniform(0.05, 0.6))
        record = kanai_tajimi(int(rng.integers(0, 1000)), seconds, 0.01,
                              soil=str(rng.choice(["firm", "medium", "soft"])), pga_g=pga_g,
                              envelope_params=(0.1 * seconds, 0.5 * seconds, 4.0 / seconds))
        return GroundMotion.from_record(record), pga_g * 9.80665 / (w1 * w1)
    rms = building.total_mass * float(rng.uniform(0.01, 0.2))
    force = narrow_band_force(int(rng.integers(0, 1000)), seconds, 0.02, centre_rad_s=w1, bandwidth=0.2, rms=rms)
    dist = np.linspace(1.0, 2.0, building.storeys)
    dist /= dist.sum()
    return ForceRecord(force, 0.02, dist, "wind"), 3 * rms / (building.total_mass * w1 * w1)


def _tuning(rng) -> float:
    """Mostly near the building's modes; one in five anywhere from 1e-2 to the largest allowed."""
    if rng.random() < 0.2:
        return float(10 ** rng.uniform(*DRAWN_TUNINGS))
    return float(10 ** rng.uniform(-1, 1))


def _damper(rng, building: Building, scale: float, units_from: tuple) -> Damper:
    kind = str(rng.choice(["cid", "pid", "tmd"]))
    mass = building.total_mass * float(10 ** rng.uniform(-3, -0.7))
    floor = int(rng.integers(1, building.storeys + 1))
    units = int(rng.choice(list(units_from)))
    if kind == "tmd":
        return Damper("tmd", mass=mass, tuning=_tuning(rng), damping=float(rng.uniform(0, 0.3)),
                      floor=floor, units=units)
    gap = scale * float(10 ** rng.uniform(-6, 2))
    e = float(rng.choice([0.0, 1.0, rng.uniform(0, 1)]))
    if kind == "pid":
        return Damper("pid", mass=mass, gap=gap, e=e, tuning=_tuning(rng), floor=floor,
                      units=units)
    nu = float(rng.uniform(0, 0.5)) if rng.random() < 0.3 else 0.0
    return Damper("cid", mass=mass, gap=gap, e=e, nu=nu, floor=floor, units=units)


def draw_scene(rng, seconds: float = 3.0, reach: dict = REACH) -> tuple[Scene, float]:
    """One random scene of about ``seconds`` and its motion's scale (metres), as far as ``reach`` goes."""
    building = _building(rng, reach["storeys"])
    load, scale = _load(rng, building, seconds)
    count = int(rng.integers(0, reach["dampers"] + 1))
    dampers = tuple(_damper(rng, building, scale, reach["units"]) for _ in range(count))
    start = str(rng.choice(["centre", "left", "right"]))
    duration = float(rng.uniform(0.3, 1.3)) * seconds if isinstance(load, Harmonic) else None
    return Scene(building, dampers, load, duration=duration, start=start), scale


def draw_yielding_scene(rng, seconds: float = 3.0, reach: dict = REACH) -> tuple[Scene, float]:
    """A scene of draw_scene on a building that yields: yield drifts from a fifth of the motion's scale to twice it
    (so that most runs yield and some never do), hardening 0 (perfectly plastic) or up to 0.2, storeys 2.5 to 5 m
    high, P-delta on half the buildings, and a collapse drift of 10 % of the height on every P-delta building and
    half the others."""
    scene, scale = draw_scene(rng, seconds, reach)
    n = scene.building.storeys
    hardening = 0.0 if rng.random() < 0.3 else float(rng.uniform(0.0, 0.2))
    building = scene.building.yielding(scale * 10 ** rng.uniform(-0.7, 0.3, n), hardening,
                                       storey_height=rng.uniform(2.5, 5.0, n), p_delta=bool(rng.random() < 0.5))
    collapse = 0.1 if rng.random() < 0.5 or building.p_delta else None  # one can fall over only with P-delta
    return replace(scene, building=building, collapse_drift_ratio=collapse), scale


YIELDING_SHARE = 0.25  # of the probe at scale's scenes, on buildings that yield (tools/probe_scenes.py --yielding)


def is_yielding(seed: int, index: int, share: float = YIELDING_SHARE) -> bool:
    """Whether the probe at scale's scene `index` of `seed` is on a building that yields."""
    return bool(np.random.default_rng([seed, index, 2]).random() < share)


def scene_of(seed: int, index: int, share: float = YIELDING_SHARE) -> tuple[Scene, float]:
    """The probe at scale's scene `index` of `seed` (its reproducer): a seed's elastic scenes are the ones it
    drew before yielding buildings existed."""
    if is_yielding(seed, index, share):
        return draw_yielding_scene(np.random.default_rng([seed, index, 1]), reach=WIDE)
    return draw_scene(np.random.default_rng([seed, index]), reach=WIDE)


def smallest_tangent(scene: Scene) -> float | None:
    """The building's post-yield stiffness nearest zero, |b k - P/h| over k (None: its storeys do not yield): near
    zero the exact flow loses digits (model.scene.MIN_TANGENT, docs/model.md), so the probe sorts its yielding
    scenes by it."""
    tangents = scene.post_yield_stiffness()
    if tangents is None:
        return None
    return float(np.min(np.abs(tangents) / scene.building.storey_stiffness))


def _monitor_rows(scene: Scene, q: np.ndarray, sign: float) -> list[np.ndarray]:
    """The monitors' displacement rows over samples (roof, drifts, first unit of each damper's stroke), each a
    position and the one below it (a floor's, a unit's floor's) combined: less it (sign -1), or, for their
    round-off, plus it (sign +1)."""
    nf = scene.building.storeys
    floors = q[:, :nf]
    below = np.concatenate([np.zeros((len(q), 1)), floors[:, :-1]], axis=1)
    firsts = np.cumsum([0] + [int(d.units) for d in scene.dampers])[:-1]
    strokes = [q[:, nf + first] + sign * q[:, scene.floor_index(d.floor)] for first, d in zip(firsts, scene.dampers)]
    return [floors[:, -1], *(floors + sign * below).T, *strokes]


def _sampled_peaks(scene: Scene, samples: dict) -> np.ndarray:
    """Each monitor's largest sample taken at the least it can be: its size less its round-off (the scene loop's
    q_roundoff, each position's, summed over a difference)."""
    values = _monitor_rows(scene, samples["q"], -1.0)
    noise = _monitor_rows(scene, samples.get("q_roundoff", np.zeros_like(samples["q"])), 1.0)
    return np.array([np.max(np.abs(r) - e) for r, e in zip(values, noise)])


def _stop(scene: Scene, diag: dict) -> str:
    """Why and where a run stopped early, in words ('event cap', 'event budget' or 'stall guard' first), with the
    unit's restitution and gap: a unit of e = 1 in a gap of nanometres reaches the budget by its nature, not by a
    defect."""
    if diag["stop_unit"] >= 0:
        _, damper = scene.unit_list()[diag["stop_unit"]]
        return (f"{diag['stopped_by']} at a {diag['stop_event']} of unit {diag['stop_unit']}: e = {damper.e:.2f}, "
                f"gap {damper.gap:.1e} m")
    return f"{diag['stopped_by']} at a {diag['stop_event']} of storey {diag['stop_storey']}"


def _roundoff(result) -> np.ndarray | float:
    """What each displacement monitor's certified peak is certified to (SceneResult.peak_roundoff, the roof's
    acceleration left out, as _sampled_peaks leaves it): the round-off of the rows its motion is written in, below
    which neither the peak search nor a sample of the same rows can tell two values apart."""
    if result.peak_roundoff is None:
        return 0.0
    return np.delete(result.peak_roundoff, 1)


def violations(scene: Scene, scale: float, result) -> list[str]:
    """Every promise the run broke: finished, finite, energy, penetration, no dense sample above a peak."""
    diag = result.diagnostics
    found = []
    stopped = diag["event_cap_reached"]
    if stopped:
        found.append(_stop(scene, diag))
    # a run stopped early reports its measures NaN, by design; its state stays finite
    if not np.all(np.isfinite(result.final_q)) or not (stopped or math.isfinite(result.peak_roof_displacement)):
        found.append("non-finite result")
    if not abs(diag["energy_residual"]) <= ENERGY_TOL + SEGMENT_ROUNDOFF * diag["segments"]:
        found.append(f"energy residual {diag['energy_residual']:.2e}")
    # an event is located on rows that carry their terms' round-off, as a peak is (contact.note_penetration)
    if not diag["penetration_beyond_roundoff"] <= PENETRATION_TOL * scale:
        found.append(f"penetration {diag['max_penetration'] / scale:.2e} of the scale, "
                     f"{diag['penetration_beyond_roundoff'] / scale:.2e} beyond its round-off")
    if diag["uncertified_peak_segments"]:
        found.append("uncertified peak")
    certified = np.concatenate([[result.peak_roof_displacement], result.peak_drifts, result.peak_strokes])
    sampled = _sampled_peaks(scene, result.samples)
    allowed = certified * (1 + 1e-9) + 1e-12 * scale + _roundoff(result)
    # a stroke between walls is certified at its cap, half the gap, from its first impact on (the engine stops
    # searching it there); a sample past the wall is penetration, which has its own bound above
    walls = np.array([0.5 * d.gap if d.kind in ("cid", "pid") else np.inf for d in scene.dampers])
    strokes = slice(len(certified) - len(walls), len(certified))
    allowed[strokes] = np.maximum(allowed[strokes], np.where(certified[strokes] >= walls, walls, -np.inf)
                                  + PENETRATION_TOL * scale)
    low = sampled > allowed
    if np.any(low):
        found.append(f"sample above a certified peak by {np.max(sampled[low] / certified[low] - 1):.2e}")
    return found
