"""The block sliding under a drive with a component across the track (models.cross_shake):
without it, the one-dimensional block of part_on_surface; on a level floor, isotropic friction
makes a skewed drive convey along its own line; the walls' friction brakes it; a bowl's chute
sees the helix's drive along it and x theta across."""

import cmath
import math

import numpy as np
import pytest

from vibrofeed.bowl import track_drive
from vibrofeed.models.cross_shake import chute_drive, sliding_speed
from vibrofeed.models.deck import transport

FREQ, MU = 100.0, 0.5
SPEED = 1e-5  # [m/s] against speeds of 5-30 mm/s
STEP_ERROR = 5e-3  # the friction step's first-order error at 2000 steps a period (0.02-0.47 % here)


def one_dimensional(amp_t, amp_n, phase, incline):
    """The event-driven single-part model's speed (Khan & Sarma, §2.3.2) [m/s]."""
    return transport({"freq": FREQ, "amp_t": amp_t, "amp_n": amp_n, "phase": phase, "mu": MU,
                      "restitution": 0.06, "incline": incline}).velocity


@pytest.mark.parametrize("amp_t, amp_n, phase, incline", [
    (5e-5, 1.5e-5, -30.0, 2.0), (5e-5, 2e-5, 0.0, 0.0), (8e-5, 1e-5, -60.0, 4.0), (5e-5, 0.0, 0.0, -3.0),
])
@pytest.mark.parametrize("clearance", [None, 5e-4])
def test_without_a_drive_across_it_is_the_one_dimensional_block(amp_t, amp_n, phase, incline, clearance):
    """Within the step's error (0.5 %) of the event-driven model, walls or not (nothing pushes
    the block on one)."""
    s = sliding_speed(FREQ, complex(amp_t), 0j,
                      amp_n * cmath.exp(1j * math.radians(phase)), MU, incline, clearance)
    want = one_dimensional(amp_t, amp_n, phase, incline)
    assert s.velocity == pytest.approx(want, rel=STEP_ERROR, abs=SPEED)
    assert s.across == pytest.approx(0.0, abs=SPEED)


@pytest.mark.parametrize("beta", [20.0, 45.0, 70.0])
def test_on_a_level_floor_a_skewed_drive_conveys_along_its_own_line(beta):
    """Friction the same in every direction: the floor shaken along a line at beta to x carries
    the block along that line, at the one-dimensional speed of the drive's full amplitude."""
    amp, amp_n, phase = 6e-5, 1.5e-5, -30.0
    b = math.radians(beta)
    normal = amp_n * cmath.exp(1j * math.radians(phase))
    s = sliding_speed(FREQ, complex(amp * math.cos(b)), complex(amp * math.sin(b)), normal, MU)
    v = one_dimensional(amp, amp_n, phase, 0.0)
    assert s.velocity == pytest.approx(v * math.cos(b), rel=2e-3, abs=SPEED)
    assert s.across == pytest.approx(v * math.sin(b), rel=2e-3, abs=SPEED)


def test_against_the_walls_a_drive_across_slows_the_block_more_the_stronger_it_is():
    """The chute's drive at growing x: without walls the block keeps most of its speed along
    (it drifts across instead); between walls 0.9 mm apart it is pressed on one and slows far
    more, and more at every step of x."""
    free, walled = [], []
    for x in (0.0, 2e-3, 4e-3, 8e-3):
        along, across, normal = chute_drive(5e-5, 1.5e-5, -30.0, 2.0, 9.4e-3, x)
        free.append(sliding_speed(FREQ, along, across, normal, MU, 2.0).velocity)
        walled.append(sliding_speed(FREQ, along, across, normal, MU, 2.0, clearance=9e-4))
    assert walled[0].velocity == pytest.approx(free[0], rel=1e-9, abs=0)  # no drive across: no wall
    assert all(w.velocity < f - 1e-3 for w, f in zip(walled[1:], free[1:]))  # [m/s]
    speeds = [w.velocity for w in walled]
    assert all(a > b for a, b in zip(speeds, speeds[1:]))
    assert free[-1] > 0.9 * free[0]  # without walls the drive across costs under 10 %
    assert all(abs(w.across) <= 1e-3 * 2 * math.pi * FREQ * 5e-5 for w in walled)  # pinned: no drift


def test_a_floor_that_would_throw_the_block_is_refused():
    with pytest.raises(ValueError, match="would hop"):
        sliding_speed(FREQ, 5e-5 + 0j, 0j, 3e-5 + 0j, MU)  # 1.2 g normal
    with pytest.raises(ValueError, match="freq > 0"):
        sliding_speed(0.0, 5e-5 + 0j, 0j, 0j, MU)


@pytest.mark.parametrize("phase", [-30.0, 0.0, 45.0])
def test_the_chutes_drive_is_the_helixs_along_and_x_theta_across(phase):
    """At its start (x = 0) the chute's drive along and normal is the one the helix sees at its
    centre line (vibrofeed.bowl.track_drive); across, amp_t x cos(helix angle) / r_mid in phase
    with the torsion."""
    amp_t, amp_n, helix, r_mid = 5e-5, 1.5e-5, 3.0, 9.4e-3
    d = track_drive(amp_t, amp_n, phase, FREQ, helix, r_mid)
    along, across, normal = chute_drive(amp_t, amp_n, phase, helix, r_mid, 0.0)
    assert abs(along) == pytest.approx(d.amp_t, rel=1e-12, abs=0)
    assert abs(normal) == pytest.approx(d.amp_n, rel=1e-12, abs=0)
    lead = (math.degrees(cmath.phase(normal) - cmath.phase(along)) + 180) % 360 - 180
    assert lead == pytest.approx(d.phase, abs=1e-9)  # [deg]
    assert across == 0
    _, across, _ = chute_drive(amp_t, amp_n, phase, helix, r_mid, 6e-3)
    assert across == pytest.approx(amp_t * 6e-3 * math.cos(math.radians(helix)) / r_mid, rel=1e-12, abs=0)


def test_the_refusals_at_their_boundaries_and_the_numbers_they_give():
    """A normal acceleration exactly at g cos(incline) is a hop (g set to it, so the two sides
    are one float); the message gives both; mu = 0 and a slow drive are accepted."""
    normal = 3e-5 + 0j
    w = 2 * math.pi * FREQ
    g = abs(normal) * w * w
    with pytest.raises(ValueError, match=r"normal acceleration \(11\.8 m/s\^2\) reaches g cos\(incline\) "
                                         r"\(11\.8\)"):
        sliding_speed(FREQ, 5e-5 + 0j, 0j, normal, MU, g=g)
    below = sliding_speed(FREQ, 5e-5 + 0j, 0j, normal, MU, g=g * (1 + 1e-9))
    assert math.isfinite(below.velocity)
    with pytest.raises(ValueError, match=r"mu >= 0, got freq=100.0, mu=-1e-09"):
        sliding_speed(FREQ, 5e-5 + 0j, 0j, 0j, -1e-9)
    # no friction on a level floor: the block keeps the floor's speed at t = 0, w A
    assert sliding_speed(FREQ, 5e-5 + 0j, 0j, 0j, 0.0).velocity == pytest.approx(w * 5e-5, rel=1e-12, abs=0)
    assert sliding_speed(0.5, 5e-5 + 0j, 0j, 0j, MU).cycle >= 1  # (a drive of 2 s periods)


def test_a_settled_block_repeats_a_cycle_of_whole_periods():
    """The 1D block settles at once into a cycle of one period (found at the first check, after
    AVERAGE periods); against a wall the cycle can be several periods long."""
    from vibrofeed.models.cross_shake import AVERAGE, MAX_PERIODS

    s = sliding_speed(FREQ, 5e-5 + 0j, 0j, 1.5e-5 * cmath.exp(-1j * math.radians(30)), MU, 2.0)
    assert (s.cycle, s.periods) == (1, AVERAGE)
    along, across, normal = chute_drive(5e-5, 1.5e-5, -30.0, 2.0, 9.4e-3, 6e-3)
    walled = sliding_speed(FREQ, along, across, normal, MU, 2.0, clearance=9e-4)
    assert 1 <= walled.cycle and walled.periods < MAX_PERIODS


def test_the_cycle_is_the_shortest_that_repeats_within_its_tolerance():
    from vibrofeed.models.cross_shake import _cycle

    three = np.tile([[1.0, 0.0], [2.0, 0.1], [4.0, -0.1]], (6, 1))
    assert _cycle(three, 1e-12) == 3
    assert _cycle(np.ones((9, 2)), 0.0) == 1
    noisy = three + np.r_[np.zeros((17, 2)), [[1e-3, 0.0]]]  # the last period off by 1e-3
    off = float(np.abs(noisy[-1] - noisy[-4]).max())  # (1e-3 to the float)
    assert _cycle(noisy, off) == 3 and _cycle(noisy, off * (1 - 1e-9)) == 0
    assert _cycle(three[:5], 1e-12) == 0  # 3 needs 6 periods, and a third of 5 is 1


@pytest.mark.parametrize("x", [2e-3, 6e-3])
def test_the_chute_is_the_same_mirrored(x):
    """A drive across of the other sign presses the block on the other wall: the same speed
    along (mirror symmetry), the mean across still 0."""
    along, across, normal = chute_drive(5e-5, 1.5e-5, -30.0, 2.0, 9.4e-3, x)
    a = sliding_speed(FREQ, along, across, normal, MU, 2.0, clearance=9e-4)
    b = sliding_speed(FREQ, along, -across, normal, MU, 2.0, clearance=9e-4)
    assert b.velocity == pytest.approx(a.velocity, rel=1e-9, abs=1e-12)
    assert b.across == pytest.approx(-a.across, rel=1e-9, abs=1e-12)


def test_walls_out_of_reach_change_nothing():
    """Walls further apart than the block drifts in MAX_PERIODS: the speed along is the free
    block's (its last half's mean: it drifts on across, so it never settles at a wall)."""
    along, across, normal = chute_drive(5e-5, 1.5e-5, -30.0, 2.0, 9.4e-3, 4e-3)
    free = sliding_speed(FREQ, along, across, normal, MU, 2.0)
    far = sliding_speed(FREQ, along, across, normal, MU, 2.0, clearance=10.0)
    # (to the cycle's tolerance, SETTLED of the floor's peak speed: 3e-5 m/s)
    assert far.cycle == 0 and far.velocity == pytest.approx(free.velocity, rel=0, abs=3e-5)
    assert far.across == pytest.approx(free.across, rel=0, abs=3e-5) and abs(free.across) > 1e-3


@pytest.mark.parametrize("shift", [40.0, -75.0])
def test_only_the_phases_between_the_motions_matter(shift):
    """Every motion's phase shifted alike (a later start of the clock) conveys the block as
    before: the along drive given a phase of its own, the normal one shifted with it, is the
    one-dimensional block of their phase difference."""
    s = cmath.exp(1j * math.radians(shift))
    got = sliding_speed(FREQ, 5e-5 * s, 0j, 1.5e-5 * cmath.exp(-1j * math.radians(30)) * s, MU, 2.0)
    assert got.velocity == pytest.approx(one_dimensional(5e-5, 1.5e-5, -30.0, 2.0), rel=STEP_ERROR, abs=SPEED)


def test_on_an_incline_the_hop_is_judged_against_g_cos_incline():
    """At 30 degrees a normal acceleration of 0.9 g hops (g cos 30 = 0.87 g), 0.85 g slides."""
    w = 2 * math.pi * FREQ
    g = 9.81
    with pytest.raises(ValueError, match=r"\(8\.83 m/s\^2\) reaches g cos\(incline\) \(8\.5\)"):
        sliding_speed(FREQ, 5e-5 + 0j, 0j, complex(0.9 * g / w ** 2), MU, incline=30.0, g=g)
    slides = sliding_speed(FREQ, 0j, 0j, complex(0.85 * g / w ** 2), 1.0, incline=30.0, g=g)
    assert math.isfinite(slides.velocity)


def test_a_bowls_chute_model_takes_its_drive_its_walls_and_its_parts():
    """vibrofeed.bowl.chute_speed: the chute's drive at x for the bowl's r_mid and helix angle,
    its play the track's width less a part's; chute_mean_speed: a lone part's length over
    time across it, by trapezoids on 1/v, 0 where it stalls, none where it hops."""
    from vibrofeed.bowl import CHUTE_POINTS, chute_mean_speed, chute_speed

    p = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 2.0, "turns": 0.5,
         "wall_height": 1e-3, "chute_length": 6e-3, "shape": 1, "part_size": 3e-4,
         "part_thickness": 1.5e-4, "freq": FREQ, "amp_t": 5e-5, "amp_n": 1.5e-5, "phase": -30.0, "mu": MU}
    r_mid = 0.01 - 0.6e-3
    want = sliding_speed(FREQ, *chute_drive(5e-5, 1.5e-5, -30.0, 2.0, r_mid, 3e-3), MU, 2.0,
                         clearance=1.2e-3 - 3e-4)
    assert chute_speed(p, 3e-3) == want
    xs = np.linspace(0.0, 6e-3 - 3e-4, CHUTE_POINTS)
    v = np.array([chute_speed(p, float(x)).velocity for x in xs])
    mean, note = chute_mean_speed(p)
    assert mean == pytest.approx((xs[-1] - xs[0]) / np.sum(np.diff(xs) * (1 / v[1:] + 1 / v[:-1]) / 2),
                                 rel=1e-12, abs=0)
    assert note == "" and v[-1] < mean < v[0]
    stalls, why = chute_mean_speed({**p, "chute_length": 0.014})  # past 12 mm it stops
    assert stalls == 0.0 and why.startswith("a lone part stalls on the chute by x = ")
    # (the first of the points, 0 to 13.7 mm, where it stands or goes back: not the slot's)
    xs = np.linspace(0.0, 0.014 - 3e-4, CHUTE_POINTS)
    v = np.array([chute_speed({**p, "chute_length": 0.014}, float(x)).velocity for x in xs])
    first = int(np.flatnonzero(v <= 0)[0])
    assert v[0] > 0 and first > 0 and why == f"a lone part stalls on the chute by x = {xs[first]:.3g} m"
    hops, why = chute_mean_speed({**p, "amp_n": 3e-5})
    assert hops is None and "only slides" in why


def test_the_cycles_searched_reach_a_third_of_the_periods_run_and_no_further():
    """A cycle of c periods is looked for once 3c periods have run: found in 9 periods of a
    3-cycle, not in 8 (though 8 would hold two of its repeats)."""
    from vibrofeed.models.cross_shake import _cycle

    three = np.tile([[1.0, 0.0], [2.0, 0.1], [4.0, -0.1]], (3, 1))
    assert _cycle(three, 1e-12) == 3
    assert _cycle(three[1:], 1e-12) == 0


def test_a_long_cycles_mean_is_the_long_run_mean():
    """Against a wall the motion repeats in a cycle of several periods; the speed is the mean
    over that cycle (not, say, its median): the mean of a run without the cycle search (the
    last half of 300 periods) agrees to the cycle's tolerance."""
    import vibrofeed.models.cross_shake as cs

    along, across, normal = chute_drive(5e-5, 1.5e-5, -30.0, 2.0, 9.4e-3, 6e-3)
    cycled = sliding_speed(FREQ, along, across, normal, MU, 2.0, clearance=9e-4)
    assert cycled.cycle >= 3
    found = cs._cycle
    try:
        cs._cycle = lambda per_period, tol: 0
        long_run = sliding_speed(FREQ, along, across, normal, MU, 2.0, clearance=9e-4)
    finally:
        cs._cycle = found
    assert long_run.cycle == 0
    assert cycled.velocity == pytest.approx(long_run.velocity, rel=0, abs=1e-3 * 2 * math.pi * FREQ * 5e-5)


@pytest.mark.parametrize("shift", [40.0, -75.0])
def test_a_skewed_drive_shifted_in_phase_as_a_whole_conveys_the_same(shift):
    """Along, across and normal shifted alike: the same speed (to the step's error) on a level
    floor without walls, along and across."""
    s = cmath.exp(1j * math.radians(shift))
    normal = 1.5e-5 * cmath.exp(-1j * math.radians(30))
    a = sliding_speed(FREQ, 5e-5 + 0j, 3e-5 + 0j, normal, MU)
    b = sliding_speed(FREQ, 5e-5 * s, 3e-5 * s, normal * s, MU)
    assert b.velocity == pytest.approx(a.velocity, rel=STEP_ERROR, abs=SPEED)
    assert b.across == pytest.approx(a.across, rel=STEP_ERROR, abs=SPEED)


def test_a_frictionless_block_drifts_across_to_a_wall_half_the_clearance_away():
    """Without friction (mu = 0, level floor) the block keeps the floor's speed at t = 0, w Ay
    across, and drifts from the middle by y(t) = Ay (w t - sin w t) relative to the floor:
    2 pi Ay a period. It reaches the wall at clearance / 2 in period n = floor(c / (4 pi Ay)),
    here 159 (its phase there, the root of phi - sin phi = 2 pi frac(c / (4 pi Ay)), below pi
    for frac < 1/2: the floor's acceleration presses it on the wall), is carried by that wall
    until the floor's speed is least (-w Ay, period n + 1/2) and leaves with it, drifting back
    by 2 pi Ay a period, not reaching the other wall by period 300. It never settles (no cycle
    with 0 mean across): the speed across is the mean of the last half, periods 150 to 300,
    the displacement over it / 150 T (the floor's mean velocity is 0), neither the median
    -w Ay of the periods drifting back nor w Ay had the walls been further. Along, the walls'
    friction (mu J) is 0."""
    from vibrofeed.models.cross_shake import MAX_PERIODS

    amp_x, amp_y, clearance = 5e-5, 2e-5, 0.04
    w, period = 2 * math.pi * FREQ, 1 / FREQ
    s = sliding_speed(FREQ, complex(amp_x), complex(amp_y), 0j, 0.0, clearance=clearance)
    side, per = clearance / 2, 2 * math.pi * amp_y  # [m], drift a period [m]
    n = math.floor(side / per)
    assert MAX_PERIODS == 300 and 150 < n < 300 and side / per - n < 0.5
    start = 150 * per  # [m] at period 150, still drifting out
    end = side - per * (300 - (n + 0.5))  # [m] at period 300, drifting back
    assert -side < end < side  # (the other wall not reached)
    assert s.cycle == 0 and s.periods == 300
    assert s.across == pytest.approx((end - start) / (150 * period), rel=0, abs=1e-3 * w * amp_y)  # [m/s]
    assert s.velocity == pytest.approx(w * amp_x, rel=1e-9, abs=0)


@pytest.mark.parametrize("k", [1, 2])
def test_between_walls_a_frictionless_block_bounces_in_a_cycle_of_2k_plus_1_periods(k):
    """Without friction, walls c = 2 pi Ay (k + 1/4) apart: the block leaves a wall when the
    floor's speed across is extreme (+-w Ay) and crosses (y = Ay (w t - sin w t) = c) in k
    periods and a phase psi, psi - sin psi = pi / 2 (psi < pi), arriving as the floor's
    acceleration presses it on that wall, which carries it to the floor's opposite extreme: a
    crossing every k + 1/2 periods, a cycle of 2k + 1. Its periods' mean speeds across are
    w Ay times 1 (k times), -1/4, -1 (k - 1 times), -3/4: their mean is 0 (the block stays
    between the walls; the floor's mean velocity is 0), so the cycle is found and kept (their
    median, -1/4 w Ay, would count as a drift across)."""
    amp_x, amp_y = 5e-5, 2e-5
    w = 2 * math.pi * FREQ
    s = sliding_speed(FREQ, complex(amp_x), complex(amp_y), 0j, 0.0,
                      clearance=2 * math.pi * amp_y * (k + 0.25))
    assert s.cycle == 2 * k + 1
    assert s.across == pytest.approx(0.0, abs=1e-3 * w * amp_y)  # [m/s]
    assert s.velocity == pytest.approx(w * amp_x, rel=1e-9, abs=0)
