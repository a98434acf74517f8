"""The HP rotor model of a turbine spec: conduction FEM, thermo-elastic stress and their
transient ROM glued into one estimator (issue 23, items 3–4).

(Over 500 lines: the estimator, its file format, its states' fingerprint and its full-order
reference share the layout of the critical points' outputs, so they stay together.)

:class:`RotorModel` follows scikit-learn's habit: the constructor stores hyper-parameters, and
:meth:`RotorModel.fit` builds the mesh of the spec's ``[rotor]`` section
(:func:`~steamtwin.rotor.geometry.rotor_mesh`), the rotor steel
(:func:`~steamtwin.rotor.steel.steel`), the conduction FEM
(:class:`~steamtwin.rotor.conduction.RotorConduction`) at a few reference temperatures, the
stress operator at the groove root and the bore (:mod:`steamtwin.rotor.elasticity`), and fits
the POD–Galerkin ROM (:class:`~steamtwin.rotor.transient_rom.ConductionRom`) on training ramps
of the unit's own operating line (FOM → :func:`~steamtwin.rotor.steam_side.steam_side` →
full-order snapshots).

**Stress in the ROM.** The stress at a point is c(T̄)·S·ε_th(T) + centrifugal·ω²
(:class:`~steamtwin.rotor.elasticity.StressOperator`: S the stress per unit nodal thermal strain,
c = E/(1−ν) at the volume-mean temperature T̄ over its value where S was built). Its tangent
about T̄ (``StressOperator.linearised``) is not good enough here: the tabulated steel's thermal
strain is the ASME mean coefficient (rounded to 0.1·10⁻⁶/°F) times T − 70 °F, whose
derivative jumps by ±15 % between table points (e.g. 14.2 → 17.3·10⁻⁶/K at 755 K), so a tangent
at T̄ was 9 % of the stress range off at the groove root on a 5 %/min ramp, and chords over
±50 K still 3.5 %. The nonlinearity is instead interpolated empirically (DEIM: Chaturantabut &
Sorensen, SIAM J. Sci. Comput. 32 (2010) 2737; node choice by Q-DEIM, Drmač & Gugercin, SIAM
J. Sci. Comput. 38 (2016) A631): a POD basis U of the nodal thermal-strain fields of the training
runs and q interpolation nodes P give ε_th(T) ≈ U·(PᵀU)⁻¹·ε_th(T_P), so the stress is
c(T̄)·[S·U·(PᵀU)⁻¹]·ε_th(T_P) + centrifugal·ω² — the ROM outputs the temperatures at the q
nodes and T̄ (rows of its modes), the model evaluates ε_th and E/(1−ν) of the steel there. The
remaining difference to a full thermo-elastic solve with E(T), ν(T) at every quadrature point is
the operator's "E/(1−ν) at the mean" (0.6 % of the range on that ramp).

**The fatigue scalar ("equivalent").** Per sample and location: the stress projected in the
von Mises metric on the location's direction of largest variance over the training runs
(:func:`~steamtwin.rotor.stress_points.equivalent_stress`, fitted by
:func:`~steamtwin.rotor.stress_points.equivalent_direction`), tensile excursions positive. It is
linear in the components, so continuous (the von Mises stress signed by the largest-magnitude
principal, used before, jumped by 2·σ_vM where |σ₁| = |σ₃|). The rotor surface at the groove
root is in a nearly proportional multiaxial state (σ_θ and σ_z driven by one temperature
difference; on the reference rotor the direction holds 99.97 % of the training variance), for
which its range between two instants equals the von Mises equivalent of the component ranges —
the equivalent stress range of ASME BPVC VIII-2 (2019) §5.5.3.2 (eq. 5.30) — while the sign keeps
compressive (heating) and tensile (cooling) peaks apart for rainflow counting and the
mean-stress correction. EN 13445-3 cl. 18.6 would use Tresca on the principal-stress ranges
(≤ 15 % above von Mises); EN 12952-3 cl. 13.4 uses the surface principal stress differences at a
bore — equivalent in this state; the von Mises form was chosen for the ASME design-curve factors
(:data:`~steamtwin.rotor.fatigue.ASME_DESIGN_FACTORS`) the life module applies.

The Dittus–Boelter cooling factor Pr^0.1 (steam_side.py) is not applied by the ROM: on the
reference unit it is ≤ 1.002 (superheated steam at the control stage), below the htc's own
uncertainty; the full-order run (``full_order=True``) applies it, so the acceptance benchmark's
ROM-vs-FEM error includes its effect.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg as la

from steamtwin.errors import RotorAreaError
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.parameters import ModelParameters
from steamtwin.progress import ProgressCallback, scaled
from steamtwin.rotor.conduction import RotorConduction, htc_column, steam_temperature_column
from steamtwin.rotor.elasticity import AxisymmetricElasticity
from steamtwin.rotor.geometry import critical_nodes, rotor_geometry, rotor_mesh
from steamtwin.rotor.steam_side import steam_side
from steamtwin.rotor.steel import TabulatedSteel, steel
from steamtwin.rotor.stress_points import (
    COMPONENTS,
    StressState,
    equivalent_direction,
    equivalent_stress,
)
from steamtwin.rotor.transient_rom import ConductionRom, RomState, SteamHistory, full_order_run
from steamtwin.spec.turbine import TurbineSpec

__all__ = ["DEFAULT_FIT_RAMPS", "LOCATIONS", "RotorModel", "RotorRun", "RotorState"]

LOCATIONS = ("groove", "bore")
"""The critical points, in the order of every per-location array."""

STRESS_COLUMNS = (*COMPONENTS, "von_mises", "equivalent")
"""Stress columns per location in a run frame (Pa): ``<location>_<name>``."""

DEFAULT_FIT_RAMPS: tuple[tuple[float, float, float], ...] = ((1.0, 0.3, 0.02), (1.0, 0.3, 0.08))
"""Training ramps (from load, to load, rate), fractions and fraction/min: each runs a hold, the
ramp, a hold, the ramp back and a hold (:data:`TRAINING_HOLD_S`). 2 and 8 %/min bracket the
3–5 %/min of deep peak shaving without containing the 5 %/min acceptance ramp."""

MAX_STRAIN_SNAPSHOTS = 2000
"""Evenly spaced training fields the thermal-strain POD reads at most."""

STRAIN_ENERGY = 1.0 - 1e-10
"""Fraction of the thermal-strain snapshots' energy the interpolation basis keeps."""

TRAINING_HOLD_S = 3600.0
"""Hold (s) after each training ramp: a few of the rotor's conduction time constants
(R²/(π²a) ≈ 0.36²/(π²·8e-6 m²/s) ≈ 27 min for the reference drum; Carslaw & Jaeger §7.4)."""

FORMAT = "steamtwin-rotor-model"
FORMAT_VERSION = 2
"""2: the equivalent stress's directions (version 1 signed von Mises by the dominant
principal)."""


@dataclass(frozen=True)
class RotorState:
    """The rotor's carried state: the ROM's reduced coordinates and time (s), and the
    fingerprint of the model they belong to (:attr:`RotorModel.fingerprint`): reduced
    coordinates mean nothing in another model's basis, so every model refuses a state whose
    fingerprint is not its own."""

    rom: RomState
    model: str

    def to_dict(self) -> dict[str, object]:
        """A JSON-ready dict; floats round-trip exactly through ``json``."""
        return {"format": FORMAT + "-state", "model": self.model, **self.rom.to_dict()}

    @classmethod
    def from_dict(cls, data: Mapping[str, object]) -> RotorState:
        """The state :meth:`to_dict` wrote, bit for bit."""
        if data.get("format") != FORMAT + "-state":
            raise RotorAreaError(f"rotor state: expected format {FORMAT + '-state'!r}, got "
                                 f"{data.get('format')!r}")
        fingerprint = data.get("model")
        if not isinstance(fingerprint, str):
            raise RotorAreaError("rotor state has no 'model' fingerprint (a string; states "
                                 "saved before it was added lack it): start the rotor afresh "
                                 "from equilibrium with its steam instead")
        return cls(RomState.from_dict(dict(data)), fingerprint)


@dataclass(frozen=True)
class RotorRun:
    """A run over a record: ``frame`` indexed like the inputs (columns in SI:
    ``groove_temperature``, ``bore_temperature`` K, ``<location>_<radial|hoop|axial|shear|
    von_mises|equivalent>`` Pa, ``mean_temperature`` K); ``state`` the final state (ROM runs;
    ``None`` for a full-order run)."""

    frame: pd.DataFrame
    state: RotorState | None


def _stress_columns(components: np.ndarray, directions: np.ndarray) -> dict[str, np.ndarray]:
    """Frame columns of stress ``components`` (samples, locations, 4) in Pa, the equivalent
    stress along ``directions`` (locations, 4)."""
    columns: dict[str, np.ndarray] = {}
    for p, location in enumerate(LOCATIONS):
        state = StressState.from_components(np.moveaxis(components[:, p, :], -1, 0))
        for name, values in zip(COMPONENTS, np.moveaxis(components[:, p, :], -1, 0),
                                strict=True):
            columns[f"{location}_{name}"] = values
        columns[f"{location}_von_mises"] = state.von_mises
        columns[f"{location}_equivalent"] = equivalent_stress(state, directions[p])
    return columns


def _seconds(index: pd.Index) -> np.ndarray:
    """Seconds from the first sample of a DatetimeIndex or a numeric index (s)."""
    if isinstance(index, pd.DatetimeIndex):
        return np.asarray((index - index[0]).total_seconds(), dtype=float)
    return np.asarray(index, dtype=float) - float(index[0])


class RotorModel:
    """The rotor thermal-stress model of ``spec`` (module docstring).

    ``mesh_size`` (m): element size far from the groove (default 0.03 m; the groove gets
    ``groove_mesh_size``, default groove radius / 6); ``rom_energy``: the POD energy fraction;
    ``fit_ramps``: training ramps (from load, to load, rate in fraction/min), default
    :data:`DEFAULT_FIT_RAMPS`; ``training_step_s`` (s): the training runs' time step;
    ``reference_temperatures`` (K): where properties and the stress tangent are evaluated
    (default: 6 points spanning the training's steam temperatures).
    """

    def __init__(self, spec: TurbineSpec, *, mesh_size: float | None = None,
                 rom_energy: float = 1.0 - 1e-9,
                 fit_ramps: Sequence[tuple[float, float, float]] | None = None,
                 groove_mesh_size: float | None = None, training_step_s: float = 10.0,
                 training_hold_s: float = TRAINING_HOLD_S,
                 reference_temperatures: Sequence[float] | None = None,
                 max_modes: int | None = None) -> None:
        self.spec = spec
        self.mesh_size = mesh_size
        self.rom_energy = rom_energy
        self.fit_ramps = fit_ramps
        self.groove_mesh_size = groove_mesh_size
        self.training_step_s = training_step_s
        self.training_hold_s = training_hold_s
        self.reference_temperatures = reference_temperatures
        self.max_modes = max_modes

    # --- fit -------------------------------------------------------------------------------
    def _build(self) -> None:
        """Geometry, mesh, steel, conduction and elasticity of the spec (no training)."""
        self.geometry_ = rotor_geometry(self.spec)
        self.mesh_ = rotor_mesh(self.geometry_, 0.03 if self.mesh_size is None
                                else self.mesh_size, self.groove_mesh_size)
        self.steel_ = steel(self.geometry_.section.material)
        self.groups_ = self.geometry_.groups
        self.conduction_ = RotorConduction(self.mesh_, self.steel_, self.groups_)
        nodes = critical_nodes(self.mesh_, self.geometry_)
        self.critical_nodes_ = {"groove": nodes["groove_root"], "bore": nodes["bore"]}
        self.critical_points = {"groove": self.geometry_.groove_root,
                                "bore": self.geometry_.bore_point}
        self.elasticity_ = AxisymmetricElasticity(self.mesh_, self.steel_)
        self.speed_ = float(self.geometry_.section.rotational_speed)
        self.fom_ = FullOrderModel(self.spec)

    @property
    def steel(self) -> TabulatedSteel:
        """The rotor steel (fitted models only)."""
        self._check_fitted()
        return self.steel_

    def training_inputs(self) -> list[pd.DataFrame]:
        """The FOM input frames of the training ramps (SI, on the spec's operating line)."""
        step = self.training_step_s
        if not (np.isfinite(step) and step > 0.0):
            raise RotorAreaError(f"training_step_s must be a positive number of seconds, "
                                 f"got {step!r}")
        frames = []
        for ramp in (DEFAULT_FIT_RAMPS if self.fit_ramps is None else self.fit_ramps):
            start, end, rate = (float(value) for value in ramp)
            if not (min(start, end) > 0.0 and max(start, end) <= 1.1 and rate > 0.0):
                raise RotorAreaError(f"training ramp {ramp!r}: expected (from load, to load, "
                                     "rate) with loads in (0, 1.1] (fraction) and rate > 0 "
                                     "(fraction/min)")
            hold = self.training_hold_s
            load = np.concatenate([
                ramp_profile(start, end, rate, hold / 6.0, hold, step),
                ramp_profile(end, start, rate, 0.0, hold, step)[1:]])
            frames.append(load_profile_inputs(self.spec, load, step))
        return frames

    def fit(self, params: ModelParameters | None = None,
            progress: ProgressCallback | None = None) -> RotorModel:
        """Build the FEM of the spec's rotor and fit the ROM on the training ramps (class
        docstring) with the steam side of ``params`` (default the FOM's defaults). Returns
        ``self``."""
        self._build()
        report = scaled(progress, 0.0, 0.2, "steam side: ")
        inputs = self.training_inputs()
        steam_frames = []
        for index, frame in enumerate(inputs):
            if report is not None:
                report(index / len(inputs), f"training ramp {index + 1}")
            steam_frames.append(self.steam_side(frame, params))
        histories = [SteamHistory(rows.htc[1:], rows.steam[1:], rows.dt)
                     for rows in map(self._history, steam_frames)]
        refs = self._references(histories)
        operators = [self.conduction_.system(ref) for ref in refs]
        report = scaled(progress, 0.2, 0.8, "full-order training runs: ")
        fields = []
        for index, history in enumerate(histories):
            if report is not None:
                report(index / len(histories), f"run {index + 1} of {len(histories)}")
            fields.append(full_order_run(operators, history, reference_temperatures=refs))
        self.stress_operator_ = self.elasticity_.stress_operator(
            [self.critical_points[name] for name in LOCATIONS], float(np.median(refs)))
        training = np.vstack(fields)
        self._fit_strain_interpolation(training)
        path = self._stress(training[:, self.strain_nodes_],
                            training @ self.stress_operator_.volume_weights)
        self.equivalent_directions_ = np.stack([equivalent_direction(path[:, p, :])
                                                for p in range(len(LOCATIONS))])
        nodes = [self.critical_nodes_[name] for name in LOCATIONS] + list(self.strain_nodes_)
        rom = ConductionRom(energy=self.rom_energy, max_modes=self.max_modes)
        rom.fit(operators, (), reference_temperatures=refs, temperature_nodes=nodes,
                output_operator=self.stress_operator_.volume_weights[None, :],
                snapshots=[field.T for field in fields],
                progress=scaled(progress, 0.8, 1.0, "ROM: "))
        self.rom_ = rom
        self.reference_temperatures_ = refs
        self.params_ = params or ModelParameters()
        self.fingerprint_ = self._fingerprint()
        return self

    def _fingerprint(self) -> str:
        """SHA-256 (first 16 hex digits) of the spec's ``[rotor]`` section, the mesh's node
        count and the ROM basis's shape and first values — all a saved and reloaded model
        reproduces bit for bit."""
        section = self.spec.rotor
        modes = self.rom_.modes_
        document = {"rotor": None if section is None else asdict(section),
                    "nodes": int(modes.shape[0]), "basis_shape": list(modes.shape),
                    "basis_start": modes[:4, :4].ravel().tolist()}
        digest = hashlib.sha256(json.dumps(document, sort_keys=True).encode("utf-8"))
        return digest.hexdigest()[:16]

    @property
    def fingerprint(self) -> str:
        """Identifies this fitted model (:meth:`_fingerprint`); carried by its states."""
        self._check_fitted()
        return self.fingerprint_

    def check_state(self, state: RotorState) -> RotorState:
        """``state`` if this model produced it (same :attr:`fingerprint`), else
        :class:`~steamtwin.errors.RotorAreaError`."""
        self._check_fitted()
        if not isinstance(state, RotorState):
            raise RotorAreaError(f"expected a RotorState, got {type(state).__name__}")
        if state.model != self.fingerprint_:
            raise RotorAreaError(
                f"rotor state belongs to another rotor model (fingerprint {state.model!r}; "
                f"this model of spec {self.spec.name!r}, {self.rom_.modes_.shape[0]} nodes, "
                f"{self.rom_.n_modes_} modes, is {self.fingerprint_!r}): use a state this "
                "model produced, or none (equilibrium with the first sample)")
        return state

    def _fit_strain_interpolation(self, fields: np.ndarray) -> None:
        """Empirical interpolation of the nodal thermal-strain field (module docstring): POD
        of ε_th(T) snapshots, Q-DEIM nodes, and the stress per unit strain at those nodes."""
        strain = np.asarray(self.steel_.thermal_strain(fields))
        if strain.shape[0] > MAX_STRAIN_SNAPSHOTS:
            strain = strain[np.linspace(0, strain.shape[0] - 1, MAX_STRAIN_SNAPSHOTS)
                            .round().astype(np.int64)]
        modes, singular, _ = la.svd(strain.T, full_matrices=False)
        energy = np.cumsum(singular ** 2) / np.sum(singular ** 2)
        rank = min(int(np.searchsorted(energy, STRAIN_ENERGY)) + 1, singular.size)
        modes = modes[:, :rank]
        # Q-DEIM (Drmač & Gugercin, SIAM J. Sci. Comput. 38 (2016) A631): the first pivots of a
        # column-pivoted QR of the modes' transpose are the interpolation nodes
        _, _, pivots = la.qr(modes.T, pivoting=True, mode="economic")
        nodes = np.sort(pivots[:rank])
        response = self.stress_operator_.strain_response  # (4, locations, n) Pa per strain
        self.strain_nodes_ = nodes
        self.strain_response_ = np.einsum("cpn,nq->cpq", response,
                                          modes @ la.inv(modes[nodes]))
        self.centrifugal_ = self.stress_operator_.centrifugal * self.speed_ ** 2
        self.frozen_temperature_ = self.stress_operator_.frozen_temperature

    def _references(self, histories: list[SteamHistory]) -> np.ndarray:
        if self.reference_temperatures is not None:
            return np.asarray(self.reference_temperatures, dtype=float)
        means = np.concatenate([np.sum(h.htc * h.steam_temperature, axis=1) / np.sum(h.htc, axis=1)
                                for h in histories])
        return np.linspace(means.min() - 20.0, means.max() + 10.0, 6)

    def _stress(self, strain_temperatures: np.ndarray, mean: np.ndarray) -> np.ndarray:
        """Stress components (samples, locations, 4) in Pa from the temperatures (K) at the
        strain-interpolation nodes (samples, q) and the volume-mean temperature (samples,)."""
        material = self.steel_
        stiffness = (np.asarray(material.youngs_modulus(mean))
                     / (1.0 - np.asarray(material.poisson_ratio(mean))))
        frozen = float(material.youngs_modulus(self.frozen_temperature_)) / (
            1.0 - float(material.poisson_ratio(self.frozen_temperature_)))
        strain = np.asarray(material.thermal_strain(strain_temperatures))
        components = np.einsum("sq,cpq->spc", strain, self.strain_response_)
        return (components * (stiffness / frozen)[:, None, None]
                + self.centrifugal_.T[None, :, :])

    def _check_fitted(self) -> None:
        if not hasattr(self, "rom_"):
            raise RotorAreaError("this RotorModel is not fitted: call fit(...) or "
                                 "RotorModel.load(path) first")

    # --- steam side ------------------------------------------------------------------------
    def steam_side(self, inputs: pd.DataFrame, params: ModelParameters | None = None
                   ) -> pd.DataFrame:
        """Per-group steam temperature (K) and rotor htc (W/(m²·K)) over the FOM input frame
        ``inputs`` (SI), as :func:`~steamtwin.rotor.steam_side.steam_side` gives them."""
        if not hasattr(self, "fom_"):
            self.fom_ = FullOrderModel(self.spec)
        groups = (self.groups_ if hasattr(self, "groups_")
                  else rotor_geometry(self.spec).groups)
        return steam_side(self.fom_, inputs, params, groups=list(groups))

    def _history(self, steam: pd.DataFrame) -> _Rows:
        """(htc, steam temperature, dt) arrays of a steam frame with a uniform time step."""
        columns = [htc_column(g) for g in self.groups_] + [
            steam_temperature_column(g) for g in self.groups_]
        missing = [name for name in columns if name not in steam.columns]
        if missing:
            raise RotorAreaError(f"steam-side frame lacks the columns {missing} (has "
                                 f"{list(steam.columns)}); make it with RotorModel.steam_side")
        values = steam[columns].to_numpy(dtype=float)
        g = len(self.groups_)
        seconds = _seconds(steam.index)
        steps = np.diff(seconds)
        dt = float(steps[0]) if steps.size else 1.0
        if steps.size and (dt <= 0.0 or np.any(np.abs(steps - dt) > 1e-6 * dt)):
            row = int(np.argmax(np.abs(steps - dt) > 1e-6 * dt)) + 1 if dt > 0 else 1
            raise RotorAreaError(f"steam-side frame: samples must be equally spaced in time; "
                                 f"row {row} ({steam.index[row]}) breaks the {dt:g}-s step")
        return _Rows(values[:, :g], values[:, g:], dt)

    # --- online ----------------------------------------------------------------------------
    def initial_state(self, steam: pd.DataFrame | pd.Series) -> RotorState:
        """Metal in equilibrium with ``steam`` (a steam-side frame's first row, or a row)."""
        self._check_fitted()
        row = steam.iloc[0] if isinstance(steam, pd.DataFrame) else steam
        htc, temperature = self._row(row)
        return RotorState(self.rom_.initial_state(htc, temperature), self.fingerprint_)

    def _row(self, row: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        try:
            htc = np.array([row[htc_column(g)] for g in self.groups_], dtype=float)
            temperature = np.array([row[steam_temperature_column(g)] for g in self.groups_],
                                   dtype=float)
        except KeyError as error:
            raise RotorAreaError(f"steam row lacks {error}; expected "
                                 f"{[htc_column(g) for g in self.groups_]} (W/(m²·K)) and "
                                 f"{[steam_temperature_column(g) for g in self.groups_]} (K)"
                                 ) from None
        return htc, temperature

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters | None = None,
                 state: RotorState | None = None, *, full_order: bool = False,
                 stress_every: int = 1) -> RotorRun:
        """Temperature and stress at the groove and bore over the FOM input frame ``inputs``
        (SI, equally spaced), from ``state`` (at the first sample; default: equilibrium with
        it). ``params`` defaults to those the model was fitted with. ``full_order``: run the
        FEM instead (local properties, :meth:`RotorConduction.transient_frame`; stress by a
        full thermo-elastic solve every ``stress_every`` samples, NaN between)."""
        self._check_fitted()
        steam = self.steam_side(inputs, params or self.params_)
        return self.simulate_steam(steam, state, full_order=full_order,
                                   stress_every=stress_every)

    def simulate_steam(self, steam: pd.DataFrame, state: RotorState | None = None, *,
                       full_order: bool = False, stress_every: int = 1) -> RotorRun:
        """:meth:`simulate` from a steam-side frame (:meth:`steam_side`'s columns)."""
        self._check_fitted()
        rows = self._history(steam)
        if full_order:
            return RotorRun(self._full_order(steam, state, stress_every), None)
        start = self.initial_state(steam) if state is None else self.check_state(state)
        temperature, outputs = self.rom_.observe(start.rom)
        observed = np.empty((len(steam), outputs.size + temperature.size))
        observed[0] = np.concatenate([temperature, outputs])
        final = start.rom
        if len(steam) > 1:
            run = self.rom_.simulate(SteamHistory(rows.htc[1:], rows.steam[1:], rows.dt),
                                     start.rom)
            observed[1:] = np.hstack([run.temperature, run.output])
            final = run.final
        return RotorRun(self._frame(observed, steam.index), RotorState(final, self.fingerprint_))

    def _columns(self, observed: np.ndarray) -> dict[str, np.ndarray]:
        """Run-frame columns of ROM observations: (samples, [location temperatures,
        strain-node temperatures, mean temperature]) in K."""
        k = len(LOCATIONS)
        components = self._stress(observed[:, k:-1], observed[:, -1])
        columns = {f"{name}_temperature": observed[:, p] for p, name in enumerate(LOCATIONS)}
        columns.update(_stress_columns(components, self.equivalent_directions_))
        columns["mean_temperature"] = observed[:, -1]
        return columns

    def _frame(self, observed: np.ndarray, index: pd.Index) -> pd.DataFrame:
        return pd.DataFrame(self._columns(observed), index=index)

    def step(self, state: RotorState, steam_row: Mapping[str, float], dt_s: float
             ) -> tuple[RotorState, dict[str, float]]:
        """Advance ``state`` by ``dt_s`` (s) under one steam-side row (:meth:`steam_side`'s
        columns); the new state and its frame row (the batch run's columns) — the same
        compiled kernel as :meth:`simulate`, so a streamed record equals the batch run."""
        rom = self.check_state(state).rom
        htc, temperature = self._row(steam_row)
        new = RotorState(self.rom_.step(rom, htc, temperature, dt_s), self.fingerprint_)
        return new, self.observe(new)

    def observe(self, state: RotorState) -> dict[str, float]:
        """The frame row (SI) of ``state``."""
        temperature, outputs = self.rom_.observe(self.check_state(state).rom)
        columns = self._columns(np.concatenate([temperature, outputs])[None, :])
        return {name: float(values[0]) for name, values in columns.items()}

    # --- full order ------------------------------------------------------------------------
    def _full_order(self, steam: pd.DataFrame, state: RotorState | None,
                    stress_every: int) -> pd.DataFrame:
        if stress_every < 1:
            raise RotorAreaError(f"stress_every must be ≥ 1 sample, got {stress_every!r}")
        if state is None:
            htc, temperature = self._row(steam.iloc[0])
            initial = self.conduction_.steady(htc, temperature)
        else:
            initial = self.rom_.field(self.check_state(state).rom)
        run = self.conduction_.transient_frame(initial, steam, probes=self.critical_nodes_,
                                               snapshot_every=stress_every)
        sampled = np.arange(0, len(steam), stress_every)
        points = [self.critical_points[name] for name in LOCATIONS]
        components = np.full((len(steam), len(LOCATIONS), 4), np.nan)
        mean = np.full(len(steam), np.nan)
        for index, field in zip(sampled, run.snapshots, strict=True):
            stress = self.elasticity_.stress(self.elasticity_.solve(field, self.speed_), points)
            components[index] = np.stack([getattr(stress, name) for name in COMPONENTS], -1)
            mean[index] = field @ self.stress_operator_.volume_weights
        columns = {f"{name}_temperature": run.probes[name].to_numpy() for name in LOCATIONS}
        columns.update(_stress_columns(components, self.equivalent_directions_))
        columns["mean_temperature"] = mean
        return pd.DataFrame(columns, index=steam.index)

    # --- file ------------------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        """Write the fitted model: ``<path>`` (``.npz``, the ROM, no pickle) and
        ``<path>.json`` (what the ROM's outputs mean, the strain interpolation; JSON floats
        round-trip exactly). Returns the npz path."""
        self._check_fitted()
        path = Path(path)
        self.rom_.save(path)
        metadata = {"format": FORMAT, "format_version": FORMAT_VERSION,
                    "spec": self.spec.name, "groups": list(self.groups_),
                    "locations": list(LOCATIONS), "steel": self.steel_.name,
                    "critical_points_m": {k: list(v) for k, v in self.critical_points.items()},
                    "critical_nodes": self.critical_nodes_, "speed_rad_s": self.speed_,
                    "reference_temperatures_k": self.reference_temperatures_.tolist(),
                    "params": asdict(self.params_),
                    "frozen_temperature_k": self.frozen_temperature_,
                    "strain_nodes": self.strain_nodes_.tolist(),
                    "strain_response_pa": self.strain_response_.tolist(),
                    "centrifugal_pa": self.centrifugal_.tolist(),
                    "equivalent_directions": self.equivalent_directions_.tolist()}
        _metadata_path(path).write_text(json.dumps(metadata, indent=1))
        return path

    @classmethod
    def load(cls, path: str | Path, spec: TurbineSpec) -> RotorModel:
        """Read a model :meth:`save` wrote, for ``spec`` (its steam side and FEM rebuild from
        it; a spec of another name is refused)."""
        path = Path(path)
        try:
            metadata = json.loads(_metadata_path(path).read_text())
        except (OSError, ValueError) as error:
            raise RotorAreaError(f"{_metadata_path(path)}: not a rotor model file ({error})"
                                 ) from None
        if metadata.get("format") != FORMAT or metadata.get("format_version") != FORMAT_VERSION:
            raise RotorAreaError(f"{_metadata_path(path)}: format {metadata.get('format')!r} "
                                 f"version {metadata.get('format_version')!r}, expected "
                                 f"{FORMAT!r} version {FORMAT_VERSION}")
        if metadata["spec"] != spec.name:
            raise RotorAreaError(f"{path}: fitted for spec {metadata['spec']!r}, given "
                                 f"{spec.name!r}")
        model = cls(spec)
        model.rom_ = ConductionRom.load(path)
        model.groups_ = tuple(metadata["groups"])
        model.steel_ = steel(metadata["steel"])
        model.critical_points = {k: tuple(v) for k, v in metadata["critical_points_m"].items()}
        model.critical_nodes_ = dict(metadata["critical_nodes"])
        model.speed_ = float(metadata["speed_rad_s"])
        model.reference_temperatures_ = np.array(metadata["reference_temperatures_k"])
        model.params_ = ModelParameters(**metadata["params"])
        model.frozen_temperature_ = float(metadata["frozen_temperature_k"])
        model.strain_nodes_ = np.array(metadata["strain_nodes"], dtype=np.int64)
        model.strain_response_ = np.array(metadata["strain_response_pa"], dtype=float)
        model.centrifugal_ = np.array(metadata["centrifugal_pa"], dtype=float)
        model.equivalent_directions_ = np.array(metadata["equivalent_directions"], dtype=float)
        model.fingerprint_ = model._fingerprint()
        return model


@dataclass(frozen=True)
class _Rows:
    htc: np.ndarray
    steam: np.ndarray
    dt: float


def _metadata_path(path: Path) -> Path:
    return path.with_name(path.name + ".json")
