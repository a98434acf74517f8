"""The POD–RBF reduced-order model of the blade temperature field, scikit-learn style.

``PodRbfRom(energy=0.992, kernel="thin_plate_spline").fit(snapshots, conditions)`` subtracts
the snapshots' mean, keeps the POD modes holding ``energy`` of the fluctuation energy
(:mod:`steamtwin.rom.pod`) — and, with ``projection_tolerance`` (K), at least as many as bring
every snapshot's largest nodal projection error within it — and fits
``scipy.interpolate.RBFInterpolator`` from the scaled RBF inputs (each mapped to [0, 1] over the
snapshots, then weighted by the field's sensitivity to it, see :func:`_sensitivity_weights`) to
the modal coefficients — and, when given, to the steam-path sensor values of each snapshot. The
RBF inputs are the conditions themselves or, with ``features`` (a
:class:`~steamtwin.rom.features.ControlStageFeatures`), physics features computed from them.
``predict(conditions)`` evaluates the map and reconstructs T = x̄ + Σ aᵢ·φᵢ.

Inputs outside the snapshots' range raise an :class:`ExtrapolationWarning` naming the distance
(in scaled units, 1 = the snapshots' span of an input); NaN or infinite inputs are errors.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.spatial import Delaunay, QhullError, cKDTree

from steamtwin.cache import njit
from steamtwin.errors import SteamtwinError
from steamtwin.rom.features import (
    ControlStageFeatures,
    feature_table_arrays,
    features_from_arrays,
)
from steamtwin.rom.pod import SVD_METHODS, pod

KERNELS = ("thin_plate_spline", "cubic", "quintic", "linear", "multiquadric",
           "inverse_multiquadric", "gaussian", "inverse_quadratic")
INPUT_SCALINGS = ("range", "sensitivity")
SENSITIVITY_FLOOR = 0.2  # smallest input weight of the "sensitivity" scaling
DEFAULT_INPUTS = ("main_steam_pressure", "main_steam_temperature", "control_stage_pressure")


class NotFittedError(SteamtwinError, RuntimeError):
    """The model is used before ``fit``."""


class ExtrapolationWarning(UserWarning):
    """Conditions lie outside the range the snapshots cover."""


class PodRbfRom:
    """POD + RBF reduced-order model (fields in K, conditions in SI).

    Hyper-parameters: ``energy`` (0–1] of the mean-subtracted snapshot energy the modes keep;
    ``projection_tolerance`` (K, or None) adds modes until no snapshot's nodal projection error
    exceeds it; ``features`` (None or a ``ControlStageFeatures``, fitted on the conditions if it
    is not yet) maps the conditions to the RBF's inputs;
    ``kernel``, ``smoothing``, ``degree``, ``epsilon`` as in ``RBFInterpolator``; ``svd`` one of
    ``"auto"``, ``"thin"``, ``"snapshots"``, ``"randomized"``; ``max_modes`` caps the modes;
    ``input_scaling`` ``"sensitivity"`` (each [0, 1]-scaled input weighted by the field's linear
    sensitivity to it) or ``"range"`` (plain [0, 1]).
    Learned: ``mean_`` (N,), ``modes_`` (r, N), ``singular_values_``, ``n_modes_``,
    ``energy_captured_``, ``coefficients_`` (m, r), ``centres_`` (m, d) scaled conditions,
    ``input_min_``/``input_span_``/``input_weights_`` (d,), ``input_points_`` (m, d) scaled
    conditions (the range check), ``feature_names_``/``feature_min_``/``feature_span_``/
    ``feature_weights_`` (k,) of the RBF inputs (the conditions' own without ``features``),
    ``features_``, ``input_names_``, ``sensor_names_``, ``sensor_values_`` (m, s),
    ``field_range_`` (K, max − min over all snapshot values).
    """

    def __init__(self, energy: float = 0.992, kernel: str = "thin_plate_spline",
                 smoothing: float = 0.0, degree: int | None = None,
                 epsilon: float | None = None, svd: str = "auto",
                 max_modes: int | None = None, input_scaling: str = "sensitivity",
                 projection_tolerance: float | None = None,
                 features: ControlStageFeatures | None = None) -> None:
        self.energy = energy
        self.kernel = kernel
        self.smoothing = smoothing
        self.degree = degree
        self.epsilon = epsilon
        self.svd = svd
        self.max_modes = max_modes
        self.input_scaling = input_scaling
        self.projection_tolerance = projection_tolerance
        self.features = features

    def get_params(self) -> dict[str, object]:
        """The hyper-parameters, as passed to ``__init__`` (scikit-learn convention)."""
        return {"energy": self.energy, "kernel": self.kernel, "smoothing": self.smoothing,
                "degree": self.degree, "epsilon": self.epsilon, "svd": self.svd,
                "max_modes": self.max_modes, "input_scaling": self.input_scaling,
                "projection_tolerance": self.projection_tolerance, "features": self.features}

    # -- fitting ----------------------------------------------------------------------------

    def _check_hyperparameters(self) -> None:
        if not isinstance(self.energy, float | int) or not 0.0 < self.energy <= 1.0:
            raise ValueError(f"energy must lie in (0, 1], got {self.energy!r}")
        if self.kernel not in KERNELS:
            raise ValueError(f"kernel must be one of {KERNELS}, got {self.kernel!r}")
        if self.svd not in SVD_METHODS:
            raise ValueError(f"svd must be one of {SVD_METHODS}, got {self.svd!r}")
        if self.smoothing < 0.0:
            raise ValueError(f"smoothing must be ≥ 0, got {self.smoothing!r}")
        if self.input_scaling not in INPUT_SCALINGS:
            raise ValueError(f"input_scaling must be one of {INPUT_SCALINGS}, got "
                             f"{self.input_scaling!r}")
        if self.max_modes is not None and self.max_modes < 1:
            raise ValueError(f"max_modes must be ≥ 1, got {self.max_modes!r}")
        tolerance = self.projection_tolerance
        if tolerance is not None and not (isinstance(tolerance, float | int)
                                          and np.isfinite(tolerance) and tolerance >= 0.0):
            raise ValueError(f"projection_tolerance must be None or a number ≥ 0 (K), got "
                             f"{tolerance!r}")
        if self.features is not None and not isinstance(self.features, ControlStageFeatures):
            raise ValueError(f"features must be None or a ControlStageFeatures, got "
                             f"{type(self.features).__name__}")

    def fit(self, snapshots: np.ndarray, conditions: np.ndarray,
            input_names: Sequence[str] = DEFAULT_INPUTS, sensors: np.ndarray | None = None,
            sensor_names: Sequence[str] = ()) -> PodRbfRom:
        """Learn modes and the RBF map from ``snapshots`` (m, N) K at ``conditions`` (m, d).

        ``sensors`` (m, s) are steam-path sensor values at each snapshot's condition (SI),
        interpolated alongside the modal coefficients.
        """
        self._check_hyperparameters()
        x = np.asarray(snapshots, dtype=float)
        c = np.asarray(conditions, dtype=float)
        if x.ndim != 2 or x.shape[0] < 3:
            raise ValueError(f"snapshots must have shape (m ≥ 3, N), got {x.shape}")
        if c.ndim != 2 or c.shape[0] != x.shape[0]:
            raise ValueError(f"conditions must have shape ({x.shape[0]}, d), got {c.shape}")
        if len(input_names) != c.shape[1]:
            raise ValueError(f"{c.shape[1]} condition columns but input_names {input_names!r}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(c))):
            raise ValueError("snapshots and conditions must be finite")
        span = c.max(axis=0) - c.min(axis=0)
        if np.any(span <= 0.0):
            flat = [name for name, s in zip(input_names, span, strict=True) if s <= 0]
            raise ValueError(f"conditions do not vary in {flat}: cannot scale them")
        s = np.zeros((x.shape[0], 0)) if sensors is None else np.asarray(sensors, dtype=float)
        if s.ndim != 2 or s.shape[0] != x.shape[0] or s.shape[1] != len(sensor_names):
            raise ValueError(f"sensors must have shape ({x.shape[0]}, {len(sensor_names)}) "
                             f"matching sensor_names, got {s.shape}")
        if self.features is not None and tuple(input_names) != self.features.input_names:
            raise ValueError(f"features take the inputs {self.features.input_names}, got "
                             f"{tuple(input_names)}")
        basis = pod(x, method=self.svd, max_rank=self.max_modes)
        r = basis.modes_for_energy(float(self.energy))
        if self.projection_tolerance is not None:
            r = _modes_for_projection(x - basis.mean, basis.modes, r,
                                      float(self.projection_tolerance))
        self.mean_ = basis.mean
        self.singular_values_ = basis.singular_values
        self.modes_ = np.ascontiguousarray(basis.modes[:r])
        self.n_modes_ = r
        self.energy_captured_ = (float(np.sum(basis.singular_values[:r] ** 2)
                                       / basis.total_energy) if basis.total_energy > 0 else 1.0)
        self.input_names_ = tuple(input_names)
        self.input_min_ = c.min(axis=0)
        self.input_span_ = span
        self.coefficients_ = (x - self.mean_) @ self.modes_.T
        unit = (c - self.input_min_) / span
        self.input_weights_ = self._weights(unit)
        self.input_points_ = unit * self.input_weights_
        if self.features is None:
            self.features_ = None
            self.feature_names_ = self.input_names_
            self.feature_min_, self.feature_span_ = self.input_min_, self.input_span_
            self.feature_weights_ = self.input_weights_
            self.centres_ = self.input_points_
        else:
            self.features_ = self.features if self.features.is_fitted else self.features.fit(c)
            z = self.features_.transform(c)
            self.feature_names_ = tuple(self.features_.feature_names)
            self.feature_min_ = z.min(axis=0)
            self.feature_span_ = z.max(axis=0) - self.feature_min_
            if np.any(self.feature_span_ <= 0.0):
                flat = [n for n, s_ in zip(self.feature_names_, self.feature_span_, strict=True)
                        if s_ <= 0]
                raise ValueError(f"features do not vary in {flat}: cannot scale them")
            z_unit = (z - self.feature_min_) / self.feature_span_
            self.feature_weights_ = self._weights(z_unit)
            self.centres_ = z_unit * self.feature_weights_
        self.sensor_names_ = tuple(sensor_names)
        self.sensor_values_ = s
        self.field_range_ = float(x.max() - x.min())
        self._build_interpolator()
        return self

    def _weights(self, unit: np.ndarray) -> np.ndarray:
        if self.input_scaling == "sensitivity":
            return _sensitivity_weights(unit, self.coefficients_)
        return np.ones(unit.shape[1])

    def get_state(self) -> dict[str, np.ndarray]:
        """The fitted ROM as named arrays (numbers and text only: no pickle): the
        hyperparameters a prediction depends on and every learned array; the ROM file's
        contents, listed once here (:meth:`from_state` reads them back)."""
        self._check_fitted()
        return {
            "energy": np.array(float(self.energy)), "kernel": np.array(self.kernel),
            "smoothing": np.array(float(self.smoothing)),
            "degree": np.array(-1 if self.degree is None else int(self.degree), dtype=np.int64),
            "epsilon": np.array(np.nan if self.epsilon is None else float(self.epsilon)),
            "input_scaling": np.array(self.input_scaling),
            "projection_tolerance": np.array(np.nan if self.projection_tolerance is None
                                             else float(self.projection_tolerance)),
            "modes": self.modes_, "mean": self.mean_, "singular_values": self.singular_values_,
            "coefficients": self.coefficients_, "centres": self.centres_,
            "sensor_values": self.sensor_values_, "sensor_names": text_array(self.sensor_names_),
            "input_names": text_array(self.input_names_), "input_min": self.input_min_,
            "input_span": self.input_span_, "input_weights": self.input_weights_,
            "energy_captured": np.array(self.energy_captured_),
            "field_range": np.array(self.field_range_), "input_points": self.input_points_,
            "feature_names": text_array(self.feature_names_), "feature_min": self.feature_min_,
            "feature_span": self.feature_span_, "feature_weights": self.feature_weights_,
            **feature_table_arrays(self.features_),
        }

    @classmethod
    def from_state(cls, state: Mapping[str, np.ndarray]) -> PodRbfRom:
        """The ROM :meth:`get_state` described (ValueError for inconsistent arrays)."""
        degree = int(state["degree"])
        epsilon = float(state["epsilon"])
        tolerance = float(state["projection_tolerance"])
        features = features_from_arrays(state, tuple(state["feature_names"]))
        rom = cls(energy=float(state["energy"]), kernel=str(state["kernel"]),
                  smoothing=float(state["smoothing"]), degree=None if degree < 0 else degree,
                  epsilon=None if np.isnan(epsilon) else epsilon,
                  input_scaling=str(state["input_scaling"]),
                  projection_tolerance=None if np.isnan(tolerance) else tolerance,
                  features=features)
        rom._check_hyperparameters()
        return rom.restore(
            modes=state["modes"], mean=state["mean"], singular_values=state["singular_values"],
            coefficients=state["coefficients"], centres=state["centres"],
            input_names=tuple(str(n) for n in state["input_names"]),
            input_min=state["input_min"], input_span=state["input_span"],
            input_weights=state["input_weights"],
            sensor_names=tuple(str(n) for n in state["sensor_names"]),
            sensor_values=state["sensor_values"],
            energy_captured=float(state["energy_captured"]),
            field_range=float(state["field_range"]), input_points=state["input_points"],
            feature_names=tuple(str(n) for n in state["feature_names"]),
            feature_min=state["feature_min"], feature_span=state["feature_span"],
            feature_weights=state["feature_weights"], features=features)

    def restore(self, *, modes: np.ndarray, mean: np.ndarray, singular_values: np.ndarray,
                coefficients: np.ndarray, centres: np.ndarray, input_names: Sequence[str],
                input_min: np.ndarray, input_span: np.ndarray, input_weights: np.ndarray,
                sensor_names: Sequence[str], sensor_values: np.ndarray, energy_captured: float,
                field_range: float, input_points: np.ndarray | None = None,
                feature_names: Sequence[str] | None = None,
                feature_min: np.ndarray | None = None, feature_span: np.ndarray | None = None,
                feature_weights: np.ndarray | None = None,
                features: ControlStageFeatures | None = None) -> PodRbfRom:
        """Set the learned state from stored arrays (a ROM file) and rebuild the RBF map.

        Without ``features`` the RBF inputs are the scaled conditions (``centres`` =
        ``input_points``); with them, ``input_points`` and the ``feature_*`` arrays are needed.
        """
        self.modes_ = np.ascontiguousarray(modes, dtype=float)
        self.mean_ = np.asarray(mean, dtype=float)
        self.singular_values_ = np.asarray(singular_values, dtype=float)
        self.n_modes_ = self.modes_.shape[0]
        self.coefficients_ = np.asarray(coefficients, dtype=float)
        self.centres_ = np.asarray(centres, dtype=float)
        self.input_names_ = tuple(input_names)
        self.input_min_ = np.asarray(input_min, dtype=float)
        self.input_span_ = np.asarray(input_span, dtype=float)
        self.input_weights_ = np.asarray(input_weights, dtype=float)
        self.sensor_names_ = tuple(sensor_names)
        self.sensor_values_ = np.asarray(sensor_values, dtype=float)
        self.energy_captured_ = float(energy_captured)
        self.field_range_ = float(field_range)
        self.features_ = features
        if features is None:
            self.input_points_ = self.centres_
            self.feature_names_ = self.input_names_
            self.feature_min_, self.feature_span_ = self.input_min_, self.input_span_
            self.feature_weights_ = self.input_weights_
        else:
            if input_points is None or feature_names is None or feature_min is None or \
                    feature_span is None or feature_weights is None:
                raise ValueError("a ROM with features needs input_points and the feature_* "
                                 "arrays")
            self.input_points_ = np.asarray(input_points, dtype=float)
            self.feature_names_ = tuple(feature_names)
            self.feature_min_ = np.asarray(feature_min, dtype=float)
            self.feature_span_ = np.asarray(feature_span, dtype=float)
            self.feature_weights_ = np.asarray(feature_weights, dtype=float)
        self._build_interpolator()
        return self

    def _build_interpolator(self) -> None:
        # (N, r) single precision for one-field sums: half the memory traffic; the rounding
        # (2⁻²⁴ relative on each mode value) stays below 1e-6 K for fields of ~1000 K
        self._modes_by_node = np.ascontiguousarray(self.modes_.T, dtype=np.float32)
        values = np.hstack([self.coefficients_, self.sensor_values_])
        self.rbf_ = RBFInterpolator(self.centres_, values, kernel=self.kernel,
                                    smoothing=self.smoothing, degree=self.degree,
                                    epsilon=self.epsilon)
        self._tree = cKDTree(self.input_points_)
        try:
            self._hull = Delaunay(self.input_points_)
        except QhullError:
            self._hull = None

    # -- prediction ---------------------------------------------------------------------------

    def _check_fitted(self) -> None:
        if not hasattr(self, "rbf_"):
            raise NotFittedError("this PodRbfRom is not fitted yet: call fit(...) or load a "
                                 "ROM file first")

    def scale(self, conditions: np.ndarray) -> np.ndarray:
        """Conditions (n, d) SI → scaled (n, d); raises ValueError on NaN/inf or bad shape."""
        return (self._validated(conditions) - self.input_min_) / self.input_span_ * \
            self.input_weights_

    def _validated(self, conditions: np.ndarray) -> np.ndarray:
        self._check_fitted()
        c = np.asarray(conditions, dtype=float)
        if c.ndim == 1:
            c = c[None, :]
        d = self.input_min_.shape[0]
        if c.ndim != 2 or c.shape[1] != d:
            raise ValueError(f"conditions must have {d} columns {self.input_names_}, got shape "
                             f"{np.shape(conditions)}")
        bad = ~np.all(np.isfinite(c), axis=1)
        if np.any(bad):
            row = int(np.flatnonzero(bad)[0])
            raise ValueError(f"conditions row {row} is not finite ({c[row].tolist()}); "
                             f"inputs {self.input_names_} must be numbers")
        return c

    def rbf_inputs(self, conditions: np.ndarray) -> np.ndarray:
        """Scaled RBF inputs (n, k): the scaled conditions, or their scaled features."""
        c = self._validated(conditions)
        if self.features_ is None:
            return (c - self.input_min_) / self.input_span_ * self.input_weights_
        return ((self.features_.transform(c) - self.feature_min_) / self.feature_span_
                * self.feature_weights_)

    def extrapolation_distance(self, conditions: np.ndarray) -> np.ndarray:
        """Scaled distance outside the snapshots' convex hull (0 inside), per row.

        Outside the snapshots' bounding box: the distance to the box, in units of each input's
        snapshot span; inside the box but outside the hull: the distance to the nearest
        snapshot in the same units (for the largest-weight input).
        """
        return self._distance(self.scale(conditions))

    def _distance(self, scaled: np.ndarray) -> np.ndarray:
        unit = scaled / self.input_weights_
        outside_box = np.linalg.norm(np.maximum(0.0, np.maximum(-unit, unit - 1.0)), axis=1)
        if self._hull is not None:
            outside = self._hull.find_simplex(scaled) < 0
        else:
            outside = outside_box > 0.0
        distance = np.zeros(scaled.shape[0])
        if np.any(outside):
            nearest, _ = self._tree.query(scaled[outside])
            nearest = nearest / float(np.max(self.input_weights_))
            distance[outside] = np.where(outside_box[outside] > 0.0, outside_box[outside],
                                         nearest)
        return distance

    def _warn_extrapolation(self, scaled: np.ndarray, conditions: np.ndarray) -> None:
        distance = self._distance(scaled)
        if np.any(distance > 0.0):
            worst = int(np.argmax(distance))
            values = ", ".join(f"{name} = {v:.6g}" for name, v in
                               zip(self.input_names_, np.atleast_2d(conditions)[worst],
                                   strict=True))
            warnings.warn(
                f"{int(np.sum(distance > 0))} condition(s) outside the snapshots' range; the "
                f"farthest ({values}) lies {distance[worst]:.3f} scaled units outside "
                "(1 = an input's snapshot span): the ROM extrapolates",
                ExtrapolationWarning, stacklevel=3)

    def predict_reduced(self, conditions: np.ndarray, warn: bool = True) -> np.ndarray:
        """Interpolated [modal coefficients | sensors] (n, r + s) at ``conditions`` (n, d)."""
        if warn:
            self._warn_extrapolation(self.scale(conditions), conditions)
        return self.rbf_(self.rbf_inputs(conditions))

    def predict_coefficients(self, conditions: np.ndarray) -> np.ndarray:
        """Modal coefficients (n, r) K at ``conditions``."""
        return self.predict_reduced(conditions)[:, : self.n_modes_]

    def predict_sensors(self, conditions: np.ndarray) -> np.ndarray:
        """Steam-path sensor predictions (n, s) SI at ``conditions``."""
        return self.predict_reduced(conditions)[:, self.n_modes_:]

    def reconstruct(self, coefficients: np.ndarray) -> np.ndarray:
        """Fields (n, N) K from modal coefficients (n, r): x̄ + a·Φ.

        One field is summed by a compiled single-thread loop over the nodes from single-precision
        modes, accumulating in double (memory bound: on a busy 2-core machine a multithreaded
        BLAS matrix–vector product took 8 ms at N = 200k, r = 10, this loop 0.3–0.7 ms);
        several fields use BLAS in double precision.
        """
        self._check_fitted()
        a = np.atleast_2d(np.asarray(coefficients, dtype=float))
        if a.shape[1] != self.n_modes_:
            raise ValueError(f"coefficients must have {self.n_modes_} columns, got {a.shape}")
        if a.shape[0] == 1:
            out = np.empty((1, self.mean_.size))
            _field_from_modes(self.mean_, self._modes_by_node, a[0], out[0])
            return out
        return self.mean_ + a @ self.modes_

    def predict(self, conditions: np.ndarray) -> np.ndarray:
        """Temperature fields (n, N) K at ``conditions`` (n, d) SI (or (N,) for one row)."""
        fields = self.reconstruct(self.predict_coefficients(conditions))
        return fields[0] if np.ndim(conditions) == 1 else fields

    def project(self, fields: np.ndarray) -> np.ndarray:
        """Modal coefficients (n, r) of fields (n, N): the best approximation in the modes."""
        self._check_fitted()
        return (np.atleast_2d(np.asarray(fields, dtype=float)) - self.mean_) @ self.modes_.T


@njit(cache=True, fastmath=True)  # reassociation only: lets the node loop vectorise
def _field_from_modes(mean: np.ndarray, modes_by_node: np.ndarray, coefficients: np.ndarray,
                      out: np.ndarray) -> None:
    """out[j] = mean[j] + Σₖ aₖ·Φ[j, k] over the nodes j (modes stored node-major)."""
    for j in range(modes_by_node.shape[0]):
        value = mean[j]
        for k in range(modes_by_node.shape[1]):
            value += coefficients[k] * modes_by_node[j, k]
        out[j] = value


def _modes_for_projection(centred: np.ndarray, modes: np.ndarray, r: int,
                          tolerance: float) -> int:
    """Smallest r' ≥ r whose modes leave every snapshot within ``tolerance`` (K) at every node.

    The projection error of snapshot x is (x − x̄) − Φᵣᵀ Φᵣ (x − x̄); it is computed for the
    snapshots themselves (held-out conditions lie between them; measured on the reference
    blade, held-out projection errors stay within the snapshots' own, 0.16 vs 0.20 K at 3
    modes). All modes if none suffices.
    """
    coefficients = centred @ modes.T
    for rank in range(r, modes.shape[0] + 1):
        residual = centred - coefficients[:, :rank] @ modes[:rank]
        if np.abs(residual).max() <= tolerance:
            return rank
    return modes.shape[0]


def _sensitivity_weights(unit: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """Input weights ∝ the field's linear sensitivity to each [0, 1]-scaled input.

    The least-squares plane a₁ ≈ β₀ + Σ βᵢ·uᵢ of the first modal coefficient gives |βᵢ|, the
    change of the dominant field pattern over input i's snapshot span; weights |βᵢ|/max|β|
    (floored at 0.2, so an input acting only nonlinearly keeps a say) make a unit step in the
    scaled space change the field alike in every
    direction — the isotropy a radial kernel assumes (the idea of per-input length scales,
    "automatic relevance determination", Rasmussen & Williams, *Gaussian Processes for Machine
    Learning*, 2006, §5.1, fixed here by a linear fit instead of optimised).
    """
    design = np.column_stack([unit, np.ones(unit.shape[0])])
    beta, *_ = np.linalg.lstsq(design, coefficients[:, 0], rcond=None)
    magnitude = np.abs(beta[:-1])
    if not np.any(magnitude > 0):
        return np.ones(unit.shape[1])
    return np.maximum(magnitude / magnitude.max(), SENSITIVITY_FLOOR)


def text_array(values: Sequence[str]) -> np.ndarray:
    """Names as a fixed-width text array (an empty one of width 1)."""
    return np.array([str(v) for v in values], dtype=np.str_) if len(values) else np.zeros(
        0, dtype="<U1")
