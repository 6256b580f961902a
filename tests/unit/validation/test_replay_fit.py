"""Replaying trials through the model and fitting it (validation/replay/fit.py)."""

import numpy as np
import pytest

from vibrofeed.models.constants import G
from vibrofeed.models.surface import CallableSurface
from vibrofeed.models.vertical import Contact, simulate
from vibrofeed.validation.replay.fit import (
    EDGE_FRAMES,
    MEASURED_NORMAL_FORCE_MG,
    MU_S,
    PART_MASS,
    fit_mu_k,
    fit_trials,
    leave_one_out,
    measured_normal_force_mg,
    prepare,
    replay,
)
from vibrofeed.validation.replay.trials import load_trials, read_trial
from vibrofeed.validation.studies.speed_dependent_friction import simulate_speed_dependent
from vibrofeed.validation.studies.vertical_study import leave_one_out_from_table

DT = 1 / 960.0
SIGMA = 2e-6  # m, tracking noise of the synthetic files


def drive(a1, f=40.0):
    """Two harmonics with sharp downward peaks: stick-slip that climbs."""
    w, a2, ph = 2 * np.pi * f, a1 / 2, -np.pi / 2
    return CallableSurface(
        lambda t: a1 * np.sin(w * t) + a2 * np.sin(2 * w * t + ph),
        lambda t: a1 * w * np.cos(w * t) + 2 * w * a2 * np.cos(2 * w * t + ph),
        lambda t: -a1 * w * w * np.sin(w * t) - 4 * w * w * a2 * np.sin(2 * w * t + ph),
        period=1 / f)


def synthetic_trial(path, a1, fn_mg, mu_k, n=290, seed=0):
    """Truth: the model on the exact drive; the file: 960 fps samples + noise, in mm."""
    surface = drive(a1)
    t = np.arange(n) * DT
    contact = Contact(PART_MASS, fn_mg * PART_MASS * G, MU_S, mu_k)
    part = simulate(surface, contact, t_end=t[-1], z0=2e-3, t_eval=t).z
    rng = np.random.default_rng(seed)
    cols = {"t": t}
    for m, z in (("p", surface.position(t)[0]), ("o", part), ("s", np.zeros(n) - 3e-3)):
        cols["x" + m] = (1e-3 + SIGMA * rng.standard_normal(n)) * 1e3
        cols["z" + m] = (z + SIGMA * rng.standard_normal(n)) * 1e3
        for q in "xz":
            v = np.gradient(cols[q + m], DT)
            cols["v" + q + m] = v
            cols["a" + q + m] = np.gradient(v, DT)
    lines = [",".join(cols)]
    for k in range(n):
        fields = [f"{cols[h][k]:.8f}" for h in cols]
        if k == 0 or k == n - 1:  # missing derivatives, as published
            fields = [f if h[0] not in "va" else "\ufffd" for h, f in zip(cols, fields)]
        lines.append(",".join(fields))
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("utf-8"))
    return prepare(read_trial(path))


TRUE_MU_K = 0.55
SYNTH = [("synth_1", 0.40e-3, 9.0), ("synth_2", 0.45e-3, 10.0)]


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    d = tmp_path_factory.mktemp("trials")
    return [synthetic_trial(d / f"{name}.csv", a1, fn, TRUE_MU_K, seed=k)
            for k, (name, a1, fn) in enumerate(SYNTH)]


def test_replay_with_true_parameters_reproduces_the_part(synthetic):
    for prep, (_, _, fn) in zip(synthetic, SYNTH):
        r = replay(prep, PART_MASS, fn * PART_MASS * G, MU_S, TRUE_MU_K)
        assert r.predicted_mm[0] == 0.0 and r.measured_mm[0] == 0.0
        assert len(r.t) == prep.trial.n_frames - 2 * EDGE_FRAMES
        assert r.max_displacement_mm > 0.3  # it really climbs...
        assert 0.2 < r.stuck_fraction < 0.99  # ...by stick-slip
        # Only tracking noise separates model and truth, but stick/slip amplifies
        # it: 2 um of platform noise shifts event times enough for ~0.02 mm.
        assert r.mean_abs_error_mm < 0.04
        assert r.final_predicted_mm == pytest.approx(r.final_measured_mm, abs=0.08)
        for factor in (0.85, 1.3):  # a 15-30 % wrong force is clearly worse
            wrong = replay(prep, PART_MASS, factor * fn * PART_MASS * G, MU_S, TRUE_MU_K)
            assert wrong.mean_abs_error_mm > 5 * r.mean_abs_error_mm


def test_fit_finds_parameters_as_good_as_the_truth(synthetic):
    fit = fit_trials(synthetic)
    truth = np.mean([replay(p, PART_MASS, fn * PART_MASS * G, MU_S, TRUE_MU_K)
                     .mean_abs_error_mm for p, (_, _, fn) in zip(synthetic, SYNTH)])
    assert fit.mean_mae_mm <= truth + 0.002
    for name, _, fn in SYNTH:
        # the kinetic friction level mu_k F_n is what the part's motion fixes
        assert fit.mu_k * fit.normal_force_mg[name] == pytest.approx(TRUE_MU_K * fn, rel=0.05)
        assert fit.normal_force[name] == pytest.approx(
            fit.normal_force_mg[name] * PART_MASS * G, rel=1e-12)
    assert fit.mean_mae_mm == pytest.approx(np.mean(list(fit.mae_mm.values())), rel=1e-12)


def test_leave_one_out_with_known_forces_recovers_mu_k(synthetic):
    forces = {name: fn for name, _, fn in SYNTH}
    mu_k, err = fit_mu_k(synthetic, forces_mg=forces)
    assert mu_k == pytest.approx(TRUE_MU_K, abs=0.02) and err < 0.01
    loo = leave_one_out(synthetic, forces_mg=forces)
    for name in forces:
        assert loo.mu_k[name] == pytest.approx(TRUE_MU_K, abs=0.03)
        assert loo.mae_mm[name] < 0.02


def test_measured_force_lookup():
    assert MEASURED_NORMAL_FORCE_MG[1] == 11.089 and MEASURED_NORMAL_FORCE_MG[2] == 16.901

    class Fake:
        number = 99
    with pytest.raises(KeyError, match="99"):
        measured_normal_force_mg(Fake())


def test_leave_one_out_from_table_picks_the_best_on_the_others():
    table = np.array([[1.0, 0.0, 5.0],
                      [0.2, 0.4, 0.1],
                      [0.3, 0.5, 0.0]])
    held_out, chosen = leave_one_out_from_table(table)
    # trial 0 held out: others prefer column 2 (mean 0.05); trial 1: column 0 (0.65 vs
    # 0.25 vs 2.5 -> column 1 mean 0.25); trial 2: column 1 (0.2)
    assert list(chosen) == [2, 1, 1]
    assert list(held_out) == [5.0, 0.4, 0.5]


def test_speed_dependent_variant_reduces_to_coulomb(synthetic):
    prep = synthetic[0]
    t = prep.trial.t[3:-3]
    c = Contact(PART_MASS, 9 * PART_MASS * G, MU_S, 0.5)
    ref = simulate(prep.surface, c, t_end=t[-1], t_start=t[0], z0=0.0, t_eval=t)
    z, stuck, _ = simulate_speed_dependent(prep.surface, c, 0.5, 0.05, t[-1], t[0], 0.0, t)
    assert np.max(np.abs(z - ref.z)) < 1e-12
    assert stuck == pytest.approx(ref.stuck_fraction, abs=1e-12)
    faster, _, _ = simulate_speed_dependent(prep.surface, c, 0.3, 0.005, t[-1], t[0], 0.0, t)
    assert np.max(np.abs(faster - ref.z)) > 1e-5  # the law matters once slips exceed v_c


# ---- the published trials ---------------------------------------------------------

real = pytest.mark.usefixtures("measured_trials_dir")


@pytest.fixture(scope="module")
def real_preps(measured_trials_dir):
    trials = [tr for tr in load_trials(measured_trials_dir) if tr.number in range(1, 7)]
    return [prepare(tr) for tr in trials]


@real
def test_fitting_protocol_meets_the_target_on_trials_1_to_6(real_preps):
    """Shared mu_k, one F_n per trial: mean MAE <= 0.14 mm (authors: 0.161 mm over 10)."""
    assert len(real_preps) == 6
    fit = fit_trials(real_preps)
    assert fit.mean_mae_mm <= 0.14
    assert 0.3 <= fit.mu_k <= MU_S
    for name, r in fit.results.items():
        assert r.mean_abs_error_mm < 0.5 * r.max_displacement_mm
        assert fit.normal_force_mg[name] > 1 / MU_S  # holds the part at rest


@real
def test_prediction_with_measured_forces_is_the_harder_figure(real_preps):
    loo = leave_one_out(real_preps)
    assert set(loo.mae_mm) == {p.name for p in real_preps}
    assert all(0.05 <= m <= MU_S for m in loo.mu_k.values())
    # What prediction must achieve (not a figure of an earlier run): beat the null
    # prediction "the part does not move" (its error is the mean measured |z|),
    # on average, and clearly on trials 1 and 2, whose measured grasp (11 and 17
    # m g) can hold the sticking they show; trials 3-6 were measured at 5.3 m g,
    # too little for their sticking (README, "Measured trials").
    null = {name: float(np.mean(np.abs(r.measured_mm))) for name, r in loo.results.items()}
    assert loo.mean_mae_mm < np.mean(list(null.values()))
    for name in ("trial_1", "trial_2"):
        assert loo.mae_mm[name] < 0.5 * null[name]


@pytest.mark.parametrize("twelfths", [5, 11])
def test_speed_dependent_variant_sticks_from_a_band_edge_turning_inward(twelfths):
    """As vertical.simulate: a_s = -A_pk sin(w t + phase) starts on a band edge (A = A_pk / 2,
    g = 0) and moves into the band; the part sticks until w t = pi / 3, though the computed
    a_s(0) may lie a rounding error outside the band."""
    from vibrofeed.models.surface import sine_drive

    f, amp, m = 60.0, 1e-3, 0.009
    A = 0.5 * amp * (2 * np.pi * f) ** 2
    c = Contact(mass=m, normal_force=A * m / 0.6, mu_s=0.6, mu_k=0.5, g=0.0)
    drive = sine_drive(amp, f, twelfths * (2 * np.pi / 12))
    _, _, segments = simulate_speed_dependent(drive, c, 0.5, 0.05, 0.5 / f, 0.0, None, [0.0])
    assert segments[0].kind == "stick" and segments[0].t0 == 0.0
    assert segments[0].t1 == pytest.approx(1 / (6 * f), abs=1e-13)  # s
