"""Least-squares tensor-product B-spline surfaces, periodic around the profile.

The side of a blade is one surface ``(x, y)(s, z)``: ``s`` ∈ [0, 1) runs once round the section
(periodic), ``z`` is the radius (sections are planes z = const, so the third coordinate is the
parameter itself). Both directions are cubic. The basis comes from scipy's B-splines (de Boor's
recurrence, as in Dierckx 1993, "Curve and surface fitting with splines", whose FITPACK scipy
wraps): ``BSpline.design_matrix`` for the least-squares system and ``NdBSpline`` for evaluation;
periodicity wraps the basis functions that leave [0, 1) round to its start (Piegl & Tiller, The
NURBS Book, 2nd ed. 1997, §12.4 on closed and periodic curves).

Fitting (Piegl & Tiller §9.4: least-squares approximation, refined by knot insertion until an
error bound is met): the coefficients solve the normal equations, with a small second-difference
penalty (Eilers & Marx 1996, P-splines) that keeps spans without data determined and damps
wiggles at the knot scale; points farther than 5 robust standard deviations and
``outlier_distance`` are trimmed (while the knots are refined, per knot span: 5 robust standard
deviations of the span's own residuals, between ``outlier_distance`` and 10 × that; then a
last fit at the final knots); every point's ``s`` is then corrected by a Newton projection onto
its section curve (Hoschek 1988, "Intrinsic parametrization for approximation", CAGD 5:27) and
the fit repeated. Knots are then inserted in the middle of every knot span whose residual RMS
exceeds the tolerance and the noise (1.5 × the median span RMS) and that holds enough points
for two spans, until no span does — so the RMS is below the tolerance too, unless the noise is
larger —, a round gains less than 3 % or the knot budget is spent. A round whose surface folds
(a section crossing itself, :meth:`PeriodicSurface.folds`, in the part of the span that is
used) is refitted with a 10 and 100 times
stronger penalty, else the refinement stops at the previous knots. Residuals are distances
within the section plane z = const (m).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.interpolate import BSpline, NdBSpline
from scipy.sparse import csr_array, diags_array, eye_array, kron
from scipy.sparse.linalg import spsolve
from scipy.spatial import cKDTree

DEGREE = 3
#: Relative weight of the second-difference penalty (against the mean diagonal of AᵀA).
PENALTY = 1e-3
#: Points with residuals beyond this many robust standard deviations are trimmed.
TRIM = 5.0
#: A knot span is refined only when its residual RMS exceeds this multiple of the median span's.
NOISE_FACTOR = 1.5
#: Refinement stops when a round lowers the RMS residual by less than this share.
MIN_GAIN = 0.03


def periodic_knots(breaks: np.ndarray) -> np.ndarray:
    """Knot vector of the periodic cubic spline with breakpoints ``breaks`` in [0, 1)."""
    k = DEGREE
    return np.concatenate([breaks[-k:] - 1.0, breaks, 1.0 + breaks[: k + 1]])


def clamped_knots(lo: float, hi: float, interior: int) -> np.ndarray:
    """Clamped cubic knot vector on [lo, hi] with ``interior`` equally spaced interior knots."""
    inner = np.linspace(lo, hi, interior + 2)
    return np.concatenate([[lo] * DEGREE, inner, [hi] * DEGREE])


def _basis(x: np.ndarray, knots: np.ndarray, period: int | None = None
           ) -> tuple[np.ndarray, np.ndarray]:
    """Columns and values (n, k + 1) of the non-zero basis functions at ``x``; with ``period``
    the columns wrap modulo it."""
    matrix = BSpline.design_matrix(x, knots, DEGREE)
    columns = matrix.indices.reshape(len(x), DEGREE + 1)
    values = matrix.data.reshape(len(x), DEGREE + 1)
    return (columns if period is None else columns % period), values


@dataclass(frozen=True)
class PeriodicSurface:
    """``(x, y)(s, z)`` (m): cubic, periodic in ``s`` ∈ [0, 1), clamped in ``z`` (m).

    ``breaks`` (m,) breakpoints in [0, 1) starting at 0; ``z_knots`` clamped knot vector;
    ``coefficients`` (m, nz, 2).
    """

    breaks: np.ndarray
    z_knots: np.ndarray
    coefficients: np.ndarray

    @cached_property
    def _spline(self) -> object:
        wrapped = np.concatenate([self.coefficients, self.coefficients[:DEGREE]], axis=0)
        return NdBSpline((periodic_knots(self.breaks), self.z_knots), wrapped, DEGREE)

    def __call__(self, s: np.ndarray, z: np.ndarray, ds: int = 0) -> np.ndarray:
        """Points (n, 2) of the surface, or their ``ds``-th derivative in ``s``."""
        s = np.mod(np.asarray(s, dtype=float), 1.0)
        z = np.broadcast_to(np.asarray(z, dtype=float), s.shape)
        return self._spline(np.column_stack([s, z]), nu=(ds, 0))

    def outward_normals(self, s: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Unit normals (n, 2) in the section plane, outward for an anticlockwise ``s``."""
        tangent = self(s, z, ds=1)
        normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
        return normal / np.linalg.norm(normal, axis=1, keepdims=True)

    def project(self, xy: np.ndarray, z: np.ndarray, s: np.ndarray,
                iterations: int = 8) -> np.ndarray:
        """Parameters ``s`` of the points of the section curves at ``z`` nearest to ``xy``,
        by Newton's method on (C(s) − p)·C'(s) = 0 from the start values ``s``; each step is
        limited to the local knot spacing. A point stops once its step is below 1e-10 (Newton
        converges quadratically: most points stop after two or three steps, and only those
        still moving are evaluated again)."""
        s = np.asarray(s, dtype=float).copy()
        z = np.broadcast_to(np.asarray(z, dtype=float), s.shape)
        spacing = np.diff(np.append(self.breaks, 1.0 + self.breaks[0]))
        active = np.arange(len(s))
        for _ in range(iterations):
            at, height = s[active], z[active]
            offset = self(at, height) - xy[active]
            first = self(at, height, ds=1)
            second = self(at, height, ds=2)
            gradient = np.einsum("ij,ij->i", offset, first)
            hessian = np.einsum("ij,ij->i", first, first) + np.einsum("ij,ij->i", offset, second)
            step = np.where(hessian > 0.0, -gradient / np.where(hessian > 0.0, hessian, 1.0),
                            -np.sign(gradient) * 1e-4)
            span = np.clip(np.searchsorted(self.breaks, np.mod(at, 1.0), side="right") - 1, 0,
                           len(self.breaks) - 1)
            limit = spacing[span]
            s[active] = np.mod(at + np.clip(step, -limit, limit), 1.0)
            active = active[np.abs(step) >= 1e-10]
            if active.size == 0:
                break
        return s

    def folds(self, levels: int = 9, samples: int = 4000,
              z_range: tuple[float, float] | None = None) -> bool:
        """Whether a section curve at one of ``levels`` heights spread over ``z_range`` (m; the
        z knots when None; both ends included) crosses itself: a loop or swallowtail, as left
        by spans that too few points pin down. Each curve is a polyline of ``samples`` points."""
        s = np.linspace(0.0, 1.0, samples, endpoint=False)
        low, high = z_range if z_range is not None else (self.z_knots[0], self.z_knots[-1])
        for z in np.linspace(low, high, levels):
            start = self(s, np.full(samples, z))
            step = np.roll(start, -1, axis=0) - start
            length = np.linalg.norm(step, axis=1)
            # segments that cross have midpoints closer than the longest segment
            pairs = cKDTree(start + 0.5 * step).query_pairs(float(length.max()),
                                                            output_type="ndarray")
            i, j = pairs[:, 0], pairs[:, 1]
            apart = np.abs(np.mod(j - i + samples // 2, samples) - samples // 2) > 1
            i, j = i[apart], j[apart]
            cross = step[i, 0] * step[j, 1] - step[i, 1] * step[j, 0]
            w = start[j] - start[i]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (w[:, 0] * step[j, 1] - w[:, 1] * step[j, 0]) / cross
                u = (w[:, 0] * step[i, 1] - w[:, 1] * step[i, 0]) / cross
            if np.any((cross != 0.0) & (t > 0.0) & (t < 1.0) & (u > 0.0) & (u < 1.0)):
                return True
        return False

    def residuals(self, xy: np.ndarray, z: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Signed distances (m) of ``xy`` from the surface points at ``(s, z)``, positive
        outside (along the outward normal)."""
        return np.einsum("ij,ij->i", xy - self(s, z), self.outward_normals(s, z))


def fit_periodic_surface(s: np.ndarray, z: np.ndarray, xy: np.ndarray, breaks: np.ndarray,
                         z_knots: np.ndarray, weights: np.ndarray | None = None,
                         smoothing: float = PENALTY) -> PeriodicSurface:
    """Least-squares tensor-product fit of ``xy`` (n, 2) at parameters ``(s, z)``.

    Solves (AᵀWA + λP) c = AᵀW xy with A the tensor-product design matrix (rows are Kronecker
    products of the s and z bases) and P a second-difference penalty in both directions scaled
    by ``smoothing`` (relative to the mean diagonal of AᵀWA; default :data:`PENALTY`).
    """
    m, nz = len(breaks), len(z_knots) - DEGREE - 1
    cols_s, vals_s = _basis(np.mod(s, 1.0), periodic_knots(breaks), period=m)
    cols_z, vals_z = _basis(np.asarray(z, dtype=float), z_knots)
    # tensor-product rows: the (k+1)² products of the non-zero s and z basis functions
    cols = (cols_s[:, :, None] * nz + cols_z[:, None, :]).reshape(len(s), -1)
    vals = (vals_s[:, :, None] * vals_z[:, None, :]).reshape(len(s), -1)
    rows = np.repeat(np.arange(len(s)), cols.shape[1])
    design = csr_array((vals.ravel(), (rows, cols.ravel())), shape=(len(s), m * nz))
    w = np.ones(len(s)) if weights is None else np.asarray(weights, dtype=float)
    weighted = diags_array(w) @ design
    normal = (design.T @ weighted).tocsc()
    second_s = _periodic_second_difference(m)
    second_z = _second_difference(nz)
    penalty = (kron(second_s.T @ second_s, eye_array(nz))
               + kron(eye_array(m), second_z.T @ second_z))
    scale = smoothing * float(normal.diagonal().mean())
    rhs = design.T @ (w[:, None] * xy)
    solution = spsolve((normal + scale * penalty).tocsc(), rhs)
    return PeriodicSurface(breaks=np.asarray(breaks, dtype=float).copy(),
                           z_knots=np.asarray(z_knots, dtype=float).copy(),
                           coefficients=np.asarray(solution).reshape(m, nz, 2))


def _periodic_second_difference(m: int) -> object:
    i = np.arange(m)
    rows = np.concatenate([i, i, i])
    cols = np.concatenate([(i - 1) % m, i, (i + 1) % m])
    vals = np.concatenate([np.ones(m), -2.0 * np.ones(m), np.ones(m)])
    return csr_array((vals, (rows, cols)), shape=(m, m))


def _second_difference(n: int) -> object:
    if n < 3:
        return csr_array((1, n))
    i = np.arange(n - 2)
    rows = np.concatenate([i, i, i])
    cols = np.concatenate([i, i + 1, i + 2])
    vals = np.concatenate([np.ones(n - 2), -2.0 * np.ones(n - 2), np.ones(n - 2)])
    return csr_array((vals, (rows, cols)), shape=(n - 2, n))


@dataclass
class AdaptiveSurfaceFit:
    """Adaptive least-squares fit of a :class:`PeriodicSurface` (scikit-learn style).

    ``tolerance`` is the RMS residual aimed at (m); ``max_breaks`` bounds the breakpoints round
    the profile; points farther than ``outlier_distance`` (m) and 5 robust standard deviations
    from the surface are trimmed; ``corrections`` is the number of fit/projection rounds per
    knot vector; ``max_rounds`` bounds the refinement rounds; a span is split only when it
    holds twice ``min_span_points`` and twice 2 × the z basis functions; ``penalty_factor``
    multiplies the penalty throughout (a repair refit, :mod:`~steamtwin.geometry.fit_guard`);
    ``fold_range`` (m) is the part of the span where folds are judged (the part of the surface
    that is used; the whole z knot vector when None). After :meth:`fit`:
    ``surface_``, ``parameters_`` (corrected s), ``residuals_`` (signed, m), ``inliers_`` (mask
    of the points kept by trimming) and ``history_`` (breakpoints, RMS, ``folded`` and the
    penalty factor ``smoothing`` of every round).
    """

    tolerance: float = 0.02e-3
    max_breaks: int = 2000
    outlier_distance: float = 0.1e-3
    corrections: int = 3
    max_rounds: int = 8
    min_span_points: int = 8
    history_: list[dict] = field(default_factory=list, init=False, repr=False)
    _split_points: int = field(default=16, init=False, repr=False)
    penalty_factor: float = 1.0
    fold_range: tuple[float, float] | None = None

    def fit(self, s: np.ndarray, z: np.ndarray, xy: np.ndarray, breaks: np.ndarray,
            z_knots: np.ndarray) -> AdaptiveSurfaceFit:
        """Fit the points ``xy`` (n, 2; m) at start parameters ``s`` ∈ [0, 1) and ``z`` (m),
        refining the start breakpoints ``breaks`` (sorted, in [0, 1), first 0); ``z_knots`` is
        a clamped cubic knot vector covering ``z``. Returns ``self``."""
        s = np.mod(np.asarray(s, dtype=float), 1.0)
        z = np.asarray(z, dtype=float)
        xy = np.asarray(xy, dtype=float)
        breaks = np.asarray(breaks, dtype=float)
        unknowns = len(breaks) * (len(z_knots) - DEGREE - 1)
        if xy.shape != (len(s), 2) or z.shape != s.shape:
            raise ValueError(f"expected s (n,), z (n,) and xy (n, 2); got {s.shape}, {z.shape} "
                             f"and {xy.shape}")
        increasing = bool(np.all(np.diff(breaks) > 0.0))
        if len(breaks) < DEGREE + 1 or breaks[0] != 0.0 or not increasing or breaks[-1] >= 1.0:
            raise ValueError("breaks must be at least 4 increasing values in [0, 1) from 0")
        if len(s) < 2 * unknowns:
            raise ValueError(f"{len(s)} points are too few for {unknowns} coefficients")
        if z.min() < z_knots[0] or z.max() > z_knots[-1]:
            raise ValueError("z lies outside the z knot vector")
        self.history_ = []
        # a span is split only when both halves keep, on average, enough points to pin down
        # their coefficients: at least twice the z basis functions (each s span adds a column
        # of them); on a sparse cloud thinner spans are held by a few points and fold
        self._split_points = 2 * max(self.min_span_points, 2 * (len(z_knots) - DEGREE - 1))
        candidates = []
        # while the knots are refined only gross outliers (10 × outlier_distance) are left out:
        # a point far from an early, still coarse surface is often just badly parametrised
        for _ in range(self.max_rounds):
            # a knot vector whose surface folds is retried with a 10 and 100 times stronger
            # penalty before the refinement stops at the coarser knots
            for smoothing in (1.0, 10.0, 100.0):
                surface, s_new, residual, inliers = self._fit_knots(
                    s, z, xy, breaks, z_knots, 10.0 * self.outlier_distance, smoothing)
                rms = self._record(breaks, z_knots, residual, inliers)
                folded = surface.folds(z_range=self.fold_range)
                self.history_[-1].update(folded=folded, smoothing=smoothing)
                if not folded:
                    break
            if folded and candidates:
                break  # refinement went too far for the data: keep the coarser knots
            s = s_new
            candidates.append((rms, len(candidates), breaks, s.copy(), smoothing))
            # the gain is measured against the previous round's kept fit, not against a folded
            # attempt of this round (a stronger penalty always costs some RMS)
            if len(candidates) > 1 and rms > (1.0 - MIN_GAIN) * candidates[-2][0]:
                break
            refined = self._refine(breaks, s, residual, inliers)
            if refined is None:
                break
            breaks = refined
        # the best round first; should its final fit (tighter trimming) fold, the coarser ones
        for _, _, breaks, s, smoothing in sorted(candidates, key=lambda c: (c[0], c[1])):
            self.surface_, self.parameters_, self.residuals_, self.inliers_ = self._fit_knots(
                s, z, xy, breaks, z_knots, self.outlier_distance, smoothing)
            self._record(breaks, z_knots, self.residuals_, self.inliers_)
            self.history_[-1].update(folded=self.surface_.folds(z_range=self.fold_range),
                                     smoothing=smoothing)
            if not self.history_[-1]["folded"]:
                break
        return self

    def _record(self, breaks: np.ndarray, z_knots: np.ndarray, residual: np.ndarray,
                inliers: np.ndarray) -> float:
        rms = float(np.sqrt(np.mean(residual[inliers] ** 2)))
        self.history_.append({"breaks": len(breaks), "z_knots": len(z_knots), "rms": rms,
                              "max": float(np.abs(residual[inliers]).max()),
                              "trimmed": int(np.sum(~inliers))})
        return rms

    def _fit_knots(self, s: np.ndarray, z: np.ndarray, xy: np.ndarray, breaks: np.ndarray,
                   z_knots: np.ndarray, distance: float, smoothing: float = 1.0) -> tuple:
        """Fit/projection rounds at fixed knots (penalty ``smoothing`` × :data:`PENALTY`),
        leaving out the points farther than ``distance`` (m) and 5 robust standard deviations
        (see :meth:`_trim`)."""
        inliers = np.ones(len(s), dtype=bool)
        for _ in range(self.corrections):
            surface = fit_periodic_surface(s, z, xy, breaks, z_knots, inliers.astype(float),
                                           smoothing * self.penalty_factor * PENALTY)
            s = surface.project(xy, z, s)
            residual = surface.residuals(xy, z, s)
            inliers = self._trim(breaks, s, residual, inliers, distance)
        return surface, s, residual, inliers

    def _trim(self, breaks: np.ndarray, s: np.ndarray, residual: np.ndarray,
              inliers: np.ndarray, distance: float) -> np.ndarray:
        """Points kept: within 5 robust standard deviations (1.4826 × median |residual|) and
        ``distance`` (m). With ``distance`` above ``outlier_distance`` (while the knots are
        refined) the bound is set per knot span: ``outlier_distance`` or 5 robust standard
        deviations of the span's own residuals, at most ``distance`` — a span the coarse
        surface misses (an edge not yet resolved) keeps its points, while the stray points of a
        sparse cloud (isolated, up to millimetres off) are left out everywhere else, where they
        would pull the surface into folds."""
        absolute = np.abs(residual)
        bound = max(TRIM * 1.4826 * float(np.median(absolute[inliers])),
                    self.outlier_distance)
        if distance <= self.outlier_distance:
            return absolute <= max(bound, distance)
        span = np.clip(np.searchsorted(breaks, s, side="right") - 1, 0, len(breaks) - 1)
        order = np.lexsort((absolute, span))
        count = np.bincount(span, minlength=len(breaks))
        start = np.concatenate([[0], np.cumsum(count)[:-1]])
        median = np.zeros(len(breaks))
        occupied = count > 0
        median[occupied] = absolute[order[start[occupied] + (count[occupied] - 1) // 2]]
        local = np.clip(TRIM * 1.4826 * median[span], bound, distance)
        return absolute <= local

    def _refine(self, breaks: np.ndarray, s: np.ndarray, residual: np.ndarray,
                inliers: np.ndarray) -> np.ndarray | None:
        """Breakpoints with the middle of every offending span added, or None."""
        m = len(breaks)
        span = np.clip(np.searchsorted(breaks, s[inliers], side="right") - 1, 0, m - 1)
        count = np.bincount(span, minlength=m)
        square = np.bincount(span, weights=residual[inliers] ** 2, minlength=m)
        rms = np.sqrt(square / np.maximum(count, 1))
        limit = max(self.tolerance, NOISE_FACTOR * float(np.median(rms[count > 0])))
        offending = np.flatnonzero((rms > limit) & (count >= self._split_points))
        if offending.size == 0 or m + offending.size > self.max_breaks:
            return None
        ends = np.append(breaks, 1.0 + breaks[0])
        middles = 0.5 * (ends[offending] + ends[offending + 1])
        return np.sort(np.mod(np.concatenate([breaks, middles]), 1.0))
