"""Reader of the measured trials and the platform-motion interpolant (validation/replay/trials.py)."""

import math

import numpy as np
import pytest

from helpers import DT, PLACEHOLDER, platform_truth, write_trial
from vibrofeed.errors import InputError, TrialFileError
from vibrofeed.validation.replay.trials import (
    COLUMNS,
    MIN_FRAMES,
    estimate_noise,
    finite_difference_comparison,
    fit_platform,
    fit_position,
    load_trials,
    read_trial,
)


def test_reads_synthetic_trial_in_si_units(tmp_path):
    path = write_trial(tmp_path / "trial_7.csv")
    tr = read_trial(path)
    assert tr.name == "trial_7" and tr.number == 7 and tr.n_frames == 300
    assert tr.dt == pytest.approx(DT, rel=1e-5)  # times printed with 8 decimals
    text = path.read_text(encoding="utf-8").splitlines()
    first = dict(zip(text[0].split(","), text[1].split(",")))
    assert tr.platform.z[0] == pytest.approx(float(first["zp"]) * 1e-3, rel=1e-12)
    assert tr.part.x[0] == pytest.approx(float(first["xo"]) * 1e-3, rel=1e-12)
    # placeholders -> NaN, everything else finite
    assert np.isnan(tr.platform.vz[0]) and np.isnan(tr.part.az[1]) and np.isnan(tr.marker.vx[-1])
    assert np.isfinite(tr.platform.vz[1:-1]).all() and np.isfinite(tr.platform.az[2:-2]).all()
    assert np.isfinite(tr.platform.z).all()


@pytest.mark.parametrize("placeholder", ["\ufffd", "\x00?", "NaN", "-", ""])
def test_any_non_numeric_placeholder_is_missing(tmp_path, placeholder):
    tr = read_trial(write_trial(tmp_path / "t.csv", placeholder=placeholder))
    assert np.isnan(tr.platform.vz[0]) and np.isfinite(tr.platform.vz[5])


def test_invalid_utf8_placeholder_bytes_are_missing(tmp_path):
    path = write_trial(tmp_path / "t.csv")
    path.write_bytes(path.read_bytes().replace(PLACEHOLDER.encode("utf-8"), b"\xff\xfe"))
    tr = read_trial(path)
    assert np.isnan(tr.part.az[0]) and tr.n_frames == 300


def _drop(name):
    return lambda cols: cols.pop(name)


def _rename(old, new):
    return lambda cols: cols.__setitem__(new, cols.pop(old))


def _set(name, k, value):
    def mutate(cols):
        cols[name] = cols[name].copy()
        cols[name][k] = value
    return mutate


@pytest.mark.parametrize("mutate,words", [
    (_drop("zo"), "missing columns zo"),
    (_rename("vzp", "speed"), "unknown columns 'speed'"),
    (_set("t", 10, math.nan), "column t has 1 missing"),
    (_set("zp", 4, math.nan), "column zp has 1 missing"),
    (_set("t", 10, 5 * DT), "time is not increasing"),
    (_set("t", 10, 10.3 * DT), "not uniformly sampled"),
])
def test_malformed_trials_are_named_and_explained(tmp_path, mutate, words):
    path = write_trial(tmp_path / "bad.csv", mutate=mutate)
    with pytest.raises(TrialFileError) as err:
        read_trial(path)
    assert isinstance(err.value, InputError) and isinstance(err.value, ValueError)
    assert str(path) in str(err.value) and words in str(err.value)


def test_too_few_frames(tmp_path):
    path = write_trial(tmp_path / "short.csv", n=MIN_FRAMES - 1)
    with pytest.raises(TrialFileError, match=f"has {MIN_FRAMES - 1} frames"):
        read_trial(path)


@pytest.mark.parametrize("content,words", [
    (b"", "is empty"),
    (",".join(COLUMNS).encode() + b"\r\n", "no data rows"),
    (b"1,2,3\r\n4,5,6\r\n", "no header"),
    (b"a,b\r\n1,2\r\n", "missing columns"),
    ((",".join(COLUMNS) + "\r\n" + ",".join(["x"] * len(COLUMNS)) + "\r\n").encode(),
     "contains no numbers"),
    ((",".join(COLUMNS) + "\r\n1,2\r\n").encode(), "line 2 has 2 fields"),
])
def test_files_that_are_not_trials(tmp_path, content, words):
    path = tmp_path / "odd.csv"
    path.write_bytes(content)
    with pytest.raises(TrialFileError) as err:
        read_trial(path)
    assert str(path) in str(err.value) and words in str(err.value)


def test_unreadable_file_is_a_trial_error(tmp_path):
    with pytest.raises(TrialFileError, match="cannot be read"):
        read_trial(tmp_path / "nowhere.csv")
    with pytest.raises(TrialFileError, match="cannot be read"):
        read_trial(tmp_path)  # a directory


def test_noise_estimate_recovers_sigma():
    t = np.arange(400) * DT
    for seed, sigma in enumerate((2e-6, 5e-6, 10e-6)):
        y = platform_truth(t) + sigma * np.random.default_rng(seed).standard_normal(t.size)
        assert estimate_noise(y) == pytest.approx(sigma, rel=0.15)


def test_spline_beats_finite_differences_on_known_motion():
    """Truth known: positions within the noise, derivatives better than the file's."""
    t = np.arange(300) * DT
    inner = slice(3, -3)  # the end frames rest on one-sided data
    for seed in range(3):
        sigma = 5e-6
        y = platform_truth(t) + sigma * np.random.default_rng(seed).standard_normal(t.size)
        fit = fit_position(t, y)
        assert fit.residual_rms == pytest.approx(fit.noise, rel=1e-3)  # the criterion

        def rms(e):
            return float(np.sqrt(np.mean(e[inner] ** 2)))
        v_fd = np.gradient(y, DT)
        a_fd = np.gradient(v_fd, DT)
        assert rms(fit.spline(t) - platform_truth(t)) < sigma
        assert rms(fit.spline.derivative(1)(t) - platform_truth(t, 1)) < 0.7 * rms(
            v_fd - platform_truth(t, 1))
        assert rms(fit.spline.derivative(2)(t) - platform_truth(t, 2)) < 0.7 * rms(
            a_fd - platform_truth(t, 2))


def test_surface_velocity_and_acceleration_are_derivatives_of_its_position():
    t = np.arange(200) * DT
    y = platform_truth(t) + 5e-6 * np.random.default_rng(3).standard_normal(t.size)
    s = fit_position(t, y).surface
    tt = np.linspace(t[5], t[-5], 37)
    h = 1e-6
    dz = (s.position(tt + h)[0] - s.position(tt - h)[0]) / (2 * h)
    dv = (s.velocity(tt + h)[0] - s.velocity(tt - h)[0]) / (2 * h)
    assert np.allclose(s.velocity(tt)[0], dz, rtol=0, atol=1e-6 * np.max(np.abs(dz)))
    assert np.allclose(s.acceleration(tt)[0], dv, rtol=0, atol=1e-5 * np.max(np.abs(dv)))


def test_residual_lag1_tells_noise_matched_from_oversmoothed():
    """Matched to the noise, the residual is not positively correlated; 2x smoother, it is."""
    t = np.arange(300) * DT
    for seed in range(3):
        y = platform_truth(t) + 5e-6 * np.random.default_rng(seed).standard_normal(t.size)
        matched = fit_position(t, y, noise=5e-6)
        smoother = fit_position(t, y, noise=10e-6)
        assert matched.lag1 < 0.1
        assert smoother.lag1 > 0.5
        # pure noise through (I - H) would be anti-correlated: the fit keeps its low band
        assert matched.expected_lag1 < 0


def test_fit_position_rejects_unknown_criterion():
    t = np.arange(50) * DT
    with pytest.raises(ValueError, match="criterion"):
        fit_position(t, platform_truth(t), criterion="eyeball")


# ---- the published trials, when present ---------------------------------------------

real = pytest.mark.usefixtures("measured_trials_dir")


@pytest.fixture(scope="module")
def real_trials(measured_trials_dir):
    return load_trials(measured_trials_dir)


@real
def test_real_trials_read_as_published(real_trials, measured_trials_dir):
    assert [tr.name for tr in real_trials][:6] == [f"trial_{k}" for k in range(1, 7)]
    for tr in real_trials:
        lines = (measured_trials_dir / f"{tr.name}.csv").read_bytes().splitlines()
        assert tr.n_frames == len(lines) - 1
        assert tr.dt == pytest.approx(1 / 960, rel=1e-4)
        assert np.isnan(tr.platform.vz[0]) and np.isnan(tr.platform.az[1])
        assert np.isfinite(tr.platform.z).all() and np.isfinite(tr.part.z).all()
    first = real_trials[0]
    # first data row of trial_1: t=0, xp=1.57760000 mm, zp=-1.15967300 mm
    assert first.t[0] == 0.0
    assert first.platform.x[0] == pytest.approx(1.5776e-3, rel=1e-12)
    assert first.platform.z[0] == pytest.approx(-1.159673e-3, rel=1e-12)


@real
def test_real_platform_fits_are_noise_matched(real_trials):
    for tr in real_trials:
        fit = fit_platform(tr)
        assert 1e-6 < fit.noise < 20e-6  # microns: a tracker, not a blunder
        assert fit.residual_rms == pytest.approx(fit.noise, rel=1e-3)
        assert fit.lag1 < 0  # no slow structure left in the residual
        cmp = finite_difference_comparison(tr, fit)
        # the file's velocity column is a central difference of the same positions:
        # it differs from the spline's velocity by noise plus truncation at impacts
        assert cmp["velocity_rms_diff"] < 4 * cmp["velocity_fd_noise"]
