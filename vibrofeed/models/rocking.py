"""Rocking and tipping of a rigid block on a vibrating or inclined plate.

A block stands on a flat plate and may pivot about one edge of its footprint. Seen in
the plane of rocking, its centre of mass (COM) sits at the horizontal distance ``b``
from the pivot edge and at the height ``h`` above the plate: the block's slenderness
angle is alpha = atan(b / h), its pivot-to-COM distance R = sqrt(b^2 + h^2).

Sources:

- G. W. Housner, "The behavior of inverted pendulum structures during earthquakes",
  Bull. Seismol. Soc. Am. 53(2), 403-417 (1963): section "Rocking of a rigid block"
  (the onset of rocking under a base acceleration, a_t > g b / h) and section
  "Free vibration" (the impact: angular momentum about the new pivot is conserved,
  which keeps the fraction r of the angular velocity, eq. for r below).
- The static tipping-or-sliding criterion of a block on an incline is the same moment
  balance with gravity's along-slope part as the "base acceleration" (e.g.
  J. L. Meriam, L. G. Kraige, *Engineering Mechanics: Statics*, section 6/3, "Tipping
  versus sliding").

Onset (Housner, "Rocking of a rigid block"). On a plate accelerating by a_t along the
track and a_n normal to it, inclined by ``incline`` (beta; gravity g (-sin beta, 0,
-cos beta) in the track's frame, as the decks tilt it), the block feels in the plate's
frame the along-track load m (a_t + g sin beta) backwards and the normal load
m (g cos beta + a_n). It lifts off its front edge and pivots about its rear edge when
the moment of the first about that edge exceeds the restoring moment of the second:

    a_t + g sin beta > (g cos beta + a_n) b / h     (pivot on the rear edge)
   -a_t - g sin beta > (g cos beta + a_n) b / h     (pivot on the front edge)

provided friction holds the pivot: the along load needs mu > b / h at the onset (with
mu < b / h the block slides first, and a sliding block does not tip). For the sine of
the decks (x_s = amp_t sin(w t), z_s = amp_n sin(w t + phase)) the largest left-hand
side minus right-hand side over a period is a closed form (:func:`sine_rocking_margin`);
with amp_n = 0 and beta = 0 the threshold amplitude is amp_t = g (b / h) / w^2.

Free rocking (Housner, "Free vibration"). At each impact the block changes pivot from
one edge to the other, 2 b apart; with no bounce and no slip the angular momentum about
the new pivot is conserved:

    I_O w2 = (I_O - 2 m b^2) w1 = (I_O - 2 m R^2 sin^2 alpha) w1
    r = w2 / w1 = 1 - (m R^2 / I_O) (1 - cos 2 alpha)

(1 - cos 2 alpha = 2 sin^2 alpha), I_O the inertia about the pivot axis. For a uniform
rectangular block of width 2 b and height 2 h, I_O = I_G + m R^2 = (4/3) m R^2, so
r = 1 - (3/2) sin^2 alpha: both forms of the brief are the same law, the second the
first's value for a solid block (:func:`impact_ratio`, :func:`block_impact_ratio`).
A block with another inertia (a clump whose pivot is inside its outline, below) takes
the general form.

Tipping versus sliding on an incline beta (at rest, plate still): it stays if tan beta
<= min(mu, b / h); otherwise it slides if mu < b / h (friction gives way before the
moment does; a sliding block's friction, mu N, still cannot tip it) and tips if
mu > b / h (:func:`incline_regime`).

A clump's rounded edges (:func:`clump_pivot`). A clump of spheres of one diameter d
whose centres span D - d along each of the part's dimensions D rests on the bottoms of
its lowest spheres. Tilting it, each sphere rolls on the plate, so the pivot at the
onset (zero tilt) is the contact point directly below the outermost sphere's centre,
not the corner of the box: b = half the span of the sphere centres across the face it
stands on, (D_across - d) / 2, not half the face D_across / 2. The COM is the box's
centre, at h = D_vertical / 2 above the plate (the spheres' bottoms are at the box's
face). So a clump's b / h = (D_across - d) / D_vertical, smaller than the box's
D_across / D_vertical: it rocks and tips earlier than the sharp-edged box.
"""

from __future__ import annotations

import math

import numpy as np

from .constants import TWO_PI, G

#: Regimes of :func:`incline_regime`.
REST, SLIDE, TIP = 0, 1, 2
REGIME_NAMES = {REST: "rest", SLIDE: "slide", TIP: "tip"}


# ------------------------------------------------------------------ geometry
def clump_pivot(across: float, vertical: float, d: float) -> tuple[float, float]:
    """(b, h) [m] of a clump of spheres of diameter ``d`` standing on a face of width
    ``across`` (the dimension along the rocking direction) with ``vertical`` its height:
    b = (across - d) / 2 (half the span of the sphere centres, the pivot being below the
    outermost centre), h = vertical / 2 (the COM at the centre, the clump resting on its
    spheres' bottoms). See the module's docstring."""
    if d <= 0 or d > min(across, vertical):
        raise ValueError(f"sphere diameter {d:g} m must be in (0, {min(across, vertical):g}] m")
    return (across - d) / 2, vertical / 2


def slenderness(b: float, h: float) -> float:
    """alpha = atan(b / h) [rad]."""
    return math.atan2(b, h)


# ------------------------------------------------------------------ onset
def onset_acceleration(b: float, h: float, incline: float = 0.0, a_n: float = 0.0,
                       g: float = G) -> float:
    """The along-track plate acceleration [m/s^2] at which the block starts to pivot on
    its rear edge (Housner): (g cos beta + a_n) b / h - g sin beta; ``incline`` beta in
    degrees, a_n the plate's normal acceleration [m/s^2] at that moment."""
    beta = math.radians(incline)
    return (g * math.cos(beta) + a_n) * b / h - g * math.sin(beta)


def slides_first(mu: float, b: float, h: float) -> bool:
    """True when friction gives way before the block can pivot (mu <= b / h): the block
    slides, and Housner's onset does not apply."""
    return mu <= b / h


def rocking_margin(b: float, h: float, a_t, a_n, incline: float = 0.0, g: float = G) -> float:
    """max over the samples of |a_t + g sin beta| - (g cos beta + a_n) b / h [m/s^2]:
    positive when the block pivots at some moment of the given plate accelerations
    (arrays over a period, [m/s^2]; ``incline`` in degrees). The general form of
    :func:`sine_rocking_margin` for any waveform."""
    beta = math.radians(incline)
    a_t, a_n = np.asarray(a_t, dtype=float), np.asarray(a_n, dtype=float)
    return float(np.max(np.abs(a_t + g * math.sin(beta)) - (g * math.cos(beta) + a_n) * b / h))


def sine_rocking_margin(b: float, h: float, freq: float, amp_t: float, amp_n: float = 0.0,
                        phase: float = 0.0, incline: float = 0.0, g: float = G) -> float:
    """The largest rocking margin [m/s^2] over a period of the decks' sine drive
    (x_s = amp_t sin(w t), z_s = amp_n sin(w t + phase), phase in degrees): with
    k = b / h, a_t = -amp_t w^2 sin(w t), a_n = -amp_n w^2 sin(w t + phase),
    max(a_t - k a_n) = w^2 sqrt(amp_t^2 + k^2 amp_n^2 - 2 k amp_t amp_n cos phase),
    max(-a_t - k a_n) = w^2 sqrt(amp_t^2 + k^2 amp_n^2 + 2 k amp_t amp_n cos phase), so

        margin = max(S- + g sin beta, S+ - g sin beta) - k g cos beta.

    Positive: the block rocks (if mu > b / h and it stays on the plate, amp_n w^2 <
    g cos beta)."""
    k = b / h
    w2 = (TWO_PI * freq) ** 2
    c = math.cos(math.radians(phase))
    beta = math.radians(incline)
    s_minus = w2 * math.sqrt(max(amp_t**2 + (k * amp_n) ** 2 - 2 * k * amp_t * amp_n * c, 0.0))
    s_plus = w2 * math.sqrt(max(amp_t**2 + (k * amp_n) ** 2 + 2 * k * amp_t * amp_n * c, 0.0))
    return max(s_minus + g * math.sin(beta), s_plus - g * math.sin(beta)) - k * g * math.cos(beta)


def sine_threshold_amplitude(b: float, h: float, freq: float, incline: float = 0.0,
                             g: float = G) -> float:
    """The along-track sine amplitude [m] at which the block starts to rock (amp_n = 0):
    amp_t w^2 = g (cos beta b / h - |sin beta|); 0 when the incline alone tips it."""
    beta = math.radians(incline)
    need = g * (math.cos(beta) * b / h - abs(math.sin(beta)))
    return max(need, 0.0) / (TWO_PI * freq) ** 2


# ------------------------------------------------------------------ free rocking
def impact_ratio(m: float, R: float, I_O: float, alpha: float) -> float:
    """Housner's fraction of the angular velocity kept at an impact [-]:
    r = 1 - (m R^2 / I_O) (1 - cos 2 alpha); m [kg], R [m] pivot-to-COM, I_O [kg m^2]
    the inertia about the pivot axis, alpha [rad]."""
    return 1.0 - m * R**2 / I_O * (1.0 - math.cos(2.0 * alpha))


def block_impact_ratio(b: float, h: float) -> float:
    """r = 1 - (3/2) sin^2 alpha of a uniform rectangular block of width 2 b and height
    2 h (I_O = (4/3) m R^2)."""
    return 1.0 - 1.5 * math.sin(slenderness(b, h)) ** 2


def clump_impact_ratio(b: float, h: float, gyration_sq: float) -> float:
    """r of a body whose pivots are 2 b apart at the COM height h, with the inertia about
    the COM I_G = m ``gyration_sq`` [m^2] (for a clump with its box's true inertia,
    gyration_sq = (D_across^2 + D_vertical^2) / 12): I_O = m (gyration_sq + R^2)."""
    R2 = b * b + h * h
    return impact_ratio(1.0, math.sqrt(R2), gyration_sq + R2, slenderness(b, h))


def impact_speed(theta0: float, b: float, h: float, gyration_sq: float, g: float = G,
                 rolling_radius: float = 0.0) -> float:
    """Angular speed [rad/s] at the first impact of a block released at rest tilted by
    ``theta0`` [rad] (0 < theta0 < alpha) on its pivot, from energy: w^2 = 2 g dz /
    (gyration_sq + R^2), dz the COM's fall. On a sharp edge dz = R (cos(alpha - theta0) -
    cos alpha) = h cos theta0 + b sin theta0 - h. A clump's pivot is a sphere of radius
    ``rolling_radius`` rolling on the plate: the COM stands at rho + (h - rho) cos theta +
    b sin theta, so dz gains rho (1 - cos theta0) (3 % more speed for the 1 x 0.5 x 0.35 mm
    box on its end released at 10 degrees)."""
    R = math.hypot(b, h)
    alpha = slenderness(b, h)
    if not 0 < theta0 < alpha:
        raise ValueError(f"release tilt {theta0:g} rad must be in (0, alpha = {alpha:g}) rad")
    rho = rolling_radius
    dz = (h - rho) * math.cos(theta0) + b * math.sin(theta0) + rho - h
    return math.sqrt(2 * g * dz / (gyration_sq + R * R))


# ------------------------------------------------------------------ incline
def incline_regime(incline: float, mu: float, b: float, h: float) -> int:
    """What a block at rest on a still plate inclined by ``incline`` [deg] does: REST if
    tan beta <= min(mu, b / h), else SLIDE if mu < b / h, else TIP."""
    t = math.tan(math.radians(abs(incline)))
    k = b / h
    if t <= min(mu, k):
        return REST
    return SLIDE if mu < k else TIP


def regime_map(inclines, mus, b: float, h: float) -> np.ndarray:
    """:func:`incline_regime` on a grid: an int array (len(inclines), len(mus))."""
    return np.array([[incline_regime(beta, mu, b, h) for mu in mus] for beta in inclines], dtype=int)
