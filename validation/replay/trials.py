"""Measured vertical-transport trials: reader and platform-motion interpolant.

Files (README of the data set): ``t`` [s], then for the tracked points
``p`` (platform/finger), ``o`` (part/object) and ``s`` (third marker):
``x?``, ``z?`` [mm], ``vx?``, ``vz?`` [mm/s], ``ax?``, ``az?`` [mm/s^2];
z up. Velocity and acceleration are the tracker's central differences and are
missing (a non-numeric placeholder) in the first and last rows.

``read_trial`` reads such a file as it is and returns SI arrays; anything
that is not such a trial raises ``vibrofeed.errors.TrialFileError`` naming
the file and the problem.

Platform motion for the model
-----------------------------
The file's velocity and acceleration columns are finite differences of noisy
positions; they are not derivatives of one motion (integrating them does not
give back the positions), so a model driven by them and compared with
positions is inconsistent. ``fit_position`` builds ONE interpolant of the
measured position and takes its exact derivatives:

* a quintic penalised spline (P-spline): B-spline basis with a knot at every
  frame, penalty lambda * sum (third differences of the coefficients)^2,
  i.e. a discrete version of lambda * int (z''')^2 -- the quintic smoothing
  spline. Quintic makes the acceleration a C2 cubic, so stick-band crossings
  are well defined;
* lambda is set by the noise, not by eye: the noise sigma is estimated
  robustly from high-order differences of the samples (``estimate_noise``:
  the 5th difference of white noise has variance C(10,5) sigma^2 = 252
  sigma^2, a motion resolved at the frame rate contributes little, and the
  median absolute deviation ignores the few impact frames where it does);
  lambda is then the largest (smoothest) whose residual RMS does not exceed
  sigma (Reinsch's discrepancy principle, RSS = N sigma^2). Any smoother fit
  would depart from the data by more than the noise.

Why it can be trusted (``PositionFit`` and ``finite_difference_comparison``
carry the numbers; the table is for the six published trials):

  trial  sigma  dof/N    lag-1 obs / pure noise  resid. RMS quiet / impacts
         [um]                                    [um]
  1      5.0    182/312  -0.51 / -0.76           3.6 / 8.0
  2      5.0    193/316  -0.61 / -0.78           3.4 / 7.5
  3      6.1    140/257  -0.47 / -0.72           4.7 / 8.9
  4      8.2    185/348  -0.35 / -0.70           5.7 / 12.2
  5      9.1    186/312  -0.43 / -0.77           4.9 / 14.6
  6      4.1    188/355  -0.54 / -0.70           2.7 / 6.9

* residual RMS = sigma by construction, and sigma itself is recovered within
  15 % on synthetic files (tests);
* whiteness: the residual's lag-1 autocorrelation is negative on every
  trial. Pure noise through (I - H) (H the hat matrix) would give the
  "pure noise" column (strongly negative: the fit keeps the low-frequency
  part of the noise, the residual is high-pass). On synthetic data the
  noise-matched fit gives about -0.1..0 and a fit twice as smooth +0.6
  (tests): structure left in the residual drives lag-1 up. The trials sit
  between pure noise and that, because the residual is about twice as large
  within 2 frames of the strongest accelerations (the 10 % largest) as
  elsewhere: impacts last less than a frame (1.04 ms), a spline smooth
  enough for the quiet parts cannot follow them fully. That is a resolution
  limit of the video, not a choice of the fit;
* the file's own columns: the spline velocity differs from the file's
  central differences by 2.7-7.9 mm/s RMS, against 2.8-6.2 mm/s that the
  position noise alone puts into a central difference (sigma/(sqrt 2 dt)):
  noise plus truncation at impacts. The acceleration columns differ by 0.4-2
  g RMS: a central difference of a central difference spreads an impact
  over 4 frames and cuts its peak (-12.7 g in trial 1's file, -18.8 g in
  the spline, which must pass within noise of every position);
* on synthetic files with known, well-resolved motion (tests) the spline's
  velocity and acceleration errors are below 0.7 times those of the central
  differences, and its positions are within the noise of the truth.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.interpolate import BSpline, PPoly
from scipy.linalg import cho_solve_banded, cholesky_banded
from scipy.optimize import brentq

from ...errors import TrialFileError, said
from ...models.surface import PolynomialSurface

__all__ = [
    "TrialFileError",
    "Track",
    "Trial",
    "PositionFit",
    "MARKERS",
    "COLUMNS",
    "DEFAULT_TRIALS_DIR",
    "trials_dir",
    "read_trial",
    "load_trials",
    "estimate_noise",
    "fit_position",
    "fit_platform",
    "finite_difference_comparison",
]

#: Data set location, beside the repository (where CI has it); the
#: environment variable VIBROFEED_TRIALS_DIR overrides it.
DEFAULT_TRIALS_DIR = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "vertical-transport"

MARKERS = {"p": "platform", "o": "part", "s": "marker"}
_QUANTITIES = ("x", "z", "vx", "vz", "ax", "az")
COLUMNS = ("t",) + tuple(q + m for m in MARKERS for q in _QUANTITIES)
_SCALE = 1e-3  # mm, mm/s, mm/s^2 -> m, m/s, m/s^2
MIN_FRAMES = 16
_UNIFORM_RTOL = 1e-3  # the times are printed with 8 decimals: ~1e-5 relative jitter


@dataclass(frozen=True)
class Track:
    """One tracked point: position [m], velocity [m/s], acceleration [m/s^2] (NaN = missing)."""

    x: np.ndarray
    z: np.ndarray
    vx: np.ndarray
    vz: np.ndarray
    ax: np.ndarray
    az: np.ndarray


@dataclass(frozen=True)
class Trial:
    """A measured trial in SI units; ``t`` starts where the file starts."""

    name: str
    path: str
    t: np.ndarray
    platform: Track
    part: Track
    marker: Track

    @property
    def dt(self) -> float:
        return float(np.median(np.diff(self.t)))

    @property
    def n_frames(self) -> int:
        return len(self.t)

    @property
    def number(self) -> int | None:
        """Trial number taken from the name (``trial_5`` -> 5), if there is one."""
        m = re.search(r"(\d+)\s*$", self.name)
        return int(m.group(1)) if m else None


def trials_dir() -> Path | None:
    """Directory of the measured trials, or None when it is not available."""
    from vibrofeed import environment

    given = environment.trials_dir()  # (a folder that does not exist is refused)
    if given is not None:
        return given
    return DEFAULT_TRIALS_DIR if DEFAULT_TRIALS_DIR.is_dir() else None


def _number(field_text: str) -> float:
    """A field as a float; anything that is not a finite number is missing (NaN)."""
    try:
        value = float(field_text)
    except ValueError:
        return math.nan
    return value if math.isfinite(value) else math.nan


def read_trial(path) -> Trial:
    """Read one trial CSV as it is published; raise ``TrialFileError`` if it is not one."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise TrialFileError(path, f"cannot be read ({exc.strerror or exc})") from None
    # Placeholders are not valid numbers in any encoding; decoding with
    # replacement keeps the row structure whatever bytes they are made of.
    text = raw.decode("utf-8", errors="replace").lstrip("\ufeff")
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines:
        raise TrialFileError(path, "is empty")
    header = [h.strip() for h in lines[0].split(",")]
    if all(not math.isnan(_number(h)) for h in header if h):
        raise TrialFileError(path, "has no header row (the first line is numbers)")
    missing = [c for c in COLUMNS if c not in header]
    unknown = [h for h in header if h not in COLUMNS]
    duplicated = sorted({h for h in header if header.count(h) > 1})
    if missing or unknown or duplicated:
        parts = []
        if missing:
            parts.append("missing columns " + ", ".join(missing))
        if unknown:
            parts.append("unknown columns " + ", ".join(repr(u) for u in unknown))
        if duplicated:
            parts.append("duplicated columns " + ", ".join(duplicated))
        raise TrialFileError(path, "is not a trial file: " + "; ".join(parts))
    rows = []
    for lineno, line in enumerate(lines[1:], start=2):
        fields = line.split(",")
        if len(fields) != len(header):
            raise TrialFileError(
                path, f"line {lineno} has {len(fields)} fields, the header has {len(header)}")
        rows.append([_number(f) for f in fields])
    if not rows:
        raise TrialFileError(path, "has a header but no data rows")
    data = np.array(rows, dtype=float)
    col = {name: data[:, k] for k, name in enumerate(header)}
    if np.isnan(data).all():
        raise TrialFileError(path, "contains no numbers")
    n = len(data)
    if n < MIN_FRAMES:
        raise TrialFileError(path, f"has {n} frames, at least {MIN_FRAMES} are needed")
    # The columns the model needs must be complete.
    for name in ("t", "xp", "zp", "xo", "zo"):
        bad = np.flatnonzero(np.isnan(col[name]))
        if bad.size:
            raise TrialFileError(
                path, f"column {name} has {bad.size} missing or non-numeric values "
                      f"(first at data row {bad[0] + 1})")
    t = col["t"]
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise TrialFileError(
            path, f"time is not increasing at data row {k + 2} ({said(t[k])} -> {said(t[k + 1])} s)")
    dt = float(np.median(steps))
    jitter = np.max(np.abs(steps - dt))
    if jitter > _UNIFORM_RTOL * dt:
        k = int(np.argmax(np.abs(steps - dt)))
        raise TrialFileError(
            path, f"time is not uniformly sampled: step {said(steps[k])} s at data row {k + 2} "
                  f"vs median {said(dt)} s")

    def track(m):
        return Track(*(col[q + m] * _SCALE for q in _QUANTITIES))

    return Trial(name=path.stem, path=str(path), t=t.copy(), platform=track("p"),
                 part=track("o"), marker=track("s"))


def load_trials(directory=None, pattern: str = "trial_*.csv") -> list[Trial]:
    """All trials in ``directory`` (default: ``trials_dir()``), ordered by number."""
    directory = trials_dir() if directory is None else Path(directory)
    if directory is None or not Path(directory).is_dir():
        raise FileNotFoundError(
            f"no trial directory (set VIBROFEED_TRIALS_DIR; default {DEFAULT_TRIALS_DIR})")
    trials = [read_trial(p) for p in Path(directory).glob(pattern)]
    return sorted(trials, key=lambda tr: (tr.number is None, tr.number or 0, tr.name))


def estimate_noise(y, order: int = 5) -> float:
    """Robust white-noise sigma of evenly sampled y from its order-th differences.

    Var(diff^k e) = C(2k, k) sigma^2 for white e; a motion sampled finely
    enough adds little to high differences, and the median absolute
    deviation ignores the few frames (impacts) where it does.
    """
    y = np.asarray(y, dtype=float)
    if y.size < order + 3:
        raise ValueError("too few samples to estimate the noise")
    d = np.diff(y, order)
    mad = np.median(np.abs(d - np.median(d)))
    return float(1.482602218505602 * mad / math.sqrt(math.comb(2 * order, order)))


@dataclass
class PositionFit:
    """A penalised quintic spline through sampled positions, with its checks."""

    spline: BSpline
    surface: PolynomialSurface  # position and its exact derivatives
    noise: float  # estimated sigma of the samples [m]
    lam: float  # penalty weight (dimensionless: coefficients' third differences)
    dof: float  # effective degrees of freedom tr(H)
    residual_rms: float  # [m]
    expected_residual_rms: float  # what pure noise would leave: sigma sqrt(tr((I-H)^2)/N)
    lag1: float  # residual lag-1 autocorrelation
    expected_lag1: float  # the same for pure noise through (I - H)
    residuals: np.ndarray = field(repr=False)


def _design(t: np.ndarray, degree: int, order: int):
    knots = np.concatenate((np.repeat(t[0], degree), t, np.repeat(t[-1], degree)))
    B = BSpline.design_matrix(t, knots, degree).toarray()
    D = np.diff(np.eye(B.shape[1]), order, axis=0)
    return knots, B, D.T @ D


def _upper_band(A: np.ndarray, u: int) -> np.ndarray:
    """LAPACK upper banded storage of a symmetric matrix with u super-diagonals."""
    m = A.shape[0]
    ab = np.zeros((u + 1, m))
    for k in range(u + 1):
        ab[u - k, k:] = np.diagonal(A, k)
    return ab


def fit_position(t, y, noise: float | None = None, degree: int = 5,
                 penalty_order: int = 3, criterion: str = "rms") -> PositionFit:
    """Penalised spline of y(t) whose residual matches the noise (see module doc).

    ``noise``: known sigma of y; by default ``estimate_noise(y)``.
    ``criterion``: "rms" (default) takes the smoothest fit whose residual RMS
    does not exceed sigma (Reinsch's discrepancy, RSS = N sigma^2);
    "unbiased" the smoothest whose RSS/(N - dof) does not, which smooths
    less (dof about 1.3x higher on the trials).
    """
    if criterion not in ("rms", "unbiased"):
        raise ValueError(f"unknown criterion {criterion!r}: 'rms' or 'unbiased'")
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    n = len(t)
    if n < degree + penalty_order + 2:
        raise ValueError("too few samples for the spline")
    sigma = estimate_noise(y) if noise is None else float(noise)
    knots, B, P = _design(t, degree, penalty_order)
    BtB, Bty = B.T @ B, B.T @ y
    # Penalty scaled to the data term so lambda is O(1) whatever the units.
    P = P * (np.trace(BtB) / np.trace(P))
    # B^T B + lam P is banded (half-bandwidth max(degree, order)): banded
    # Cholesky solves cost O(N) each and need no multi-threaded BLAS.
    u = max(degree, penalty_order)
    band_btb, band_p = _upper_band(BtB, u), _upper_band(P, u)

    def factor(log_lam):
        return cholesky_banded(band_btb + 10.0 ** log_lam * band_p)

    def solve(log_lam):
        coef = cho_solve_banded((factor(log_lam), False), Bty)
        return coef, y - B @ coef

    def dof(log_lam):  # tr(H) = tr((B^T B + lam P)^-1 B^T B)
        return float(np.trace(cho_solve_banded((factor(log_lam), False), BtB)))

    def mismatch(log_lam):
        # log of (residual variance) / sigma^2
        _, res = solve(log_lam)
        denom = n if criterion == "rms" else max(n - dof(log_lam), 1e-9)
        return math.log(float(res @ res) / denom + 1e-300) - 2 * math.log(sigma)

    # The smoothest fit whose residual variance does not exceed the noise:
    # scan down from heavy smoothing to the first grid value at or below the
    # noise, then refine between it and its smoother neighbour.
    grid = np.arange(6.0, -8.5, -0.5)
    log_lam = grid[-1]  # nothing at/below the noise: the least smoothing tried
    if sigma > 0:
        prev = None
        for g in grid:
            if mismatch(g) <= 0:
                log_lam = g if prev is None else brentq(mismatch, g, prev, xtol=1e-4)
                break
            prev = g
    coef, res = solve(log_lam)
    # What pure white noise e would leave: r = (I - H) e, H = B A^-1 B^T.
    H = B @ cho_solve_banded((factor(log_lam), False), B.T)
    R = np.eye(n) - H
    C = R @ R.T
    expected_lag1 = float(np.sum(np.diag(C, 1)) / np.trace(C))
    tr_res = float(np.trace(C))
    rc = res - res.mean()
    lag1 = float(np.sum(rc[1:] * rc[:-1]) / np.sum(rc * rc)) if np.any(rc) else 0.0
    spline = BSpline(knots, coef, degree, extrapolate=False)
    return PositionFit(
        spline=spline,
        surface=PolynomialSurface(PPoly.from_spline(spline)),
        noise=sigma,
        lam=10.0 ** log_lam,
        dof=float(np.trace(H)),
        residual_rms=float(np.sqrt(np.mean(res ** 2))),
        expected_residual_rms=sigma * math.sqrt(max(tr_res, 0.0) / n),
        lag1=lag1,
        expected_lag1=expected_lag1,
        residuals=res,
    )


def fit_platform(trial: Trial, noise: float | None = None, criterion: str = "rms") -> PositionFit:
    """Interpolant of the platform's vertical position (z_s and exact derivatives)."""
    return fit_position(trial.t, trial.platform.z, noise=noise, criterion=criterion)


def finite_difference_comparison(trial: Trial, fit: PositionFit) -> dict:
    """RMS differences between the spline derivatives and the file's own columns.

    Also returns the part of each that pure position noise would cause in a
    central difference (sigma/(sqrt 2 dt) for velocity, sqrt(6) sigma/(4 dt^2)
    for the central difference of a central difference).
    """
    t, dt = trial.t, trial.dt
    v = fit.spline.derivative(1)(t)
    a = fit.spline.derivative(2)(t)
    dv = trial.platform.vz - v
    da = trial.platform.az - a
    return {
        "velocity_rms_diff": float(np.sqrt(np.nanmean(dv ** 2))),
        "velocity_fd_noise": fit.noise / (math.sqrt(2.0) * dt),
        "acceleration_rms_diff": float(np.sqrt(np.nanmean(da ** 2))),
        "acceleration_fd_noise": math.sqrt(6.0) * fit.noise / (4.0 * dt * dt),
        "spline_min_acceleration": float(np.nanmin(a)),
        "file_min_acceleration": float(np.nanmin(trial.platform.az)),
    }

