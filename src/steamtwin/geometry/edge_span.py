"""A thin blade edge as one smooth model along the span, fitted to all its points at once.

The edge of each section is a circle tangent to both flank lines (Dixon & Hall, "Fluid
Mechanics and Thermodynamics of Turbomachinery", 7th ed. 2014, §3.3; Pritchard 1985, ASME
85-GT-219; the section geometry is :mod:`~steamtwin.geometry.edge_circle`). Along the span the
edge changes slowly, so its five section parameters are smooth functions of the span
coordinate z: the circle's centre cₓ(z), c_y(z), its radius r(z) and the angles θ₀(z), θ₁(z)
of the two lines' inward unit normals nᵢ = (cos θᵢ, sin θᵢ). The tangency is built into the
parametrisation: line i is nᵢ·p = nᵢ·c − r, so the circle touches both lines at every z.

Each function is a cubic B-spline in z on uniform knots every :data:`KNOT_SPACING` (Dierckx,
"Curve and Surface Fitting with Splines", 1993, ch. 1 and 5: B-splines and smoothing with a
roughness penalty) with the second-difference penalty of P-splines on its coefficients
(Eilers & Marx 1996, "Flexible smoothing with B-splines and penalties", Stat. Sci. 11:89): a
stretch of span without points — a scan hole, stray points — is filled by the penalty, a
straight continuation of its neighbours, with no separate bridging. All coefficients are
fitted together to every point of the edge and its flanks by robust nonlinear least squares
(Levenberg–Marquardt on the banded, reweighted normal equations, :func:`_robust_lm`; soft-L1
loss of scale :data:`~steamtwin.geometry.edge_circle.SOFT_SCALE`, Triggs et al. 2000 §6.8) on the
geometric distance of :func:`~steamtwin.geometry.edge_circle.edge_distance_at`, with its
analytic Jacobian; points beyond three robust standard deviations (at least
:data:`~steamtwin.geometry.edge_circle.TRIM_FLOOR`) are then left out and the fit repeated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.interpolate import BSpline
from scipy.linalg import LinAlgError, solveh_banded

from steamtwin.geometry.edge_circle import (
    SOFT_SCALE,
    TRIM_FLOOR,
    edge_distance_at,
    tip_and_half_angle,
)

#: Knot spacing (m) of the span model's cubic B-splines: four knot spans per 10 mm of span.
KNOT_SPACING = 2.5e-3
#: Scale of the roughness penalty: the second difference of neighbouring coefficients that
#: costs as much as one point a soft-L1 scale off — (m) for the centre and the radius, (rad)
#: for the angles. A 20° twist over 60 mm about a centre 20 mm from the edge bends the
#: centre's path by ~4 µm per knot span squared: the penalty hardly biases it.
PENALTY_SCALE = np.array([5e-6, 5e-6, 5e-6, 5e-3, 5e-3])
#: Weight λ of the second-difference penalty of the start (:func:`initial_coefficients`),
#: in units of one slab's circle (each row of the B-spline basis sums to one). Beyond the
#: last slab with a circle of its own — next to a cap, where the flanks are cut short — a
#: P-spline continues the straight line of its last values (Eilers & Marx 1996 §3; Dierckx
#: 1993 §5.2 on the end behaviour of smoothing splines): with the former λ = 1e-3 it
#: interpolated the slabs, so the scatter of the last two (σ ≈ 0.05 mm along the bisector,
#: each from ~100 points) was extrapolated by their slope — median 0.31 mm, up to 0.79 mm at
#: the cap over 20 synthetic draws (tests/geometry/test_edge_span_start.py); λ ≥ 3 smooths
#: over ~2 knot spans and keeps the start within 2.6 σ (0.13 mm), λ = 10 on that plateau.
#: The robust fit does not undo a poor start at the ends within its evaluations: measured on
#: high-camber-turbine 40k seed 1 (blade frame, 2026-11-27), a start 0.36–0.42 mm short of
#: the trailing edge's tip over the last 2.5 mm gave a fit still 0.28–0.31 mm short (its
#: three least-squares rounds each stopped at max_nfev, and the trimming then dropped
#: 19–26 of ~115 good points per end slab); from the λ = 10 start it converges to within
#: 0.011 mm of the exact tip at every z, at 0.8 s instead of 1.9 s CPU.
START_PENALTY = 10.0
#: Trimming rounds after the first fit.
TRIM_ROUNDS = 2
DEGREE = 3


@dataclass(frozen=True)
class SpanEdgeModel:
    """An edge along the span: cubic B-splines (``knots``, ``coefficients`` (K, 5): centre x,
    centre y, radius (m), angles of the two lines' inward normals (rad)) valid over
    ``z_range`` (m)."""

    knots: np.ndarray
    coefficients: np.ndarray
    z_range: tuple[float, float]

    def at(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Centre (n, 2; m), radius (n,; m) and inward unit normals (n, 2, 2) at heights
        ``z`` (n,; m), clipped to ``z_range``."""
        values = BSpline(self.knots, self.coefficients, DEGREE, extrapolate=False)(
            _inside(self.knots, z))
        angles = values[:, 3:5]
        normals = np.stack([np.cos(angles), np.sin(angles)], axis=2)
        return values[:, :2], values[:, 2], normals

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m, positive outside) of ``points`` (n, 3; m) from the model."""
        return edge_distance_at(points[:, :2], *self.at(points[:, 2]))[0]


def span_knots(z_range: tuple[float, float], knot_spacing: float = KNOT_SPACING) -> np.ndarray:
    """Uniform cubic knot vector over ``z_range`` (m), knots at most ``knot_spacing`` (m)
    apart and three more beyond either end: the equally spaced knots of P-splines, whose
    second-difference penalty is zero for a straight line (clamped end knots would
    penalise the slope of a leaning or twisting edge at both ends; Eilers & Marx 1996 §3)."""
    spans = max(1, math.ceil((z_range[1] - z_range[0]) / knot_spacing))
    step = (z_range[1] - z_range[0]) / spans
    return z_range[0] + step * np.arange(-DEGREE, spans + DEGREE + 1)


def _inside(knots: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Heights ``z`` (m) clipped to the base interval of the cubic ``knots``."""
    return np.clip(z, knots[DEGREE], knots[-DEGREE - 1])


def _second_difference(count: int) -> np.ndarray:
    """The (count − 2, count) second-difference matrix of P-splines."""
    return np.diff(np.eye(count), n=2, axis=0)


def initial_coefficients(knots: np.ndarray, z: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Coefficients (K, 5) of penalised least-squares splines (P-splines, weight
    :data:`START_PENALTY`) smoothing the per-slab ``values`` (m, 5) at heights ``z`` (m,):
    the start of the robust fit."""
    basis = BSpline.design_matrix(_inside(knots, z), knots, DEGREE).toarray()
    count = basis.shape[1]
    difference = _second_difference(count)
    system = basis.T @ basis + START_PENALTY * difference.T @ difference + 1e-9 * np.eye(count)
    return np.linalg.solve(system, basis.T @ values)


def _penalty(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Penalty residuals z whose soft-L1 cost 2(√(1 + z²) − 1) is q² exactly — the roughness
    penalty stays quadratic under the robust loss —, and dz/dq: z = q·√(1 + q²/4)."""
    root = np.sqrt(1.0 + 0.25 * q * q)
    return q * root, root + 0.25 * q * q / root


#: Largest number of residual evaluations of one robust fit (:func:`_robust_lm`).
MAX_EVALUATIONS = 60
#: Relative decrease of the cost, and step relative to the coefficients (both in units of
#: ``x_scale``), below which :func:`_robust_lm` stops: scipy ``least_squares``' defaults.
TOLERANCE = 1e-8


def _interleaved(count: int) -> np.ndarray:
    """The coefficients (field-major, 5 × ``count``) ordered by knot, then field: the span
    model's normal equations are then banded, each coefficient meeting those of the
    ``DEGREE`` knots either side (B-spline support; the penalty's second differences reach
    two)."""
    return np.arange(5 * count).reshape(5, count).T.ravel()


def _robust_lm(function, jacobian, x: np.ndarray, bounds: tuple[np.ndarray, np.ndarray],
               x_scale: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Minimise the soft-L1 cost Σ 2(√(1 + fᵢ²) − 1) of the residuals f = ``function(x)``
    (sparse Jacobian ``jacobian(x)``) from ``x`` within ``bounds``: Levenberg–Marquardt
    (Moré 1978, "The Levenberg–Marquardt algorithm: implementation and theory", LNM 630) on
    the iteratively reweighted normal equations (weights 1/√(1 + fᵢ²), the soft-L1 loss's
    ρ'; Holland & Welsch 1977, Commun. Stat. 6:813), damping μ in units of ``x_scale``,
    coefficients at a bound held there while the step would leave it. The normal equations
    are banded in the ``order`` of :func:`_interleaved` and solved by banded Cholesky in
    O(K·b²): scipy ``least_squares``' trust-region steps by LSMR iterations, which this
    replaces, took 22 s of slender 80k's 39-s reconstruction (2026-11-28), most fits
    stopping at their evaluation limit."""
    lower, upper = bounds
    band = 5 * DEGREE + 4
    inverse = np.argsort(order)

    def cost(f: np.ndarray) -> float:
        return float(np.sum(2.0 * (np.sqrt(1.0 + f * f) - 1.0)))

    f, jac = function(x), jacobian(x)
    current = cost(f)
    mu = math.nan
    evaluations = 1
    while evaluations < MAX_EVALUATIONS:
        weight = 1.0 / np.sqrt(1.0 + f * f)
        scaled = jac @ sparse.diags(x_scale)
        normal = (scaled.T @ (sparse.diags(weight) @ scaled)).toarray()[np.ix_(order, order)]
        step_rhs = -(scaled.T @ (weight * f))[order]
        held = (((x <= lower) & (step_rhs[inverse] < 0.0))
                | ((x >= upper) & (step_rhs[inverse] > 0.0)))[order]
        normal[held, :], normal[:, held], step_rhs[held] = 0.0, 0.0, 0.0
        diagonal = np.diag(normal).copy()
        if math.isnan(mu):  # τ = 1e-3 of the largest diagonal term (Madsen, Nielsen &
            # Tingleff 2004, "Methods for non-linear least squares problems", §3.2)
            mu = 1e-3 * float(diagonal.max())
        ab = np.zeros((band + 1, len(x)))
        for k in range(band + 1):
            ab[band - k, k:] = np.diagonal(normal, k)
        accepted = False
        while evaluations < MAX_EVALUATIONS and not accepted:
            ab[band] = diagonal + mu + held
            try:
                step = solveh_banded(ab, step_rhs, check_finite=False)[inverse] * x_scale
            except LinAlgError:  # not positive definite in floating point: damp more
                mu *= 4.0
                evaluations += 1
                continue
            trial = np.clip(x + step, lower, upper)
            f_trial = function(trial)
            evaluations += 1
            trial_cost = cost(f_trial)
            if trial_cost < current:
                accepted = True
                moved = float(np.max(np.abs(trial - x) / x_scale))
                if (current - trial_cost <= TOLERANCE * trial_cost
                        or moved <= TOLERANCE * (TOLERANCE + np.abs(trial / x_scale).max())):
                    return trial
                x, f, jac, current = trial, f_trial, jacobian(trial), trial_cost
                mu /= 3.0
            else:
                mu *= 4.0
    return x


def fit_span_edge(points: np.ndarray, start: SpanEdgeModel,
                  radius_bounds: tuple[float, float]) -> tuple[SpanEdgeModel, np.ndarray]:
    """Fit the span model to ``points`` (n, 3; m) of the edge and its flanks, from ``start``
    (knots and first coefficients, e.g. :func:`initial_coefficients`), radius within
    ``radius_bounds`` (m). Returns the model and the mask of the points kept."""
    knots, z_range = start.knots, start.z_range
    basis = BSpline.design_matrix(_inside(knots, points[:, 2]), knots, DEGREE).tocsr()
    count = basis.shape[1]
    difference = _second_difference(count)
    scale = np.repeat(PENALTY_SCALE, count - 2)  # per penalty row
    x = start.coefficients.T.ravel().copy()
    lower = np.full(x.size, -np.inf)
    upper = np.full(x.size, np.inf)
    lower[2 * count: 3 * count], upper[2 * count: 3 * count] = radius_bounds
    x[2 * count: 3 * count] = np.clip(x[2 * count: 3 * count], radius_bounds[0] * 1.001,
                                      radius_bounds[1] * 0.999)
    x_scale = np.repeat([1e-5, 1e-5, 1e-5, 1e-2, 1e-2], count)
    keep = np.ones(len(points), dtype=bool)

    def evaluate(x: np.ndarray, use: np.ndarray) -> tuple:
        values = basis[use] @ x.reshape(5, count).T
        normals = np.stack([np.cos(values[:, 3:5]), np.sin(values[:, 3:5])], axis=2)
        return values, normals

    def residual(x: np.ndarray, use: np.ndarray) -> np.ndarray:
        values, normals = evaluate(x, use)
        d = edge_distance_at(points[use, :2], values[:, :2], values[:, 2], normals)[0]
        q = (difference @ x.reshape(5, count).T).T.ravel() / scale
        return np.concatenate([d / SOFT_SCALE, _penalty(q)[0]])

    def jacobian(x: np.ndarray, use: np.ndarray) -> np.ndarray:
        values, normals = evaluate(x, use)
        xy, centre, radius = points[use, :2], values[:, :2], values[:, 2]
        _, _, which = edge_distance_at(xy, centre, radius, normals)
        gradient = np.zeros((len(xy), 5))
        gradient[:, 2] = -1.0
        on_arc = which < 0
        offset = xy[on_arc] - centre[on_arc]
        gradient[on_arc, :2] = -offset / np.linalg.norm(offset, axis=1)[:, None]
        for i in range(2):  # d = nᵢ·(c − p) − r: ∂/∂c = nᵢ, ∂/∂θᵢ = nᵢ'·(c − p)
            on = which == i
            n = normals[on, i]
            gradient[on, :2] = n
            gradient[on, 3 + i] = np.einsum("ij,ij->i", np.column_stack([-n[:, 1], n[:, 0]]),
                                            centre[on] - xy[on])
        local = basis[use]
        data = sparse.hstack([sparse.diags(gradient[:, f] / SOFT_SCALE) @ local
                              for f in range(5)])
        q = (difference @ x.reshape(5, count).T).T.ravel() / scale
        rows = sparse.diags(_penalty(q)[1] / scale) @ sparse.block_diag([difference] * 5)
        return sparse.vstack([data, rows]).tocsr()

    for _ in range(TRIM_ROUNDS + 1):
        x = _robust_lm(lambda x, use=keep: residual(x, use),
                       lambda x, use=keep: jacobian(x, use), x, (lower, upper), x_scale,
                       _interleaved(count))
        values, normals = evaluate(x, np.ones(len(points), dtype=bool))
        d = edge_distance_at(points[:, :2], values[:, :2], values[:, 2], normals)[0]
        spread = 1.4826 * float(np.median(np.abs(d[keep])))
        new = np.abs(d) <= max(3.0 * spread, TRIM_FLOOR)
        if np.array_equal(new, keep):
            break
        keep = new
    return SpanEdgeModel(knots, x.reshape(5, count).T.copy(), z_range), keep


def sample_span_edge(model: SpanEdgeModel, z: np.ndarray, u_fraction: np.ndarray,
                     cut: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Model points (R·U, 3; m) in rings at heights ``z`` (R,; m), at arc lengths u =
    ``u_fraction`` (U,; in [−1, 1]) × ``cut`` (R,; m) from the tip (negative towards line 0):
    on the arc between the tangent points, then along the lines. Returns the points and
    their u (m)."""
    centre, radius, normals = model.at(z)
    tip, half = tip_and_half_angle(normals)
    perp = np.column_stack([-tip[:, 1], tip[:, 0]])
    sign = np.where(-np.einsum("ij,ij->i", normals[:, 0], perp) > 0, 1.0, -1.0)
    u = u_fraction[None, :] * cut[:, None]  # (R, U)
    angle = np.clip(u / radius[:, None], -half[:, None], half[:, None])
    direction = (np.cos(angle)[:, :, None] * tip[:, None, :]
                 - (sign[:, None] * np.sin(angle))[:, :, None] * perp[:, None, :])
    beyond = np.maximum(np.abs(u) - (radius * half)[:, None], 0.0)
    away = np.stack([normals[:, :, 1], -normals[:, :, 0]], axis=2)  # (R, line, 2)
    away = np.where((np.einsum("rli,ri->rl", away, tip) > 0)[:, :, None], -away, away)
    line_away = np.where((u < 0.0)[:, :, None], away[:, None, 0, :], away[:, None, 1, :])
    xy = (centre[:, None, :] + radius[:, None, None] * direction
          + beyond[:, :, None] * line_away)
    xyz = np.concatenate([xy, np.broadcast_to(z[:, None, None], (len(z), len(u_fraction), 1))],
                         axis=2)
    return xyz.reshape(-1, 3), u.ravel()
