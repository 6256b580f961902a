"""Model bugs that only an engine cross-check used to catch, pinned by closed forms.

* Impact friction is kinetic (mu_k), the stick decision static (mu_s): with
  mu_s != mu_k the post-impact tangential velocity and the slide after it
  are known in closed form (Khan & Sarma, "Vibratory Assembly Update: Part
  Transportation Mechanics Analysis", §2.2.1 friction envelope, §2.3 impacts).
* The slip-event search ends at the end of slipping: a launch later in the
  window must not be taken for the next event.
* ``is_locked`` against criteria that do not go through the model: the
  closed-form period-one limit Gamma = sqrt(1 + pi^2) for e = 0 (Khan & Sarma,
  §2.3.2, as corrected in the project's notes on the source) and, for e > 0,
  an independent bouncing-ball computation written here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from vibrofeed.models import hopping as H
from vibrofeed.models.constants import G
from vibrofeed.models.part_on_surface import PartOnSurface, PartParams
from vibrofeed.models.surface import SineWaveform

MU_S, MU_K = 0.8, 0.3


# -- impact friction -----------------------------------------------------------------------
@pytest.mark.parametrize("vx", [0.5, 0.08])
def test_impact_friction_is_kinetic_then_the_part_slides_to_a_stop(vx):
    """Drop from h onto a still surface: w = -sqrt(2 g h); the tangential impulse is
    mu_k |w| (0.042 m/s here); then the part slides at -mu_k g and sticks."""
    h = 1e-3
    wf = SineWaveform(50.0, 0.0, 0.0)
    m = PartOnSurface(wf, PartParams(MU_S, MU_K, e=0.0)).start(0.0, z=h, vx=vx, vz=0.0)
    m.run(1.0)
    kinds = [e.kind for e in m.events]
    assert kinds == ["impact", "slip", "stick"]  # 0.08 < mu_s |w| = 0.112: still not stopped
    impact, _, stick = m.events
    w = -math.sqrt(2 * G * h)
    t_land = math.sqrt(2 * h / G)
    assert impact.t == pytest.approx(t_land, rel=1e-12)
    v_after = vx + MU_K * w
    assert impact.vx == pytest.approx(v_after, rel=1e-12)
    t_slide = v_after / (MU_K * G)
    assert stick.t == pytest.approx(t_land + t_slide, rel=1e-9)
    x_stop = vx * t_land + v_after * t_slide - 0.5 * MU_K * G * t_slide ** 2
    assert stick.x == pytest.approx(x_stop, rel=1e-9)
    assert m.vx == 0.0 and m.x == pytest.approx(x_stop, rel=1e-9)


def test_hop_speed_on_a_tangentially_still_surface():
    """Gamma_n = 1.5, no tangential motion: a part resting with speed u0 slides,
    launches at theta_l = asin(1/Gamma) with its slide speed, and lands with
    u reduced by mu_k |w| (|u| > mu_k |w| here)."""
    freq, gamma = 50.0, 1.5
    w_ = 2 * math.pi * freq
    wf = SineWaveform.from_gamma(freq, gamma, 0.0, 0.0)
    amp = wf.amp_n
    th_l = math.asin(1 / gamma)
    t0 = (math.pi - th_l + 0.2) / w_      # in contact (n > 0) from here to th_l + 2 pi
    t_l = (th_l + 2 * math.pi) / w_
    slide = MU_K * (G * (t_l - t0) + amp * w_ * (math.cos(th_l) - math.cos(w_ * t0)))
    u0 = slide + 1.0                      # still sliding at the launch: 1 m/s
    m = PartOnSurface(wf, PartParams(MU_S, MU_K, e=0.0)).start(t0, vx=u0)
    m.run(t0 + 2 / freq, stop_on=("impact",))
    launch = [e for e in m.events if e.kind == "launch"][0]
    assert launch.t == pytest.approx(t_l, rel=1e-12)
    assert launch.vx == pytest.approx(1.0, rel=1e-9)
    # the flight: parabola against the sine, landing where the gap closes
    z0, vz0 = amp * math.sin(th_l), amp * w_ * math.cos(th_l)

    def gap(t):
        return z0 + vz0 * (t - t_l) - 0.5 * G * (t - t_l) ** 2 - amp * math.sin(w_ * t)

    grid = np.linspace(t_l + 1e-7, t_l + 1 / freq, 20001)
    k = int(np.argmax(np.array([gap(t) for t in grid]) < 0))
    t_hit = brentq(gap, grid[k - 1], grid[k], xtol=1e-16)
    impact = [e for e in m.events if e.kind == "impact"][0]
    assert impact.t == pytest.approx(t_hit, rel=1e-10)
    w_in = vz0 - G * (t_hit - t_l) - amp * w_ * math.cos(w_ * t_hit)
    assert impact.info["w"] == pytest.approx(w_in, rel=1e-8)
    assert impact.vx == pytest.approx(1.0 + MU_K * w_in, rel=1e-8)  # mu_k, not mu_s


# -- the slip-event search -----------------------------------------------------------------
def test_slip_ends_before_a_later_launch_in_the_same_window():
    """Slipping ends where the kinetic friction impulse has used up u0; a launch
    later in the same period must not be taken instead (nor let the part slip
    on backwards until then)."""
    freq, gamma = 50.0, 1.5
    w_ = 2 * math.pi * freq
    wf = SineWaveform.from_gamma(freq, gamma, 0.0, 0.0)
    amp = wf.amp_n
    th_l = math.asin(1 / gamma)
    t0 = (math.pi - th_l + 0.2) / w_
    t_stop = 4.5 / w_                     # chosen; the launch is at (th_l + 2 pi) / w = 7.01 / w
    t_l = (th_l + 2 * math.pi) / w_
    # u(t) = u0 - mu_k (g (t - t0) + v_n(t) - v_n(t0)): zero at t_stop by construction
    u0 = MU_K * (G * (t_stop - t0) + amp * w_ * (math.cos(w_ * t_stop) - math.cos(w_ * t0)))
    m = PartOnSurface(wf, PartParams(MU_S, MU_K, e=0.0)).start(t0, vx=u0)
    m.run(t0 + 1 / freq)
    kinds = [(e.kind, e.t) for e in m.events]
    assert [k for k, _ in kinds[:3]] == ["slip", "stick", "launch"]
    assert kinds[1][1] == pytest.approx(t_stop, rel=1e-10)
    assert kinds[2][1] == pytest.approx(t_l, rel=1e-12)
    # x at the stop: integral of u, closed form
    tau = t_stop - t0
    x_stop = (u0 * tau - MU_K * (0.5 * G * tau ** 2
                                + amp * (math.sin(w_ * t_stop) - math.sin(w_ * t0))
                                - amp * w_ * math.cos(w_ * t0) * tau))
    assert m.events[1].x == pytest.approx(x_stop, rel=1e-9)
    assert m.events[2].x == pytest.approx(x_stop, rel=1e-9)  # stuck until the launch


# -- is_locked -----------------------------------------------------------------------------
@pytest.mark.parametrize("gamma", [1.2, 2.0, 3.0, 3.29, 3.30, 3.5, 4.0])
def test_is_locked_without_restitution_is_the_closed_form_limit(gamma):
    # e = 0: the flight from the launch lasts less than a period iff Gamma < sqrt(1 + pi^2)
    assert H.is_locked(gamma, 0.0) is (gamma < math.sqrt(1 + math.pi ** 2))


def rest_phase(gamma: float, e: float) -> float:
    """Phase at which a part launched from rest on sin(theta) (gravity 1/Gamma) is
    back at rest, bounce by bounce: an independent bouncing-ball computation."""
    th = math.asin(1 / gamma)
    z, v = math.sin(th), math.cos(th)
    deadline = th + 2 * math.pi          # the next launch phase
    while th < deadline + 0.1:
        z0, v0, th0 = z, v, th

        def gap(t, z0=z0, v0=v0, th0=th0):
            return z0 + v0 * (t - th0) - (t - th0) ** 2 / (2 * gamma) - math.sin(t)

        rel = v0 - math.cos(th0)          # relative normal velocity after the bounce
        decel = 1 / gamma - math.sin(th0)  # gap'' at th0
        step = min(0.01, 0.05 * 2 * rel / decel) if decel > 0 and rel > 0 else 0.01
        t = th0 + step * 1e-3
        while gap(t + step) > 0:
            t += step
        th = brentq(gap, t, t + step, xtol=1e-15)
        w = v0 - (th - th0) / gamma - math.cos(th)
        z, v = math.sin(th), math.cos(th) - e * w
        n = 1 / gamma - math.sin(th)     # normal force per unit mass at the landing
        if -w < 1e-6 and n > 0:          # sum the remaining bounces (< 1e-5 rad)
            return th + 2 * e * -w / ((1 - e) * n)
    return th  # still bouncing after the next launch phase


@pytest.mark.parametrize("e", [0.1, 0.3, 0.5])
def test_is_locked_with_restitution_against_an_independent_bouncing_ball(e):
    outcomes = set()
    for gamma in (1.3, 1.8, 2.2, 2.6, 2.9, 3.2):
        margin = math.asin(1 / gamma) + 2 * math.pi - rest_phase(gamma, e)
        if abs(margin) < 1e-3:
            continue  # too close to call with the bounce cut-off
        assert H.is_locked(gamma, e) is (margin > 0), f"Gamma={gamma}, e={e}"
        outcomes.add(margin > 0)
    assert outcomes == {True, False}


# -- smaller promises of the model ------------------------------------------------------------
def test_impact_friction_impulse_grows_with_restitution():
    """The normal impulse of an impact with restitution e is (1 + e) |w| per unit mass."""
    h, e = 1e-3, 0.5
    wf = SineWaveform(50.0, 0.0, 0.0)
    m = PartOnSurface(wf, PartParams(MU_S, MU_K, e=e, mass=2e-6)).start(0.0, z=h, vx=1.0, vz=0.0)
    m.run(0.1, stop_on=("impact",))
    impact = [ev for ev in m.events if ev.kind == "impact"][0]
    w = -math.sqrt(2 * G * h)
    assert impact.info["impulse_n"] == pytest.approx(2e-6 * (1 + e) * -w, rel=1e-12, abs=0)  # [N s], ~4e-7
    assert impact.vx == pytest.approx(1.0 + MU_K * (1 + e) * w, rel=1e-12)
    assert impact.vz == pytest.approx(-e * w, rel=1e-12)


def test_summed_chattering_interpolates_the_slide_and_rests_on_the_surface():
    """With a wide chatter tolerance the bounces are summed at once: the summed stretch
    moves x at the mean of its end speeds, and the part rests on the moving surface."""
    freq = 20.0
    wf = SineWaveform.from_gamma(freq, 0.3, 0.2, 30.0)   # Gamma < 1: the surface always pushes
    m = PartOnSurface(wf, PartParams(MU_S, MU_K, e=0.5), chatter_tol=10.0)
    zs0 = wf.position(0.0)[1]
    m.start(0.0, z=zs0 + 1e-5, vx=0.3, vz=0.0)
    m.run(0.5 / freq, stop_on=("rest",))
    rest = [ev for ev in m.events if ev.kind == "rest"]
    assert rest
    seg = [s for s in m.segments if s.mode == "chatter"][0]
    assert m.z == wf.position(rest[0].t)[1] and m.vz == wf.velocity(rest[0].t)[1]
    mid = 0.5 * (seg.t0 + seg.t1)
    state = m.sample([mid])
    assert state["vx"][0] == pytest.approx(0.5 * (seg.vx0 + seg.vx1), rel=1e-12)
    v_mid = 0.5 * (seg.vx0 + seg.vx1)  # constant deceleration: x at the mean speed
    assert state["x"][0] == pytest.approx(seg.x0 + 0.5 * (seg.vx0 + v_mid) * (mid - seg.t0), rel=1e-12)
    assert state["phase"][0] == "flight"


def test_invalid_part_and_placement_are_refused():
    with pytest.raises(ValueError, match="mass"):
        PartParams(0.5, 0.5, mass=0.0)
    with pytest.raises(ValueError, match="mu_k <= mu_s"):
        PartParams(0.3, 0.5)
    with pytest.raises(ValueError, match="0 <= e < 1"):
        PartParams(0.5, 0.5, e=1.0)
    wf = SineWaveform.from_gamma(50.0, 0.5, 0.0)
    with pytest.raises(ValueError, match="incline"):
        PartOnSurface(wf, PartParams(0.5, 0.5), incline=95.0)
    zs = wf.position(0.003)[1]
    with pytest.raises(ValueError, match="below the surface"):
        PartOnSurface(wf, PartParams(0.5, 0.5)).start(0.003, z=zs - abs(zs) * 1e-10)


def test_simulate_sums_chattering_by_default():
    wf = SineWaveform(10.0, 0.0, 0.0)
    from vibrofeed.models.part_on_surface import simulate

    tr = simulate(wf, PartParams(0.5, 0.5, e=0.5), n_periods=3.0, initial=dict(z=1e-3))
    assert len(tr.events_of("rest")) == 1 and tr.phase[-1] == "stick"


def test_hopping_defaults():
    lo, hi = H.rebound_window()
    assert lo == H.period_one_limit(1) and (lo, hi) == H.rebound_window(1)
    flights, _, (ta, tb) = H.run_flights(2.0, n_periods=4, n_transient=4)  # e = 0 by default
    assert flights and all(f.w_land <= 0 for f in flights)
    assert H.ideal_speed(2.0, n_periods=8, n_transient=8) == pytest.approx(
        H.ideal_speed(2.0, 0.0, n_periods=8, n_transient=8), rel=1e-12)  # the same run
    # chattering bounces (shorter than 1 % of a period) are left out of the diagram by default
    (jumps,) = H.bifurcation_diagram([2.0], 0.5, n_periods=8, n_transient=8, sweep=False)
    (every,) = H.bifurcation_diagram([2.0], 0.5, n_periods=8, n_transient=8, sweep=False,
                                     min_jump=0.0)
    assert jumps.min() >= 1e-2 and every.min() < 1e-2


def test_square_wave_closed_form_refuses_hopping():
    from vibrofeed.models.subhopping import square_wave_speed

    with pytest.raises(ValueError, match="regime"):
        square_wave_speed(50.0, 0.8 * G, G, 0.75, 0.6)  # acc_n = g: the part is weightless in B


def test_steady_speed_is_the_mean_of_the_last_two_blocks():
    from vibrofeed.models.part_on_surface import mean_velocity

    wf = SineWaveform.from_gamma(50.0, 0.6, 0.9, 60.0)
    ss = mean_velocity(wf, PartParams(0.6, 0.35), n_transient=2, n_block=3, max_blocks=4)
    assert ss.velocity == 0.5 * (ss.block_velocities[-1] + ss.block_velocities[-2])
    assert ss.n_periods == 2 + 3 * len(ss.block_velocities)


def test_one_averaging_block_is_its_own_answer():
    from vibrofeed.models.part_on_surface import mean_velocity

    wf = SineWaveform.from_gamma(50.0, 0.6, 0.9, 60.0)
    ss = mean_velocity(wf, PartParams(0.6, 0.35), n_transient=2, n_block=3, max_blocks=1)
    assert ss.velocity == ss.block_velocities[0] and not ss.converged and ss.change == math.inf


def test_summed_chattering_leaves_the_part_at_the_surfaces_along_track_speed():
    """A part dropped with the surface's along-track speed stops relative to it at the first impact;
    the summed bounces end with it riding the surface: vx = the surface's tangential velocity at the
    end of the series (not its normal one: the 30 degree stroke makes them differ)."""
    freq = 20.0
    wf = SineWaveform.from_gamma(freq, 0.3, 0.2, 30.0)
    m = PartOnSurface(wf, PartParams(MU_S, MU_K, e=0.5), chatter_tol=10.0)
    t0 = 0.0
    m.start(t0, z=wf.position(t0)[1] + 1e-7, vx=float(wf.velocity(t0)[0]), vz=float(wf.velocity(t0)[1]))
    m.run(0.5 / freq, stop_on=("rest",))
    rest = [ev for ev in m.events if ev.kind == "rest"][0]
    vt, vn = wf.velocity(rest.t)
    assert abs(vt - vn) > 1e-3 * abs(vt)
    assert rest.vx == pytest.approx(vt, rel=1e-12, abs=0)
    assert rest.vz == vn
