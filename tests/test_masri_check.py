"""The closed-form check: simulator and Masri's orbit agree, and disagree as predicted."""

from __future__ import annotations

import pytest

from impact.closed_form.masri import masri_2eipc, orbit_rms_amplitude
from impact.stages.masri.check import check_stable, check_unstable

BETA, XST = 0.0048, 0.096


def test_stable_orbit_stays_to_round_off():
    mu, e, r, gap = 0.01, 0.25, 1.0, 16.0
    root = masri_2eipc(mu, e, BETA, r, gap, XST)["upper"]
    assert root["admissible"] and root["stable"]
    out = check_stable(mu, e, BETA, r, gap, XST, root, half_periods=100)
    assert out["stays"]
    assert out["max_state_deviation"] < 1e-10
    assert out["amplitude_rel_error"] < 1e-8
    assert out["u_rel_error"] < 1e-8


def test_unstable_orbit_leaves_at_the_predicted_rate():
    mu, e, r, g = 0.01, 0.25, 1.0, 0.8
    gap = g * XST / (2 * BETA)
    root = masri_2eipc(mu, e, BETA, r, gap, XST)["upper"]
    assert root["admissible"] and not root["stable"]
    out = check_unstable(mu, e, BETA, r, gap, XST, root, max_half_periods=400)
    assert out["left_orbit"]
    assert out["growth_per_impact"] == pytest.approx(root["max_modulus"], rel=0.01)


def test_orbit_rms_amplitude_is_below_the_peak_amplitude():
    mu, e, r, gap = 0.01, 0.5, 1.0, 15.0
    root = masri_2eipc(mu, e, BETA, r, gap, XST)["upper"]
    rms = orbit_rms_amplitude(root, mu, e, BETA, r, gap, XST)
    # sqrt(2) RMS equals the peak only for a pure sinusoid; impacts flatten x
    assert 0.8 * root["amplitude"] < rms <= root["amplitude"] * 1.0000001
