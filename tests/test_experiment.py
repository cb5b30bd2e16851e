"""Experiment records and the analysis chain (impact.stages.validation).

Every test compares against an independent closed form (SDOF frequency
response, exact free decay, the impact law of model.md) or a deliberately
malformed file, so each one can fail.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from impact.outputs.measurements import (
    MeasurementError,
    load_measurement,
    load_measurements,
    make_measurement,
    write_measurement,
)
from impact.outputs.signals import (
    ASSUMED_SENSOR_NOISE_MM,
    UnresolvedPeakError,
    beta_to_delta,
    count_impacts,
    delta_to_beta,
    drop_test_restitution,
    free_decay_delta,
    half_power,
    half_power_damping,
    impacts_per_cycle,
    log_decrement,
    rebound_height,
    restitution_from_drop,
    steady_amplitude,
    sweep_curve,
)

F_STRUCT = 1.5  # Hz, the paper's rig
G = 9.80665


def sdof_amplitude(r, beta):
    """Exact steady amplitude ratio of a linear SDOF oscillator."""
    r = np.asarray(r, dtype=float)
    return 1.0 / np.sqrt((1.0 - r**2) ** 2 + (2.0 * beta * r) ** 2)


def free_decay(t, x0, beta, f=F_STRUCT, offset=0.0):
    """Exact free decay of a viscously damped SDOF released from rest at x0."""
    wn = 2.0 * math.pi * f
    s = beta * wn
    wd = wn * math.sqrt(1.0 - beta**2)
    return x0 * np.exp(-s * t) * (np.cos(wd * t) + s / wd * np.sin(wd * t)) + offset


PAPER_GRID = np.round(np.arange(0.9, 1.1 + 1e-9, 0.01), 10)  # the experiment's sweep, 21 points


# ----------------------------------------------------------------------------
# half-power damping
# ----------------------------------------------------------------------------


def test_paper_grid_has_21_points_and_hits_r_1():
    assert PAPER_GRID.size == 21 and 1.0 in PAPER_GRID


def test_half_power_paper_grid_beta_0048():
    # bandwidth 2 beta = 0.0096 ~ one grid step: resolved only because the
    # grid hits the peak (r = 1.00); the local 1/A^2 interpolation recovers it
    beta = 0.0048
    res = half_power(PAPER_GRID, sdof_amplitude(PAPER_GRID, beta))
    assert res.resolved
    assert res.beta == pytest.approx(beta, rel=0.02)
    assert half_power_damping(PAPER_GRID, sdof_amplitude(PAPER_GRID, beta)) == pytest.approx(beta, rel=0.02)


def test_half_power_paper_grid_cannot_resolve_beta_00048():
    # half-power bandwidth 0.00096 is ~1/10 of the 0.01 step: refused
    beta = 0.00048
    amp = sdof_amplitude(PAPER_GRID, beta)
    with pytest.raises(UnresolvedPeakError, match="does not resolve"):
        half_power_damping(PAPER_GRID, amp)
    # reading the curve as drawn (straight lines between points) gives a
    # bandwidth set by the grid, not by the damping: beta ~ 0.003, 6x too large
    lin = half_power(PAPER_GRID, amp, method="linear", strict=False)
    assert not lin.resolved
    assert lin.beta > 5 * beta
    assert lin.step_over_bandwidth > 1


def test_half_power_unresolved_estimate_is_noise_dominated():
    # strict=False still returns the model-based number; on exact SDOF data it
    # happens to be right, but 1 % amplitude noise with the resonance anywhere
    # between grid points makes it useless -- the reason strict is the default
    beta = 0.00048
    rng = np.random.default_rng(3)
    errs = []
    for shift in rng.uniform(-0.005, 0.005, 60):
        amp = sdof_amplitude(PAPER_GRID / (1 + shift), beta) * (1 + 0.01 * rng.standard_normal(PAPER_GRID.size))
        res = half_power(PAPER_GRID, amp, strict=False)
        assert not res.resolved
        errs.append(abs(res.beta / beta - 1) if math.isfinite(res.beta) else np.inf)
    assert np.median(errs) > 0.1


def test_half_power_grid_phase_matters_for_beta_0048():
    # the same 0.01 step with the resonance midway between two samples: no
    # sample lies inside the half-power band -> refused
    r = PAPER_GRID + 0.005
    with pytest.raises(UnresolvedPeakError):
        half_power(r, sdof_amplitude(r, 0.0048))


@pytest.mark.parametrize("beta, step", [(0.0048, 0.001), (0.0048, 0.005), (0.00048, 0.0001), (0.00048, 0.0005)])
def test_half_power_fine_grid_any_phase(beta, step):
    # step <= bandwidth / 2 (= beta) resolves the band wherever the peak falls
    for phase in np.linspace(0.0, 1.0, 7, endpoint=False):
        r = np.arange(0.9 + phase * step, 1.1, step)
        res = half_power(r, sdof_amplitude(r, beta))
        assert res.resolved
        assert res.beta == pytest.approx(beta, rel=0.02)
        assert res.r_peak == pytest.approx(math.sqrt(1 - 2 * beta**2), abs=0.1 * beta)


def test_half_power_linear_reading_needs_much_finer_grid():
    # plain linear interpolation (as read off a plot) is within 2 % only for step <~ bandwidth/10
    beta = 0.00048
    r = np.arange(0.9, 1.1, 0.0001)
    assert half_power(r, sdof_amplitude(r, beta), method="linear").beta == pytest.approx(beta, rel=0.02)
    # step = bandwidth / 2 with the peak midway between samples: ~30 % off (the local method: exact)
    r = np.arange(0.9 + 0.00025, 1.1, 0.0005)
    assert abs(half_power(r, sdof_amplitude(r, beta), method="linear").beta / beta - 1) > 0.1
    assert half_power(r, sdof_amplitude(r, beta)).beta == pytest.approx(beta, rel=1e-4)


def test_half_power_refuses_peak_at_edge():
    r = np.linspace(0.9, 0.99, 10)
    with pytest.raises(UnresolvedPeakError, match="edge"):
        half_power(r, sdof_amplitude(r, 0.0048))


# ----------------------------------------------------------------------------
# log decrement
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("beta", [0.00048, 0.0048])
@pytest.mark.parametrize("x0", [10.0, 25.0])
def test_log_decrement_noise_free_exact(beta, x0):
    t = np.arange(0.0, 40.0, 0.01)
    x = free_decay(t, x0, beta, offset=0.3)  # with a sensor zero offset
    res = log_decrement(t, x)
    expected = 2 * math.pi * beta / math.sqrt(1 - beta**2)
    assert res.mean == pytest.approx(expected, rel=1e-6)
    np.testing.assert_allclose(res.delta, expected, rtol=1e-6)
    # window amplitudes are the exact envelope x0 sqrt(1 + (s/wd)^2) exp(-s t)
    wn = 2 * math.pi * F_STRUCT
    s, wd = beta * wn, wn * math.sqrt(1 - beta**2)
    env = x0 * math.sqrt(1 + (s / wd) ** 2) * np.exp(-s * res.window_t)
    np.testing.assert_allclose(res.window_amplitude, env, rtol=1e-6)
    np.testing.assert_allclose(res.frequency, wd / (2 * math.pi), rtol=1e-6)
    assert res.cycles == 1 and res.delta.size == res.amplitude.size == res.t.size


@pytest.mark.parametrize("x0", [10.0, 25.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_log_decrement_with_sensor_noise(x0, seed):
    # the rig's structure, beta = 0.00048 (delta = 0.003), 100 Hz, 60 s, 0.01 mm rms noise
    beta = 0.00048
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 60.0, 0.01)
    x = free_decay(t, x0, beta, offset=-0.2) + ASSUMED_SENSOR_NOISE_MM * rng.standard_normal(t.size)
    res = log_decrement(t, x)
    assert res.mean == pytest.approx(beta_to_delta(beta), rel=0.05)
    assert delta_to_beta(res.mean) == pytest.approx(beta, rel=0.05)
    assert np.all(np.abs(res.amplitude / free_decay(0, x0, beta) - 1) < 0.3)


def test_log_decrement_min_amplitude_and_bad_input():
    t = np.arange(0.0, 40.0, 0.01)
    x = free_decay(t, 20.0, 0.0048)
    res = log_decrement(t, x, min_amplitude=12.0)
    assert np.all(res.amplitude >= 12.0) and res.amplitude.size < log_decrement(t, x).amplitude.size
    with pytest.raises(ValueError, match="increasing"):
        log_decrement(t[::-1], x)
    with pytest.raises(ValueError, match="cycles"):
        log_decrement(t[:100], x[:100])


def test_beta_delta_conversion():
    assert beta_to_delta(0.00048) == pytest.approx(0.003016, rel=1e-4)  # the paper's delta = 0.003
    assert delta_to_beta(beta_to_delta(0.05)) == pytest.approx(0.05, rel=1e-12)


# ----------------------------------------------------------------------------
# drop tests (Eq. 3b, x'_- = 0)
# ----------------------------------------------------------------------------

MUS = (0.0054, 0.0129, 0.0252)  # the paper's balls, diameters 30, 40, 50 mm
HEIGHTS = (25.0, 50.0, 100.0)  # cm


def impact_law_rebound(h_drop_cm, e, mu):
    """Rebound height from the impact law of model.md (Eq. 3a, 3b), struck body at rest."""
    ym = -math.sqrt(2 * G * h_drop_cm / 100)  # ball velocity before impact (towards the plate)
    xm = 0.0
    yp = (1 + e) / (1 + mu) * xm + (mu - e) / (1 + mu) * ym
    xp = (1 - mu * e) / (1 + mu) * xm + mu * (1 + e) / (1 + mu) * ym
    assert yp - xp == pytest.approx(-e * (ym - xm))  # the law reverses the relative velocity
    assert yp > 0
    return 100 * yp**2 / (2 * G)


@pytest.mark.parametrize("e", [0.37, 0.46, 0.58, 0.64])
def test_restitution_recovers_e_from_impact_law(e):
    hd = np.array([h for _ in MUS for h in HEIGHTS])
    mu = np.array([m for m in MUS for _ in HEIGHTS])
    hr = np.array([impact_law_rebound(h, e, m) for h, m in zip(hd, mu)])
    np.testing.assert_allclose(rebound_height(hd, e, mu), hr, rtol=1e-12)
    est = restitution_from_drop(hd, hr, mu)
    np.testing.assert_allclose(est, e, rtol=1e-10)
    # with reading noise on the rebound height (0.1 cm rms), 5 drops each: average within 1 %
    rng = np.random.default_rng(int(100 * e))
    hd5, hr5, mu5 = (np.repeat(a, 5) for a in (hd, hr, mu))
    noisy = np.clip(hr5 + 0.1 * rng.standard_normal(hr5.size), 0, None)
    assert np.mean(restitution_from_drop(hd5, noisy, mu5)) == pytest.approx(e, rel=0.01)


def test_restitution_immobile_target_and_mu_effect():
    assert restitution_from_drop(100.0, 16.0, 0.0) == pytest.approx(0.4)
    # neglecting mu underestimates e by mu (1 + sqrt(h_r/h_d))
    e_mu = restitution_from_drop(100.0, 16.0, 0.0252)
    assert e_mu - 0.4 == pytest.approx(0.0252 * 1.4)


def test_restitution_rejects_impossible_rebound():
    with pytest.raises(ValueError, match="drop 2"):
        restitution_from_drop([50.0, 50.0], [10.0, 49.9], 0.0252)


# ----------------------------------------------------------------------------
# steady amplitude
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("fs", [100.0, 173.0])
@pytest.mark.parametrize("phase", [0.0, 0.7])
def test_steady_amplitude_pure_sinusoid(fs, phase):
    f, a = F_STRUCT, 3.7
    t = np.arange(0.0, 40.0, 1.0 / fs)
    x = a * np.sin(2 * math.pi * f * t + phase)
    for n in (3, 30):  # whole periods
        t0 = 5.0
        assert steady_amplitude(t, x, t0, t0 + n / f) == pytest.approx(a, rel=1e-9)


def test_steady_amplitude_window_and_offset():
    t = np.arange(0.0, 20.0, 0.01)
    x = 2.0 * np.sin(2 * math.pi * 1.5 * t) + 0.5
    assert steady_amplitude(t, x, 2.0, 4.0) == pytest.approx(2.0, rel=1e-9)
    assert steady_amplitude(t, x, 2.0, 4.0, remove_mean=False) == pytest.approx(math.sqrt(4 + 2 * 0.25), rel=1e-9)
    # beating record: sqrt(2)*RMS over whole beats = sqrt(a1^2 + a2^2)
    xb = 1.0 * np.sin(2 * math.pi * 1.5 * t) + 0.6 * np.sin(2 * math.pi * 1.6 * t)
    assert steady_amplitude(t, xb, 0.0, 20.0) == pytest.approx(math.hypot(1.0, 0.6), rel=1e-9)
    with pytest.raises(ValueError):
        steady_amplitude(t, x, 30.0, 40.0)


# ----------------------------------------------------------------------------
# impact counting
# ----------------------------------------------------------------------------


def test_count_impacts_relative_displacement():
    d = 20.0
    t = np.arange(0.0, 10.0, 0.0037)
    ph = (0.8 * t) % 1.0  # ball crossing the clearance at constant speed, 1.6 wall hits per second
    s = np.where(ph < 0.5, -d / 2 + 2 * d * ph, d / 2 - 2 * d * (ph - 0.5))
    res = count_impacts(t, s=s, d=d)
    expected = int(np.floor(0.8 * 2 * t[-1] + 1e-9))  # reversals at t = 0.625, 1.25, ...
    assert res.count == expected == 15
    assert set(res.wall) == {-1.0, 1.0}
    # a pendulum turning back short of the walls never hits them
    assert count_impacts(t, s=0.95 * d / 2 * np.sin(2 * math.pi * t), d=d).count == 0
    assert impacts_per_cycle(res.times, 0.8, 0.0, 5.0) == pytest.approx(8 / 4.0)


def _kicked_oscillator(t, x0, f, times, jumps):
    """Undamped oscillator with velocity jumps (impacts) at given times; exact piecewise solution."""
    w = 2 * math.pi * f
    x = np.empty_like(t)
    X, V, T0, k = x0, 0.0, t[0], 0
    bounds = list(times) + [math.inf]
    dv = list(jumps) + [0.0]
    for i, ti in enumerate(t):
        while ti >= bounds[k]:
            tau = bounds[k] - T0
            X, V = X * math.cos(w * tau) + V / w * math.sin(w * tau), -X * w * math.sin(w * tau) + V * math.cos(w * tau) + dv[k]
            T0, k = bounds[k], k + 1
        tau = ti - T0
        x[i] = X * math.cos(w * tau) + V / w * math.sin(w * tau)
    return x


def test_count_impacts_structure_displacement():
    t = np.arange(0.0, 20.0, 0.01)
    times = [2.003, 4.5, 7.21, 9.9, 13.3, 16.71]
    jumps = [20.0, -20.0, 25.0, -30.0, 20.0, -20.0]  # mm/s, above the detection limit
    x = _kicked_oscillator(t, 15.0, F_STRUCT, times, jumps)
    rng = np.random.default_rng(5)
    xn = x + ASSUMED_SENSOR_NOISE_MM * rng.standard_normal(t.size)
    res = count_impacts(t, x=xn, noise_rms=ASSUMED_SENSOR_NOISE_MM)
    assert res.count == len(times)
    np.testing.assert_allclose(res.times, times, atol=0.02)
    np.testing.assert_array_equal(res.wall, np.sign(jumps))
    assert 5.0 < res.min_detectable_jump < 15.0  # mm/s at 100 Hz, 0.01 mm noise
    # jumps well below the limit are invisible; no false alarms on a clean sinusoid
    small = _kicked_oscillator(t, 15.0, F_STRUCT, times, [j / 20 for j in jumps])
    assert count_impacts(t, x=small + ASSUMED_SENSOR_NOISE_MM * rng.standard_normal(t.size),
                         noise_rms=ASSUMED_SENSOR_NOISE_MM).count == 0
    with pytest.raises(ValueError, match="exactly one"):
        count_impacts(t)


# ----------------------------------------------------------------------------
# records: format, loader, writer
# ----------------------------------------------------------------------------


def _free_decay_header(**over):
    h = {"format_version": 1, "kind": "free_decay", "synthetic": True, "sample_rate_hz": 100.0,
         "units": "mm", "damper": "none", "x0_mm": 20.0, "structure_hz": 1.5, "noise_rms": 0.01}
    h.update(over)
    return h


def _csv(path: Path, header_lines, column_line, rows) -> Path:
    text = "\n".join(header_lines + [column_line] + rows) + "\n"
    path.write_text(text)
    return path


GOOD_HEADER = ["# kind: free_decay", "# synthetic: false", "# sample_rate_hz: 100", "# units: mm",
               "# damper: none", "# x0_mm: 20"]
GOOD_ROWS = [f"{0.01 * i:.2f},{20 * math.cos(2 * math.pi * 1.5 * 0.01 * i):.4f}" for i in range(30)]


def test_record_roundtrip_csv_and_netcdf(tmp_path):
    t = np.arange(0.0, 10.0, 0.01)
    x = free_decay(t, 20.0, 0.00048)
    rec = make_measurement(_free_decay_header(), {"t_s": t, "x": x})
    for name in ("a.csv", "a.nc"):
        path = write_measurement(tmp_path / name, rec)
        back = load_measurement(path)
        assert back.header == rec.header
        np.testing.assert_array_equal(back.t, t)
        np.testing.assert_array_equal(back.x, x)
        np.testing.assert_allclose(back.x_in("m"), x / 1000)
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    recs = load_measurements(tmp_path, kind="free_decay")
    assert len(recs) == 2
    res = free_decay_delta(recs[0])
    assert res.mean == pytest.approx(beta_to_delta(0.00048), rel=1e-6)


def test_loader_accepts_hand_written_file(tmp_path):
    rec = load_measurement(_csv(tmp_path / "ok.csv", GOOD_HEADER, "t_s,x", GOOD_ROWS))
    assert rec.kind == "free_decay" and rec.synthetic is False and rec.header["sample_rate_hz"] == 100.0
    assert rec.t.size == 30 and not rec.x.flags.writeable


@pytest.mark.parametrize("drop, match", [
    ("# sample_rate_hz: 100", "header field sample_rate_hz missing"),
    ("# kind: free_decay", "header field kind missing"),
    ("# x0_mm: 20", "header field x0_mm missing"),
    ("# synthetic: false", "header field synthetic missing"),
])
def test_loader_missing_header_field(tmp_path, drop, match):
    header = [h for h in GOOD_HEADER if h != drop]
    with pytest.raises(MeasurementError, match=match):
        load_measurement(_csv(tmp_path / "bad.csv", header, "t_s,x", GOOD_ROWS))


def test_loader_non_increasing_time(tmp_path):
    rows = list(GOOD_ROWS)
    rows[16] = rows[15]  # data row 17 repeats the time of row 16
    with pytest.raises(MeasurementError, match=r"row 17 \(line 24\): t_s is not increasing"):
        load_measurement(_csv(tmp_path / "bad.csv", GOOD_HEADER, "t_s,x", rows))


def test_loader_nan(tmp_path):
    rows = list(GOOD_ROWS)
    rows[4] = "0.04,nan"
    with pytest.raises(MeasurementError, match=r"row 5 .*x is NaN"):
        load_measurement(_csv(tmp_path / "bad.csv", GOOD_HEADER, "t_s,x", rows))


@pytest.mark.parametrize("columns, match", [
    ("t_s,y", "column 'y' not allowed"),
    ("time,x", "column 'time' not allowed"),
    ("x,t_s", "wrong order"),
    ("t_s", "column x missing"),
])
def test_loader_wrong_column(tmp_path, columns, match):
    rows = GOOD_ROWS if "," in columns else [r.split(",")[0] for r in GOOD_ROWS]
    with pytest.raises(MeasurementError, match=match):
        load_measurement(_csv(tmp_path / "bad.csv", GOOD_HEADER, columns, rows))


@pytest.mark.parametrize("edit, match", [
    (lambda h, r: (h + ["# sampel_rate_hz: 100"], r), "header field 'sampel_rate_hz' is unknown"),
    (lambda h, r: ([x.replace("100", "50") for x in h], r), "sample_rate_hz = 50.0 disagrees"),
    (lambda h, r: ([x.replace("mm", "inch") if "units" in x else x for x in h], r), "units: 'inch'"),
    (lambda h, r: ([x.replace("false", "maybe") for x in h], r), "synthetic: 'maybe'"),
    (lambda h, r: (h, r[:7] + ["0.07,1.0,2.0"] + r[8:]), r"row 8 .*expected 2 values"),
    (lambda h, r: (h, r[:2] + ["0.02,abc"] + r[3:]), r"row 3 .*x is not a number"),
    (lambda h, r: (h, r[:10] + r[12:]), r"row 11 .*gap in t_s"),
    (lambda h, r: (h + ["# damper: pid"], r), "given twice"),
    (lambda h, r: ([x.replace("none", "pid") for x in h], r), "header field mu missing"),
])
def test_loader_other_malformations(tmp_path, edit, match):
    header, rows = edit(list(GOOD_HEADER), list(GOOD_ROWS))
    with pytest.raises(MeasurementError, match=match):
        load_measurement(_csv(tmp_path / "bad.csv", header, "t_s,x", rows))


def test_loader_error_names_the_file(tmp_path):
    path = _csv(tmp_path / "named.csv", GOOD_HEADER[1:], "t_s,x", GOOD_ROWS)
    with pytest.raises(MeasurementError, match="named.csv: header field kind missing"):
        load_measurement(path)


def test_drop_test_record(tmp_path):
    e, mu = 0.46, 0.0129
    hd = np.array(HEIGHTS * 2)
    rec = make_measurement({"kind": "drop_test", "synthetic": True, "mu": mu, "wall": "rubber_1.0mm", "e": e,
                       "ball_diameter_mm": 40.0}, {"drop_height_cm": hd, "rebound_height_cm": rebound_height(hd, e, mu)})
    back = load_measurement(write_measurement(tmp_path / "drop.csv", rec))
    np.testing.assert_allclose(drop_test_restitution(back), e, rtol=1e-12)
    lines = (tmp_path / "drop.csv").read_text().splitlines()
    lines[-1] = "50.0,60.0"
    (tmp_path / "bad.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(MeasurementError, match=r"row 6 .*rebound_height_cm \(60.0\) exceeds drop_height_cm"):
        load_measurement(tmp_path / "bad.csv")
    with pytest.raises(MeasurementError, match="give e only for a synthetic drop test"):
        make_measurement({"kind": "drop_test", "synthetic": False, "mu": mu, "wall": "steel", "e": 0.4},
                    {"drop_height_cm": [25.0], "rebound_height_cm": [3.0]})


def test_write_refuses_invalid_and_keeps_old_file(tmp_path):
    t = np.arange(0.0, 1.0, 0.01)
    good = make_measurement(_free_decay_header(), {"t_s": t, "x": np.sin(t)})
    path = write_measurement(tmp_path / "r.csv", good)
    before = path.read_text()
    x = np.sin(t)
    x[3] = np.nan
    with pytest.raises(MeasurementError, match="row 4: x is NaN"):
        write_measurement(path, (_free_decay_header(), {"t_s": t, "x": x}))
    assert path.read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]


def test_sweep_records_to_half_power(tmp_path):
    # end to end: steady-state SDOF records on a fine grid -> sqrt(2)*RMS -> half-power beta
    beta, a_static = 0.00048, 0.01  # mm static deflection: 10.4 mm at resonance
    rs = np.round(np.arange(0.996, 1.004 + 1e-12, 0.0002), 6)
    fs = 100.0
    for i, r in enumerate(rs):
        fhz = r * F_STRUCT
        t = np.arange(0.0, 20.0, 1 / fs)
        amp = a_static * sdof_amplitude(r, beta)
        header = {"kind": "forced_sweep_point", "synthetic": True, "sample_rate_hz": fs, "units": "mm",
                  "damper": "none", "r": float(r), "structure_hz": F_STRUCT}
        write_measurement(tmp_path / f"p{i:03d}.csv", (header, {"t_s": t, "x": amp * np.sin(2 * math.pi * fhz * t + 0.3)}))
    curve = sweep_curve(load_measurements(tmp_path, kind="forced_sweep_point"))
    np.testing.assert_allclose(curve.amplitude, a_static * sdof_amplitude(curve.r, beta), rtol=2e-3)
    assert half_power_damping(curve.r, curve.amplitude) == pytest.approx(beta, rel=0.02)
