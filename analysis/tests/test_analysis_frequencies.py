"""Characteristic bearing frequencies (docs/model.md section 7.3)."""

import math

import pytest

from analysis.frequencies import case_frequencies, characteristic_frequencies, race_speeds
from analysis.studyfile import select_cases

PAPER = dict(inner_diameter=29.2e-3, outer_diameter=46.6e-3, inner_waviness_number=35, outer_waviness_number=35)


def test_crank_ground_at_300_rpm_matches_model_md():
    f = characteristic_frequencies("crank_ground", 300, ball_count=9, **PAPER)
    assert f.cage_speed == pytest.approx(12.10, abs=0.005)  # rad/s
    assert f.outer_pass == pytest.approx(1.926, abs=0.0005)
    assert f.inner_pass == pytest.approx(3.074, abs=0.0005)
    assert f.waviness_outer == pytest.approx(67.4, abs=0.05)
    assert f.waviness_inner == pytest.approx(107.6, abs=0.05)
    assert f.cage == pytest.approx(f.outer_pass, rel=1e-12)  # the outer race stands still
    assert f.inner_pass + f.outer_pass == pytest.approx(5.0, rel=1e-12)  # the crank frequency
    assert f.ball_pass_outer == pytest.approx(9 * f.outer_pass, rel=1e-12)
    assert f.ball_pass_inner == pytest.approx(9 * f.inner_pass, rel=1e-12)


def test_waviness_whirls_where_the_ball_count_divides_n_plus_or_minus_one():
    """35 = 4·9 − 1: with 9 balls the outer waviness whirls the journal forward at
    36 f_c = N_o f_out + f_c and the inner backward at N_i f_in − f_c (docs/model.md §7.3);
    with 17 balls (34 = 2·17) at N_o f_out − f_c and N_i f_in + f_c; 8 balls divide
    neither 34 nor 36: no whirl."""
    f = characteristic_frequencies("crank_ground", 300, ball_count=9, **PAPER)
    assert f.whirl_outer == pytest.approx(36 * f.cage, rel=1e-12)
    assert f.whirl_outer == pytest.approx(69.3, abs=0.05)
    assert f.whirl_inner == pytest.approx(f.waviness_inner - f.cage, rel=1e-12)
    assert f.whirl_inner == pytest.approx(105.7, abs=0.05)
    g = characteristic_frequencies("crank_ground", 300, ball_count=17, **PAPER)
    assert g.whirl_outer == pytest.approx(g.waviness_outer - g.cage, rel=1e-12)
    assert g.whirl_inner == pytest.approx(g.waviness_inner + g.cage, rel=1e-12)
    h = characteristic_frequencies("crank_ground", 300, ball_count=8, **PAPER)
    assert math.isnan(h.whirl_outer) and math.isnan(h.whirl_inner)
    # At crank_rod the outer race turns: the same rule in the races' own speeds.
    r = characteristic_frequencies("crank_rod", 300, ball_count=9, **PAPER)
    assert r.whirl_outer == pytest.approx(abs(36 * r.cage_speed - 35 * 10 * math.pi) / (2 * math.pi), rel=1e-12)


def test_crank_rod_turns_the_outer_race():
    """Outer race on the crank, inner on the rod (mean speed 0): the cage runs at
    ω d_o/(d_i + d_o); the races pass each other as fast as at crank_ground."""
    f = characteristic_frequencies("crank_rod", 300, ball_count=8, **PAPER)
    assert f.cage_speed == pytest.approx(2 * math.pi * 5 * 46.6 / 75.8, rel=1e-12)
    assert f.cage == pytest.approx(3.074, abs=0.0005)
    assert f.waviness_outer == pytest.approx(67.4, abs=0.05)
    assert f.waviness_inner == pytest.approx(107.6, abs=0.05)


def test_race_speeds():
    assert race_speeds("crank_ground", 600) == (pytest.approx(20 * math.pi), 0.0)
    assert race_speeds("crank_rod", 600) == (0.0, pytest.approx(20 * math.pi))
    with pytest.raises(ValueError, match="ideal"):
        race_speeds("ideal", 600)


def test_case_frequencies_read_the_case_parameters(smoke):
    case = int(select_cases(smoke, location="crank_ground", ball_count=9, waviness_amplitude=4e-6)[0])
    f = case_frequencies(smoke, case)  # 600 rpm: twice the 300 rpm figures
    assert f.waviness_outer == pytest.approx(2 * 35 * 5 * 29.2 / 75.8, rel=1e-9)
    assert f.ball_pass_outer == pytest.approx(9 * 10 * 29.2 / 75.8, rel=1e-9)
