"""Squeeze-film air damping (vibrofeed/models/squeeze_film.py) against Khan &
Sarma, "Vibratory Assembly Update: Part Transportation Mechanics Analysis",
§3.2 and its Figure 13 (a silicon disc 400 um across, 200 um thick, launched at
Gamma = 10 from several clearances).

Asserted: Stefan's law from the lubrication pressure and its scaling; the
exact momentum integral along the ODE's solution; the inverse-square
saturated deficit (log-log slope -2); Figure 13 read at the top of the flight
(saturated while the stroke is large against the clearance, falling where it
is not, no hop once the deficit exceeds the launch velocity) and read as the
report's ODE over a fixed 10 ms window (slope +1 in frequency at low
frequency, the riding limit, saturation above); the first-order small-damping
perturbation of the flight's height; the free-flow limit.
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from vibrofeed.models import squeeze_film as sf
from vibrofeed.models.constants import G

MU = sf.AIR_VISCOSITY
M = sf.FIG13_MASS
R = sf.FIG13_RADIUS


def slope(x, y):
    return np.polyfit(np.log(x), np.log(y), 1)[0]


def test_stefan_force_is_the_integral_of_the_lubrication_pressure():
    # Reynolds' equation for a disc approaching a plane at V: (1/rho) d/drho(rho h^3 p' / (12 mu)) = V,
    # p(r) = 0, gives p(rho) = 3 mu V (r^2 - rho^2) / h^3; the force is its integral over the disc.
    r, h, v = 200e-6, 5e-6, 0.1
    force, _ = quad(lambda rho: 2 * math.pi * rho * 3 * MU * v * (r ** 2 - rho ** 2) / h ** 3, 0, r,
                    epsabs=0, epsrel=1e-12)
    assert sf.stefan_force(MU, r, h, v) == pytest.approx(force, rel=1e-10)
    # Dimensions: mu [Pa s] r^4 [m^4] V [m/s] / h^3 [m^3] is Pa m^2 = N; lengths scaled
    # by k scale the force by k; it is linear in mu and V.
    k = 3.0
    assert sf.stefan_force(MU, k * r, k * h, v) == pytest.approx(k * force, rel=1e-12)
    assert sf.stefan_force(2 * MU, r, h, 3 * v) == pytest.approx(6 * force, rel=1e-12)


def test_film_limits_at_small_and_large_gaps():
    disc = sf.Film(MU, R, h_c=1e-6)
    # contact: the film keeps the clearance; the force is Stefan's there
    assert disc.thickness(-1e-7) == disc.h_c == disc.thickness(0.0)
    stefan = sf.stefan_force(MU, R, disc.h_c, 1.0)
    assert disc.coefficient(disc.h_c) == pytest.approx(stefan + 16 * MU * R, rel=1e-12)
    # far away: the face-on Stokes drag of a disc, 16 mu r
    assert disc.coefficient(10 * R) == pytest.approx(16 * MU * R, rel=1e-3)
    sphere = sf.Film(MU, 150e-6, h_c=1e-6, flat=False)
    assert sphere.coefficient(1e-7) == pytest.approx(6 * math.pi * MU * 150e-6 ** 2 / 1e-7, rel=1e-3)
    assert sphere.coefficient(1e3) == pytest.approx(6 * math.pi * MU * 150e-6, rel=1e-6, abs=0)
    # the film cannot be thinner than the mean free path
    assert sf.clearance(0.0) == sf.MEAN_FREE_PATH and sf.clearance(2e-6) == 2e-6
    with pytest.raises(ValueError):
        sf.saturated_deficit(sphere, M)


@pytest.mark.parametrize("flat, side", [(True, 0.0), (False, 0.0), (True, 300e-6)],
                         ids=["disc", "sphere", "square"])
def test_impulse_is_the_integral_of_the_coefficient(flat, side):
    film = sf.Film(MU, R, h_c=3e-6, flat=flat, side=side)
    h0, h1 = 3e-6, 400e-6
    # in log h, where the integrand is smooth
    want, _ = quad(lambda u: film.coefficient(math.exp(u)) * math.exp(u), math.log(h0), math.log(h1),
                   epsabs=0, epsrel=1e-12)
    assert film.impulse(h0, h1) == pytest.approx(want, rel=1e-9, abs=0)  # N s, from 1e-10


def test_the_deficit_is_a_function_of_the_gap_along_the_whole_flight():
    # The film force is -d/dt of a function of the gap: deficit(t) = impulse(h_c, h(t)) / m,
    # at every point of the ODE's solution, Stokes drag included.
    film = sf.Film(MU, R, h_c=5e-6, free_flow=True)
    run = sf.launch(film, M, 100.0, 10.0)
    assert run.end == "apex" and len(run.t) > 50
    want = film.impulse(film.h_c, run.gap + film.h_c) / M
    np.testing.assert_allclose(run.deficit, want, rtol=1e-6, atol=1e-9 * run.v_launch)
    # launch: w t0 = asin(1 / Gamma), at the surface's velocity
    w = 2 * math.pi * 100.0
    assert w * run.t0 == pytest.approx(math.asin(1 / 10.0), rel=1e-12)
    assert run.v_launch == pytest.approx(10 * G / w * math.cos(math.asin(0.1)), rel=1e-12)


def test_saturated_deficit_is_inverse_square_in_the_clearance():
    clearances = np.geomspace(3e-6, 30e-6, 5)
    deficits = [sf.apex_deficit(h0, 50.0).final_deficit for h0 in clearances]
    assert slope(clearances, deficits) == pytest.approx(-2.0, abs=0.01)
    for h0, d in zip(clearances, deficits):
        assert d == pytest.approx(sf.saturated_deficit(sf.fig13_film(h0), M), rel=5e-3)


def test_figure13_at_the_top_of_the_flight():
    # Stroke a = Gamma g / w^2 against the clearance h0 decides: saturated while a >> h0
    # (low frequencies), below the saturation where a nears h0 (high frequencies).
    h0 = 5e-6
    sat = sf.saturated_deficit(sf.fig13_film(h0), M)
    freqs = [1.0, 10.0, 100.0, 300.0, 1000.0]
    runs = [sf.apex_deficit(h0, f) for f in freqs]
    for f, run in zip(freqs, runs):
        stroke = sf.FIG13_GAMMA * G / (2 * math.pi * f) ** 2
        assert run.end == "apex"
        # the exact momentum integral at the apex, to 1e-9 (launch's rtol 1e-10, accumulated over the run)
        want = sf.fig13_film(h0).impulse(h0, h0 + run.max_gap) / M
        assert run.final_deficit == pytest.approx(want, rel=1e-9, abs=0)
        if stroke >= 5 * h0:
            assert run.final_deficit == pytest.approx(sat, rel=0.02)
        if stroke <= h0:
            assert run.final_deficit < 0.8 * sat
    # no low-frequency dependence: 1 to 100 Hz agree to 1e-4
    assert np.ptp([r.final_deficit for r in runs[:3]]) < 1e-4 * sat
    assert all(a.final_deficit >= b.final_deficit for a, b in zip(runs, runs[1:]))


def test_no_hop_once_the_deficit_exceeds_the_launch_velocity():
    h0 = 2e-6  # saturated deficit 0.29 m/s
    sat = sf.saturated_deficit(sf.fig13_film(h0), M)
    for f in (100.0, 300.0):  # launch velocities 0.155 and 0.052 m/s
        run = sf.apex_deficit(h0, f)
        assert run.v_launch < sat
        # it never gets free: the gap stops growing within a few clearances (without
        # air it would rise (v_l)^2 / 2g, tens to hundreds of clearances)
        assert run.max_gap < 3 * h0 < 0.1 * run.v_launch ** 2 / (2 * G)
    free = sf.apex_deficit(h0, 20.0)  # launch velocity 0.78 m/s > 0.29 m/s: it hops
    assert free.v_launch > sat and free.end == "apex"
    assert free.max_gap > 1000 * h0
    assert free.final_deficit == pytest.approx(sat, rel=1e-3)


def test_figure13_as_the_report_integrates_it_over_a_fixed_window():
    window, h0 = 0.01, 5e-6
    sat = sf.saturated_deficit(sf.fig13_film(h0), M)
    low = [0.03, 0.1, 0.3]
    d_low = [sf.window_deficit(h0, f, window) for f in low]
    # below ~1 Hz the part still rides the surface: slope +1 in frequency, the riding limit
    assert slope(low, d_low) == pytest.approx(1.0, abs=0.02)
    for f, d in zip(low, d_low):
        assert d == pytest.approx(sf.riding_deficit(f, sf.FIG13_GAMMA, window), rel=0.02)
        assert d < 0.2 * sat
    # above a few Hz: the limit of infinitely fast withdrawal
    for f in (10.0, 30.0, 100.0):
        assert sf.window_deficit(h0, f, window) == pytest.approx(sat, rel=2e-3)


def test_small_damping_perturbs_the_flight_height_to_first_order():
    # Weak film (large clearance): the gap is the free flight's minus the integral of
    # the deficit; at the top the shift of the apex time is second order, so
    # max gap = free max gap - int_{t0}^{t_apex} deficit(h_free(t)) dt + O(film^2).
    freq, gamma, h0 = 100.0, 10.0, 60e-6
    w = 2 * math.pi * freq
    a = gamma * G / w ** 2
    film = sf.fig13_film(h0)
    run = sf.launch(film, M, freq, gamma)
    t0, v0 = run.t0, run.v_launch
    z0 = a * math.sin(w * t0)

    def free_gap(t):
        return z0 + v0 * (t - t0) - G / 2 * (t - t0) ** 2 - a * math.sin(w * t)

    top = minimize_scalar(lambda t: -free_gap(t), bounds=(t0, t0 + 2 / freq), method="bounded",
                          options={"xatol": 1e-12})
    correction, _ = quad(lambda t: film.impulse(h0, free_gap(t) + h0) / M, t0, top.x, limit=200)
    exact_change = free_gap(top.x) - run.max_gap
    assert exact_change > 0
    assert exact_change == pytest.approx(correction, rel=0.02)
    assert correction / free_gap(top.x) < 0.05  # the perturbation is small indeed


def test_film_step_limit_is_a_tenth_of_the_relaxation_time():
    film = sf.fig13_film(1e-6)
    dt = sf.film_step_limit(film, M)
    assert dt * film.coefficient(film.h_c) / M == pytest.approx(0.1, rel=1e-12)
    assert sf.film_step_limit(sf.Film(0.0, R, 1e-6), M) == math.inf


def square_plate_poisson(n):
    """int phi over the unit square, nabla^2 phi = -1, phi = 0 on the edges, by the
    5-point finite-difference stencil on an n x n interior grid."""
    from scipy.sparse import diags, identity, kron
    from scipy.sparse.linalg import spsolve
    h = 1.0 / (n + 1)
    second = diags([1.0, -2.0, 1.0], [-1, 0, 1], shape=(n, n)) / h ** 2
    laplace = kron(identity(n), second) + kron(second, identity(n))
    phi = spsolve(laplace.tocsc(), -np.ones(n * n))
    return phi.sum() * h ** 2


def test_the_square_plates_stefan_constant_solves_the_reynolds_equation():
    # Reynolds: nabla^2 p = 12 mu V / h^3 on the face, p = 0 at its edge; F = int p, so
    # for a square of side a, F = 12 (int phi) mu a^4 V / h^3 with phi on the unit square.
    coarse, fine = square_plate_poisson(60), square_plate_poisson(120)
    extrapolated = fine + (fine - coarse) / 3  # the stencil's error is O(h^2)
    assert 12 * extrapolated == pytest.approx(sf.STEFAN_SQUARE, rel=2e-5)
    assert sf.STEFAN_SQUARE == pytest.approx(0.421731, abs=1e-6)
    # a long strip (L >> B): F = mu V L B^3 / h^3, the factor tends to 1 - 0.63 B / L
    assert sf.rectangle_factor(1e-3) == pytest.approx(1 - 192 / math.pi ** 5 * 1.0045 * 1e-3, rel=1e-6)
    # the disc of the same area squeezes harder: 1.5 pi r^4 with pi r^2 = a^2 is 1.5 / pi a^4
    assert 1.5 / math.pi / sf.STEFAN_SQUARE == pytest.approx(1.132, abs=1e-3)
    with pytest.raises(ValueError):
        sf.rectangle_factor(1.5)


def test_vibrofeed_parameters_holds_the_same_square_constant():
    from vibrofeed.parameters import STEFAN_SQUARE
    assert STEFAN_SQUARE == pytest.approx(sf.STEFAN_SQUARE, rel=1e-14)


def test_a_square_face_film_and_its_panels():
    a, h = 300e-6, 2e-6
    square = sf.Film(MU, 0.0, h_c=1e-6, side=a)
    assert square.coefficient(h) == pytest.approx(MU * sf.STEFAN_SQUARE * a ** 4 / h ** 3
                                                  + 16 * MU * a / math.sqrt(math.pi), rel=1e-12)
    # the equal-area disc's free-flow drag
    disc = sf.Film(MU, a / math.sqrt(math.pi), h_c=1e-6)
    assert square.free_coefficient == pytest.approx(disc.free_coefficient, rel=1e-12, abs=0)
    assert sf.saturated_deficit(square, 1e-8) == pytest.approx(
        0.5 * MU * sf.STEFAN_SQUARE * a ** 4 / (1e-8 * 1e-12), rel=1e-12)
    # a clump's n panels at one gap (a part lying flat) carry the face's force together
    gap, v = 3e-6, -0.02
    assert 9 * square.panel_force(gap, v, 9) == pytest.approx(square.force(gap, v), rel=1e-14)


def test_stokes_layer_is_sqrt_of_two_nu_over_omega():
    # the layer a plate vibrating at w drags along, delta = sqrt(2 nu / w): 0.2 mm at 100 Hz in air
    nu = 1.5e-5
    for freq in (10.0, 100.0, 1000.0):
        assert sf.stokes_layer(freq, nu) == pytest.approx(math.sqrt(2 * nu / (2 * math.pi * freq)),
                                                          rel=1e-14, abs=0)
    assert sf.stokes_layer(100.0) == pytest.approx(0.22e-3, rel=0.01)
    # air at 20 C: nu = mu / rho with rho = 1.204 kg/m^3
    assert sf.AIR_KINEMATIC_VISCOSITY == pytest.approx(sf.AIR_VISCOSITY / 1.204, rel=0.01)
    assert sf.stokes_layer(100.0) == pytest.approx(sf.stokes_layer(100.0, sf.AIR_KINEMATIC_VISCOSITY),
                                                   rel=1e-14, abs=0)


def test_film_force_opposes_the_relative_velocity_with_stefans_coefficient():
    # F = -(1.5 pi mu r^4 / h^3 + 16 mu r) v_rel, h = max(gap, 0) + h_c
    disc = sf.Film(MU, R, h_c=2e-6)
    for gap, h in ((-1e-7, 2e-6), (0.0, 2e-6), (3e-6, 5e-6)):
        for v in (0.05, -0.3):
            want = -(1.5 * math.pi * MU * R ** 4 / h ** 3 + 16 * MU * R) * v
            assert disc.force(gap, v) == pytest.approx(want, rel=1e-12, abs=0)
    # a sphere: -6 pi mu R (R / h + 1) v_rel
    sphere = sf.Film(MU, 150e-6, h_c=1e-6, flat=False)
    assert sphere.force(1e-6, 0.02) == pytest.approx(
        -6 * math.pi * MU * 150e-6 * (150e-6 / 2e-6 + 1) * 0.02, rel=1e-12, abs=0)


def test_rectangle_factor_takes_aspects_in_zero_to_one():
    assert sf.rectangle_factor(1.0) == sf.STEFAN_SQUARE
    for aspect in (0.0, -0.5, 1.0 + 1e-12):
        with pytest.raises(ValueError, match="aspect"):
            sf.rectangle_factor(aspect)


def test_a_film_is_an_immutable_value_and_a_disc_by_default():
    import dataclasses
    film = sf.Film(MU, R, 1e-6)
    assert film == sf.Film(MU, R, 1e-6, flat=True, free_flow=True, side=0.0)
    assert hash(film) == hash(sf.Film(MU, R, 1e-6, flat=True, free_flow=True, side=0.0))
    with pytest.raises(dataclasses.FrozenInstanceError):
        film.h_c = 2e-6


def test_figure13_part_is_the_reports_silicon_disc():
    # 400 um across, 200 um thick, at Gamma = 10; silicon of the decks' default density
    from vibrofeed.decks import Deck
    assert sf.FIG13_GAMMA == 10.0
    assert 2 * sf.FIG13_RADIUS == pytest.approx(400e-6, rel=1e-12) and sf.FIG13_THICKNESS == 200e-6
    for deck in ("single_part", "bulk_feeder"):
        assert float(Deck.find(deck).variables["density"].default) == sf.FIG13_DENSITY
    assert sf.FIG13_MASS == pytest.approx(math.pi * (200e-6) ** 2 * 200e-6 * sf.FIG13_DENSITY,
                                          rel=1e-12, abs=0)  # kg, ~6e-8


def free_flight(freq, gamma, g=G):
    """A part leaving the surface a sin(w t) at w t0 = asin(g / (Gamma G)) with its velocity, in
    free flight: the gap and the relative velocity against the time since lift-off."""
    w = 2 * math.pi * freq
    a = gamma * G / w ** 2
    t0 = math.asin(g / (gamma * G)) / w
    v0 = a * w * math.cos(w * t0)

    def gap(s):
        return a * math.sin(w * t0) + v0 * s - g * s * s / 2 - a * math.sin(w * (t0 + s))

    def u(s):
        return v0 - g * s - a * w * math.cos(w * (t0 + s))

    return t0, v0, gap, u


def first_downward_root(f, t_max, n=4000):
    from scipy.optimize import brentq
    s = np.linspace(t_max / n, t_max, n)
    k = np.nonzero(np.array([f(x) for x in s]) < 0)[0][0]
    return brentq(f, s[k - 1], s[k], xtol=1e-16, rtol=1e-15)


@pytest.mark.parametrize("freq", [3.0, 100.0])
def test_without_air_the_launch_is_free_flight_to_the_gaps_maximum(freq):
    # mu -> 0 (1e-20 Pa s: deficit ~1e-17 m/s): the part flies v_l - g t from w t0 = asin(1 / Gamma)
    # and the run stops where the gap is largest, v_part = v_surface
    film = sf.fig13_film(5e-6, viscosity=1e-20)
    run = sf.launch(film, M, freq, 10.0)
    t0, v0, gap, u = free_flight(freq, 10.0)
    t_top = first_downward_root(u, 2 / freq)
    assert run.end == "apex"
    assert run.t[0] == 0.0 and run.t0 == pytest.approx(t0, rel=1e-14)
    assert run.t[-1] == pytest.approx(t_top, rel=1e-9, abs=0)
    assert run.max_gap == run.gap[-1] == pytest.approx(gap(t_top), rel=1e-9, abs=0)
    np.testing.assert_allclose(run.gap, [gap(s) for s in run.t], rtol=0, atol=1e-9 * gap(t_top))
    np.testing.assert_allclose(run.v_part, v0 - G * run.t, rtol=0, atol=1e-9 * v0)
    np.testing.assert_allclose(run.v_surface, v0 - G * run.t - [u(s) for s in run.t], rtol=0, atol=1e-9 * v0)
    assert np.abs(run.deficit).max() < 1e-9 * v0


def test_a_part_that_cannot_get_free_rides_the_film_back_to_contact():
    # 0.2 um of air at 1 kHz: relaxation time tau = m / c(h0) = 3.4 ns, saturated deficit ~2000 x the
    # launch velocity. The film holds the part at x = tau u_free(t) (to tau w and 3 x / h0), u_free the
    # free flight's velocity relative to the surface: the gap never opens beyond 1e-3 h0 and closes
    # again; the run ends back on the track (gap <= 0) instead of at an apex.
    h0, freq = 0.2e-6, 1000.0
    film = sf.fig13_film(h0)
    tau = M / film.coefficient(h0)
    run = sf.launch(film, M, freq, 10.0)
    t0, v0, gap, u = free_flight(freq, 10.0)
    assert sf.saturated_deficit(film, M) > 1000 * v0
    assert run.end == "contact"
    u_max = max(u(s) for s in np.linspace(0, run.t[-1], 20001))
    assert run.max_gap == pytest.approx(tau * u_max, rel=0.01, abs=0)  # m, ~1e-10
    assert run.max_gap < 1e-3 * h0
    assert -1.001e-3 * h0 < run.gap[-1] <= 0  # closed, by no more than the event's 1e-3 h0
    assert run.gap[:-1].min() > run.gap[-1] and run.v_part[-1] < run.v_surface[-1]  # the first closing
    assert run.gap[-1] == pytest.approx(tau * u(run.t[-1]), rel=0.01)
    assert run.t[-1] > 1 / freq  # it rode the film over several periods
    # the momentum the film took, impulse(h0, h) / m, negative once the film is thinner than h0
    np.testing.assert_allclose(run.deficit, film.impulse(h0, run.gap + h0) / M, rtol=1e-6, atol=1e-9 * v0)


def test_the_reports_frame_starts_at_peak_surface_velocity_without_gravity():
    # report_frame: t0 = 0, v0 = a w; free flight is v_part = v0 (no gravity), gap = v0 t - a sin(w t);
    # a window shorter than the period (where the gap would stop growing) ends the run
    freq, gamma = 100.0, 0.5  # Gamma < 1 is allowed: nothing holds the part back in that frame
    w = 2 * math.pi * freq
    a = gamma * G / w ** 2
    film = sf.fig13_film(5e-6, viscosity=1e-20)
    run = sf.launch(film, M, freq, gamma, report_frame=True, window=0.6 / freq)
    assert run.end == "window"
    assert run.t0 == 0.0 and run.v_launch == pytest.approx(a * w, rel=1e-14)
    assert run.t[0] == 0.0 and run.t[-1] == pytest.approx(0.6 / freq, rel=1e-14)
    np.testing.assert_allclose(run.v_part, a * w, rtol=1e-9)
    np.testing.assert_allclose(run.v_surface, a * w * np.cos(w * run.t), rtol=0, atol=1e-12 * a * w)
    np.testing.assert_allclose(run.gap, a * w * run.t - a * np.sin(w * run.t), rtol=0, atol=1e-9 * a)
    assert np.abs(run.deficit).max() < 1e-9 * a * w


def test_a_part_riding_the_film_stops_after_max_periods():
    # report's frame, 0.2 um of air at 1 kHz: the part rides the surface (gap < 1e-3 h0, never an
    # apex nor a contact) and its deficit is the surface's velocity loss a w (1 - cos w t), to tau w
    freq, gamma, h0 = 1000.0, 10.0, 0.2e-6
    w = 2 * math.pi * freq
    film = sf.fig13_film(h0)
    run = sf.launch(film, M, freq, gamma, report_frame=True)
    assert run.end == "max_periods"
    assert run.t[-1] == pytest.approx(50 / freq, rel=1e-14)  # the default, 50 periods
    assert run.max_gap < 1e-3 * h0
    riding = [sf.riding_deficit(freq, gamma, t) for t in run.t]
    np.testing.assert_allclose(run.deficit, riding, rtol=0, atol=1e-4 * gamma * G / w)
    short = sf.launch(film, M, freq, gamma, report_frame=True, max_periods=2.5)
    assert short.end == "max_periods" and short.t[-1] == pytest.approx(2.5 / freq, rel=1e-14)


def test_launch_refuses_a_track_that_cannot_throw_the_part():
    film = sf.fig13_film(5e-6)
    for gamma in (1.0, 0.5):  # a w^2 <= g: the surface never pulls away faster than gravity
        with pytest.raises(ValueError, match="never leaves"):
            sf.launch(film, M, 100.0, gamma)
    # gravity g larger than the standard G the amplitude is taken in
    with pytest.raises(ValueError, match="never leaves"):
        sf.launch(film, M, 100.0, 2.0, 2 * G)


def test_launchs_options_are_keyword_only():
    with pytest.raises(TypeError):
        sf.launch(sf.fig13_film(5e-6), M, 100.0, 10.0, G, True)


def test_a_failed_integration_is_an_error_not_a_result(monkeypatch):
    from types import SimpleNamespace

    def failing(fun, t_span, y0, **options):
        return SimpleNamespace(status=-1, message="Required step size is less than spacing between numbers.",
                               t=np.array([t_span[0]]), y=np.zeros((2, 1)), t_events=[[], []])

    monkeypatch.setattr(sf, "solve_ivp", failing)
    with pytest.raises(RuntimeError, match="step size"):
        sf.launch(sf.fig13_film(5e-6), M, 100.0, 10.0)


@pytest.mark.parametrize("film", [sf.Film(MU, R, 3e-6), sf.Film(MU, 0.0, 3e-6, side=300e-6),
                                  sf.Film(MU, 150e-6, 3e-6, flat=False)], ids=["disc", "square", "sphere"])
def test_radau_gets_the_ode_of_the_film_and_its_jacobian(monkeypatch, film):
    # The ODE handed to the solver, state (gap x, relative velocity u):
    # x' = u, u' = -g + a w^2 sin(w t) - c(x + h_c) u / m; its Jacobian by central differences.
    seen = {}
    real = sf.solve_ivp

    def spy(fun, t_span, y0, **options):
        seen.update(fun=fun, jac=options["jac"])
        return real(fun, t_span, y0, **options)

    monkeypatch.setattr(sf, "solve_ivp", spy)
    freq, gamma = 100.0, 10.0
    w = 2 * math.pi * freq
    a = gamma * G / w ** 2
    sf.launch(film, M, freq, gamma)
    rhs, jac = seen["fun"], seen["jac"]
    for t, x, u in ((1e-3, 0.0, 0.01), (4e-3, 2e-6, -0.2), (7e-3, 40e-6, 0.3)):
        c = film.coefficient(x + film.h_c)
        want = [u, -G + a * w * w * math.sin(w * t) - c * u / M]
        np.testing.assert_allclose(rhs(t, np.array([x, u])), want, rtol=1e-12)
        dx, du = 1e-5 * (x + film.h_c), 1e-3 * abs(u)
        d_dx = (np.array(rhs(t, [x + dx, u])) - rhs(t, [x - dx, u])) / (2 * dx)
        d_du = (np.array(rhs(t, [x, u + du])) - rhs(t, [x, u - du])) / (2 * du)
        np.testing.assert_allclose(jac(t, np.array([x, u])), np.column_stack([d_dx, d_du]),
                                   rtol=1e-7, atol=1e-12)
