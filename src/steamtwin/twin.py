"""``steamtwin.Twin``: one turbine's twin — spec, parameters, blade ROM and provenance.

The object a Python user works with, in the scikit-learn habit: the constructor stores its
arguments (validated, nothing computed); :meth:`Twin.calibrate` and :meth:`Twin.build_rom` learn
and return the twin, their results in attributes ending in ``_`` (``params_``, ``rom_``, …);
:meth:`Twin.simulate` and :meth:`Twin.validate` use what the twin holds. The CLI commands
``calibrate`` and ``validate`` are thin layers over it.

One folder holds a twin (:meth:`Twin.save`, :meth:`Twin.load`), to zip and hand on; nothing is
pickled. Its format and checks are :mod:`steamtwin.twinfile`.

(Over 500 lines for a reason: the one class a user imports, each method the body a CLI command
had before; what is not the class's — the folder format — lives in :mod:`steamtwin.twinfile`.)
"""

from __future__ import annotations

import dataclasses
import json
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.dcs.history import History
from steamtwin.dcs.tagmap import TagMap
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.parameters import (
    DEFAULT_PRIORS,
    ModelParameters,
    ParameterPrior,
)
from steamtwin.model.sensor_setup import SensorSetup, sensor_setup
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.progress import ProgressCallback
from steamtwin.rom.romfile import BladeRom
from steamtwin.spec import TurbineSpec
from steamtwin.spec.fingerprint import (
    builtin_spec_text,
    load_spec_and_text,
    spec_hash,
)
from steamtwin.twinfile import (
    PARAMS_FILE,
    REPORTS,
    ROM_FILE,
    SPEC_FILE,
    TwinError,
    read_folder,
    write_manifest,
    write_parameters_file,
)

__all__ = ["Twin", "TwinError", "monitoring_model", "sensor_model"]

STEADY_TOLERANCE = 0.02
"""± fraction of rated load of a steady hold (validation's automatic windows)."""


class Twin:
    """A steam turbine's digital twin.

    ``spec``: the turbine (:class:`~steamtwin.spec.TurbineSpec`, SI); ``params``: model
    parameters (default: the empirical 1, 1, 1); ``rom``: a blade ROM
    (:class:`~steamtwin.rom.romfile.BladeRom`) built for this spec and these parameters;
    ``spec_toml``: the spec's TOML text (what :meth:`save` writes; default: the built-in's text
    when ``spec`` is a built-in turbine); ``sensor_offsets``: signal → measured − model (K;
    Pa for a pressure), a calibration's estimate of each sensor's bias, read by :meth:`validate`;
    ``provenance``: earlier steps (dicts) this twin carries on.

    Fitted attributes: after :meth:`calibrate` ``params_``, ``sensor_offsets_``,
    ``calibrator_``, ``windows_`` (the :class:`~steamtwin.calibration.windowset.WindowSet`),
    ``model_`` (the FOM read through the plant's sensors), ``sensors_``,
    ``initial_rmse_`` (K, the empirical parameters on the same windows); after
    :meth:`calibrate_online` ``online_``; after :meth:`build_rom` ``rom_``; after
    :meth:`validate` ``validation_`` (the report).
    In use, fitted or given: :attr:`parameters`, :attr:`intervals`, :attr:`offsets`,
    :attr:`blade_rom`; the provenance: :attr:`steps`.
    """

    def __init__(self, spec: TurbineSpec, params: ModelParameters | None = None, *,
                 rom: BladeRom | None = None, spec_toml: str | None = None,
                 sensor_offsets: Mapping[str, float] | None = None,
                 provenance: Sequence[Mapping[str, Any]] = ()) -> None:
        for name, value, kind in (("spec", spec, TurbineSpec),
                                  ("params", params, ModelParameters | None),
                                  ("rom", rom, BladeRom | None),
                                  ("spec_toml", spec_toml, str | None)):
            if not isinstance(value, kind):
                raise TypeError(f"Twin: {name} must be {kind} (got {type(value).__name__})")
        self.spec = spec
        self.params = params
        self.rom = rom
        self.spec_toml = spec_toml
        self.sensor_offsets = dict(sensor_offsets or {})
        self.provenance = [dict(step) for step in provenance]

    # -- construction -----------------------------------------------------------------------

    @classmethod
    def from_spec(cls, source: str | Path, params: ModelParameters | None = None) -> Twin:
        """The twin of a built-in turbine (``"reference"``) or a spec TOML file."""
        spec, text = load_spec_and_text(source)
        return cls(spec, params, spec_toml=text,
                   provenance=[_step("from_spec", source=str(source),
                                     spec={"name": spec.name, "sha256": spec_hash(spec)})])

    # -- what the twin holds ----------------------------------------------------------------

    @property
    def parameters(self) -> ModelParameters:
        """The parameters in use: the calibrated ``params_``, else ``params``, else 1, 1, 1."""
        fitted = getattr(self, "params_", None)
        return fitted or self.params or ModelParameters()

    @property
    def offsets(self) -> dict[str, float]:
        """Sensor offsets in use (K; Pa for a pressure witness): the calibration's, else the
        constructor's."""
        return dict(getattr(self, "sensor_offsets_", self.sensor_offsets))

    @property
    def delivered_model(self) -> FullOrderModel:
        """The calibrated FOM as ``validate`` and ``predict`` read it: the plant's sensors of
        the calibration (time constants, thermocouple depth) and the sensor offsets in use
        (:attr:`offsets`, K; Pa for a pressure). Needs :meth:`calibrate` first (``model_``)."""
        if not hasattr(self, "model_"):
            raise TwinError("the twin is not calibrated: call calibrate(history) first")
        return FullOrderModel(self.model_.spec, sensor_offsets=self.offsets or None,
                              sensor_time_constants=self.model_.sensor_time_constants)

    @property
    def intervals(self) -> dict[str, tuple[float, float]]:
        """The parameters' 95 % posterior intervals (name → (low, high), dimensionless) of the
        calibration — this twin's, else the one its ``params.json`` carries; empty without."""
        calibrator = getattr(self, "calibrator_", None)
        if calibrator is not None:
            posterior = calibrator.posterior_
            section = posterior.to_dict()["intervals"] if posterior is not None else {}
        else:
            text = getattr(self, "_params_text", None)
            document = json.loads(text) if text is not None else {}
            section = document.get("posterior", {}).get("intervals", {})
        return {name: (float(row["low"]), float(row["high"])) for name, row in section.items()}

    @property
    def blade_rom(self) -> BladeRom | None:
        """The ROM in use: the one :meth:`build_rom` built, else the constructor's."""
        return getattr(self, "rom_", self.rom)

    @property
    def steps(self) -> list[dict[str, Any]]:
        """The provenance: the steps that made this twin, oldest first."""
        return [*self.provenance, *getattr(self, "steps_", [])]

    def _record(self, step: dict[str, Any]) -> None:
        self.steps_ = [*getattr(self, "steps_", []), step]

    # -- model ------------------------------------------------------------------------------

    @property
    def full_order_model(self) -> FullOrderModel:
        """The spec's full-order model (ideal sensors), built once: what :meth:`simulate` runs;
        its design point and detailed runs (``simulate_detailed``) for a user who wants them."""
        model = getattr(self, "_model", None)
        if model is None:
            model = self._model = FullOrderModel(self.spec)
        return model

    @property
    def blade_rows(self) -> tuple[str, ...]:
        """The blade rows this spec sizes (``hp1``…, ``ip1``…): what :meth:`build_rom`'s
        ``row`` and the geometry chain accept for this turbine (each row sized: seconds)."""
        from steamtwin.errors import SteamtwinError
        from steamtwin.geometry.profile import ROWS, row_design

        rows = []
        for row in ROWS:
            try:
                row_design(self.spec, row)
            except (SteamtwinError, ValueError):
                continue
            rows.append(row)
        return tuple(rows)

    def blade_design(self, row: str) -> Any:
        """Blade row ``row`` sized from the spec
        (:class:`~steamtwin.geometry.profile.RowDesign`: mean section, radii and counts in m);
        ValueError naming the spec and listing its :attr:`blade_rows` for a row it has not."""
        from steamtwin.errors import SteamtwinError
        from steamtwin.geometry.profile import row_design

        try:
            return row_design(self.spec, row)
        except (SteamtwinError, ValueError):
            raise ValueError(f"row {row!r} is not a blade row of spec {self.spec.name!r}; its "
                             f"rows: {', '.join(self.blade_rows)}") from None

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters | None = None
                 ) -> pd.DataFrame:
        """The full-order model's outputs for ``inputs`` with the twin's parameters.

        ``inputs``: canonical SI boundary conditions (``main_steam_pressure`` Pa,
        ``main_steam_temperature`` K, ``main_steam_flow`` kg/s, ``hp_exhaust_pressure`` Pa) on
        a time index; returns one row per sample (temperatures K, pressures Pa, power W),
        exactly :meth:`FullOrderModel.simulate` of the spec with :attr:`parameters` (or
        ``params``, e.g. to compare other coefficients with the twin's).
        """
        return self.full_order_model.simulate(inputs, params or self.parameters)

    # -- calibration ------------------------------------------------------------------------

    def calibrate(self, history: History | Sequence[History], *, method: str = "ga",
                  windows: Sequence[str | tuple[pd.Timestamp, pd.Timestamp]] = (),
                  ramps: bool = True, min_steady_s: float = 3600.0,
                  max_steady_s: float = 7200.0, pressure_witness: bool | None = None,
                  sensor_bias: bool = False,
                  priors: Mapping[str, ParameterPrior] | None = DEFAULT_PRIORS,
                  population: int = 50, generations: int = 200, max_evaluations: int = 400,
                  random_state: int = 0, workers: int | None = None, scheduler: Any = None,
                  progress: ProgressCallback | None = None,
                  checkpoint: str | Path | None = None, resume: bool = False) -> Twin:
        """Calibrate the flow, friction and heat-transfer coefficients jointly over one or
        several cleaned histories (:func:`steamtwin.load_history`); returns the twin.

        Windows: the ``windows`` spans (ISO 8601 START/END or timestamp pairs) from every
        history covering them, else the steady holds of ≥ ``min_steady_s`` (s, the last
        ``max_steady_s``) at every load and, with ``ramps``, the load ramps, weighted by load
        band (:mod:`steamtwin.calibration.windowset`). The model reads through the plant's
        sensors (:func:`~steamtwin.model.sensor_setup.sensor_setup`; every history's tag map
        must agree). ``pressure_witness``: also fit the control-stage pressure (None: when
        every history maps it). ``sensor_bias``: integrate out each thermocouple's constant
        bias (IEC 60584-1 class 1). ``method``: ``"ga"`` (population × generations; a
        ``checkpoint`` file, ``resume``) or ``"surrogate"`` (≤ ``max_evaluations`` model runs).
        ``priors`` None: plain RMSE fit, no intervals. Same ``random_state``, same result.
        The calibrator (:class:`~steamtwin.calibration.calibrator.Calibrator`) is
        ``calibrator_``.
        """
        from steamtwin.calibration import (
            Calibrator,
            GeneticSearch,
            ObjectiveSettings,
            SurrogateSearch,
        )
        from steamtwin.calibration.histories import calibration_window_set
        from steamtwin.calibration.settings import THERMOCOUPLE_BIAS

        if method not in ("ga", "surrogate"):
            raise ValueError(f"method must be 'ga' or 'surrogate' (got {method!r})")
        if method == "surrogate" and resume:
            raise ValueError("resume continues a GA run; the surrogate mode has no checkpoint")
        histories = list(history) if isinstance(history, list | tuple) else [history]
        if not histories:
            raise ValueError("calibrate: no history given")
        for item in histories:
            _check_history(item, "calibrate")
        search = (SurrogateSearch(max_evaluations=max_evaluations, population=population)
                  if method == "surrogate" else
                  GeneticSearch(population=population, generations=generations,
                                checkpoint=checkpoint))
        window_set, sensors = calibration_window_set(
            histories, self.spec.design.generator_power, windows=windows, ramps=ramps,
            min_steady_s=min_steady_s, max_steady_s=max_steady_s,
            pressure_witness=pressure_witness)
        model = sensor_model(self.spec, histories)
        _ = model.design_  # the first run compiles the kernels
        objective = ObjectiveSettings(
            sensors=sensors, priors=priors,
            sensor_bias=THERMOCOUPLE_BIAS if sensor_bias else None)
        calibrator = Calibrator(model, objective=objective, search=search,
                                random_state=random_state, workers=workers,
                                scheduler=scheduler, progress=progress)
        initial = Calibrator(model, workers=1).rmse(window_set, ModelParameters())
        calibrator.fit(window_set, resume=resume)
        self.calibrator_ = calibrator
        self._ga_settings = {"population": population, "generations": generations}
        self.windows_ = window_set
        self.model_ = model
        self.sensors_ = sensors
        self.initial_rmse_ = initial
        self.params_ = calibrator.params_
        self.sensor_offsets_ = dict(calibrator.sensor_offsets_)
        self._record(_step(
            "calibrate", method=method, data=[h.historian.source for h in histories],
            windows=len(window_set), samples=int(sum(len(w.data) for w in window_set)),
            sensors=list(sensors), sensor_bias=sensor_bias, random_state=random_state,
            population=population, generations=generations if method == "ga" else None,
            max_evaluations=max_evaluations if method == "surrogate" else None,
            evaluations=int(calibrator.n_evaluations_), rmse_K=float(calibrator.rmse_),
            parameters=asdict(calibrator.params_)))
        return self

    def calibration_report(self, folder: str | Path, *, sensitivity: bool = False,
                           progress: ProgressCallback | None = None) -> list[Path]:
        """Write the calibration's result files into ``folder``; returns their paths.

        Table 6 (RMSE per load band before/after, with the instruments' error; the parameter
        intervals), Figure 7 (GA convergence), Figure 8 (temperatures before/after in the
        window closest to 50 % load, as the method shows it), the identifiability check and,
        with ``sensitivity``, Table 7 (nine more calibrations with the GA settings varied;
        ``progress(fraction, message)`` names it).
        """
        from steamtwin.calibration import Calibrator, GeneticSearch
        from steamtwin.calibration.report import (
            band_rmse_table,
            convergence_figure,
            ga_sensitivity_table,
            parameter_table,
            temperature_comparison_figure,
        )

        if not hasattr(self, "calibrator_"):
            raise TwinError("the twin is not calibrated: call calibrate(history) first")
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        model, window_set, calibrator = self.model_, self.windows_, self.calibrator_
        rated = self.spec.design.generator_power
        windows = [w.data for w in window_set]
        names = [f"window {i + 1}: {w.name}" for i, w in enumerate(window_set)]
        written = [folder / "table6_rmse.csv"]
        band_rmse_table(model, window_set, calibrator.params_,
                        delivered=self.delivered_model if self.offsets else None
                        ).to_csv(written[-1])
        if calibrator.posterior_ is not None:
            written.append(folder / "table6_parameters.csv")
            parameter_table(calibrator.posterior_).to_csv(written[-1])
        if isinstance(calibrator.search_strategy, GeneticSearch):
            written.append(convergence_figure(calibrator.history_,
                                              folder / "figure7_convergence.png"))
        loads = [abs(float(w["load"].mean()) / rated - 0.5) if "load" in w.columns else 0.0
                 for w in windows]
        closest = int(np.argmin(loads))  # the method's Figure 8 is at 50 % load
        written.append(temperature_comparison_figure(
            model, windows[closest], calibrator.params_, folder / "figure8_temperatures.png",
            title=f"Predicted vs measured temperatures, {names[closest]} (Figure 8)"))
        if calibrator.identifiability_ is not None:
            written.append(folder / "identifiability.csv")
            calibrator.identifiability_.to_csv(written[-1])
        if sensitivity:
            if progress is not None:
                progress(0.0, "Table 7: GA settings varied")
            table7 = ga_sensitivity_table(
                lambda s: Calibrator(model, objective=calibrator.objective,
                                     search=GeneticSearch(**s),
                                     random_state=calibrator.random_state,
                                     workers=calibrator.workers,
                                     scheduler=calibrator.scheduler).fit(window_set),
                self._ga_settings)
            written.append(folder / "table7_ga_sensitivity.csv")
            table7.to_csv(written[-1], index=False)
        return written

    def calibrate_online(self, history: History, *, method: str = "ga",
                         store: str | Path | None = None, window_s: float = 3600.0,
                         every_s: float = 1800.0, population: int = 20, generations: int = 8,
                         first_generations: int = 25, random_state: int = 0,
                         workers: int | None = 1, scheduler: Any = None,
                         progress: ProgressCallback | None = None) -> Twin:
        """Keep the parameters current as ``history`` streams in (replayed in one-minute
        chunks), starting from the twin's :attr:`parameters`, the model reading through the
        plant's sensors (:func:`sensor_model`) with the twin's sensor :attr:`offsets`; returns
        the twin, the calibrator in ``online_`` (its ``trajectory_``, ``params_``).

        ``method="ga"``: every ``every_s`` (s of data time) the GA refits the last
        ``window_s`` (s), warm-started (:class:`~steamtwin.calibration.online.OnlineCalibrator`:
        ``population``, ``generations``, ``first_generations``, ``random_state``, ``workers``,
        ``scheduler``, ``progress``). ``method="track"``: a recursive Bayesian filter updated
        every ``every_s`` of new data (:class:`~steamtwin.calibration.tracking.ParameterTracker`;
        σ from the tag map, the default priors centred on the start). ``store``: the live
        parameters file, replaced atomically at every change.
        """
        from steamtwin.calibration.online import OnlineCalibrator, ParameterStore
        from steamtwin.calibration.tracking import ParameterTracker, tracking_sigma

        if method not in ("ga", "track"):
            raise ValueError(f"method must be 'ga' or 'track' (got {method!r})")
        _check_history(history, "calibrate_online")
        model = sensor_model(self.spec, [history])
        if self.offsets:
            model = FullOrderModel(model.spec, sensor_offsets=self.offsets,
                                   sensor_time_constants=model.sensor_time_constants)
        start = self.parameters
        live = ParameterStore(start, path=store)
        if method == "track":
            centred = {name: dataclasses.replace(prior, center=getattr(start, name))
                       for name, prior in DEFAULT_PRIORS.items()}
            self.online_ = ParameterTracker(
                model, sigma=tracking_sigma(history.tag_map), step_s=every_s, priors=centred,
                store=live).run(history.data)
        else:
            self.online_ = OnlineCalibrator(
                model, window_s=window_s, every_s=every_s, population=population,
                generations=generations, first_generations=first_generations,
                random_state=random_state, workers=workers, scheduler=scheduler, store=live,
                progress=progress).run(history.data)
        return self

    # -- ROM --------------------------------------------------------------------------------

    def build_rom(self, mesh: object | None = None, *, row: str = "hp1",
                  element_size: float | None = None, n_snapshots: int = 32,
                  observed: History | None = None, random_state: int = 0,
                  workers: int | None = None,
                  scheduler: str | None = None, progress: ProgressCallback | None = None,
                  **options: Any) -> Twin:
        """Build the blade-temperature POD–RBF ROM with the twin's parameters; returns the twin.

        ``mesh``: the blade's tetrahedral mesh (m); default: the spec's blade ``row`` meshed
        at ``element_size`` (m; None: the mesher's default). ``observed``: a history whose
        conditions widen the snapshots' envelope. ``options``: further arguments of
        :func:`steamtwin.rom.build.build_rom` (``energy``, ``layout``, …).
        """
        from steamtwin.rom.build import build_rom

        given = mesh is not None
        if mesh is None:
            from steamtwin.geometry.meshing import blade_volume_mesh

            mesh = blade_volume_mesh(self.spec, row, element_size=element_size)
        bundle, _ = build_rom(self.spec, mesh, self.parameters, n_snapshots=n_snapshots,
                              max_workers=workers, scheduler=scheduler,
                              random_state=random_state,
                              progress=progress, spec_toml=self._spec_text(),
                              observed=None if observed is None else observed.data, **options)
        self.rom_ = bundle
        self._record(_step("build_rom", row=row,
                           mesh="given" if given else "the spec's exact blade, meshed",
                           n_snapshots=n_snapshots, random_state=random_state,
                           modes=int(bundle.rom.n_modes_),
                           parameters=asdict(self.parameters)))
        return self

    def held_out_fields(self, n_conditions: int, *, random_state: int = 1000,
                        workers: int | None = None,
                        progress: ProgressCallback | None = None) -> Any:
        """The full-order model's steady blade fields (K, on the ROM's mesh, with the ROM's
        parameters) at ``n_conditions`` design-envelope conditions drawn with ``random_state``
        (:func:`~steamtwin.rom.snapshots.design_conditions`): held-out checks of the ROM, for
        :meth:`validate`'s ``field_check`` (Figure 9). Use another ``random_state`` than the
        build's so the conditions are not the snapshots'."""
        from steamtwin.rom.provenance import rom_parameters
        from steamtwin.rom.snapshots import design_conditions, generate_snapshots

        bundle = self._rom_or_error()
        conditions = design_conditions(self.spec, n_conditions, random_state=random_state)
        return generate_snapshots(self.spec, bundle.mesh, conditions, rom_parameters(bundle),
                                  max_workers=workers, progress=progress)

    # -- validation -------------------------------------------------------------------------

    def signals_needed(self, *, monitor: str = "fom", field_check: bool = False
                       ) -> tuple[str, ...]:
        """Signals :meth:`validate` cannot do without: the ROM's inputs, and the FOM's when it
        monitors (``monitor="fom"``) or solves reference fields (``field_check``)."""
        needed = [str(name) for name in self._rom_or_error().rom.input_names_]
        if field_check or monitor == "fom":
            needed += [name for name in INPUT_SIGNALS if name not in needed]
        return tuple(needed)

    def validate(self, history: History, out_dir: str | Path, *,
                 windows: Sequence[str | tuple[pd.Timestamp, pd.Timestamp]]
                 | Mapping[str, str | tuple[pd.Timestamp, pd.Timestamp]] = (),
                 hours: float = 2.0, monitor: str = "fom", sensor_lag: bool = True,
                 field_check: Any = False, settings: Mapping[str, object] | None = None,
                 timings: Mapping[str, float] | None = None,
                 progress: ProgressCallback | None = None, title: str | None = None,
                 extra_sections: Sequence[Any] = ()) -> Any:
        """Replay the twin over measured windows and write the validation report into
        ``out_dir`` (:func:`steamtwin.validation.monitor.validate`); returns the
        :class:`~steamtwin.validation.html.ValidationReport` (also ``validation_``).

        Windows: the ``windows`` spans (a mapping: name → span, the names the report uses),
        else the last ``hours`` (h) of every steady-load span (± 2 % of rated) of at least
        ``hours``; named by mean load unless named. Blade temperatures come
        from the ROM; the steam-path temperatures from the FOM with the ROM's parameters
        (``monitor="fom"``) or the ROM (``"rom"``), either read through the tag map's sensors:
        lags unless ``sensor_lag`` is False, and the twin's sensor offsets. ``field_check``
        True adds the FOM blade field at each window's mean conditions (Figure 9), or give the
        FOM fields to compare with (e.g. :meth:`held_out_fields`). ``settings`` and
        ``timings`` (stage → s) of the caller head the report's own, ``extra_sections``
        (:mod:`steamtwin.validation.html` sections) follow it, ``title`` replaces its title;
        ``progress(fraction, message)`` names the stage.
        """
        from steamtwin.dcs.windows import name_windows
        from steamtwin.validation.monitor import validate as run_validation
        from steamtwin.validation.replay import WARM_UP_S, replay_span
        from steamtwin.validation.tables import quality_section

        if monitor not in ("fom", "rom"):
            raise ValueError(f"--monitor must be 'fom' or 'rom' (got {monitor!r})")
        _check_history(history, "validate")
        bundle = self._rom_or_error()
        solve_fields = field_check is True
        missing = [name for name in self.signals_needed(monitor=monitor,
                                                        field_check=solve_fields)
                   if name not in history.data.columns]
        if missing:
            raise ValueError(f"{history.historian.source}: signal(s) {missing} are needed but "
                             f"not in the data; map them in {history.tag_map.source}")
        timings = dict(timings or {})
        clock = time.perf_counter()
        rated = self.spec.design.generator_power
        if not windows and "load" not in history.data.columns:
            raise ValueError("no --window given and the data have no 'load' signal, which the "
                             "search for steady windows needs; map the generator load in the "
                             "tag map or pass --window START/END")
        duration = hours * 3600.0
        spans = list(windows.values()) if isinstance(windows, Mapping) else list(windows)
        picked = history.windows(rated, given=spans, min_steady_s=duration,
                                 max_steady_s=duration, tolerance=STEADY_TOLERANCE, ramps=False)
        if not picked:
            raise ValueError(f"no steady-load span of {hours:g} h found in the data; pass "
                             "--window START/END")
        zone = history.tag_map.time_zone
        frames = [w.data.set_axis(w.data.index.tz_convert(zone)) if zone else w.data
                  for w in picked]
        named = (dict(zip(windows, frames, strict=True)) if isinstance(windows, Mapping)
                 else name_windows(frames, rated))
        _check_windows(bundle, named)
        timings["window selection"] = time.perf_counter() - clock
        reference = None if field_check is False else field_check
        if solve_fields:
            clock = time.perf_counter()
            if progress is not None:
                progress(0.2, "solving the FOM blade field at each window's conditions")
            reference = _reference_fields(bundle, self.spec, named)
            timings["FOM blade fields (Figure 9)"] = time.perf_counter() - clock
        offsets = self.offsets
        report_settings = {
            **(settings or {}),
            "windows from": "--window" if windows else (
                f"steady load (± {STEADY_TOLERANCE:.0%} of rated {rated / 1e6:g} MW) over "
                f"≥ {hours:g} h, the last {hours:g} h of each span"),
            "samples read": len(history.data),
            "sensor offsets (measured − model)": ", ".join(
                f"{name} {value:+.2f} K" for name, value in offsets.items())
            or "none (--params without sensor_offsets, or not given)",
        }
        if progress is not None:
            progress(0.5, "monitoring the windows and writing the report")
        simulator = monitoring_model(self.spec, monitor, sensor_lag, history.tag_map, offsets)
        replay_over = None if simulator is None else replay_span(history.data, frames)
        if replay_over is not None:
            report_settings["model runs"] = (
                f"one continuous run from {replay_over.index[0]} (up to "
                f"{WARM_UP_S / 3600:g} h before the first window): the metal's and the "
                "thermowells' state carried through the ramps between the windows")

        def monitored(replay_over: pd.DataFrame | None) -> Any:
            return run_validation(
                bundle, named, out_dir, settings=report_settings, timings=timings,
                field_check=reference, time_zone=zone, simulator=simulator,
                sensors=rom_sensors(self.spec, monitor, sensor_lag, history.tag_map, offsets),
                replay_over=replay_over,
                extra_sections=[quality_section(history.report, "Data quality of the export "
                                                "(whole file, before windowing)"),
                                *extra_sections],
                **({} if title is None else {"title": title}))

        try:
            report = monitored(replay_over)
        except InputError as error:
            if replay_over is None:
                raise
            # a row the model cannot take (a trip, a start-up between the windows): each
            # window is then run on its own, from steady state, and the report says so (a
            # row inside a window stops that run too, and its error is raised there)
            report_settings["model runs"] = (
                "each window from steady state at its first sample: the continuous run "
                f"stopped at a row the model cannot take ({error})")
            warnings.warn(f"validate: {report_settings['model runs']}", stacklevel=2)
            report = monitored(None)
        self.validation_ = report
        self._record(_step("validate", data=history.historian.source, windows=list(named),
                           monitor=monitor, report=str(out_dir)))
        return report

    # -- files ------------------------------------------------------------------------------

    def save(self, directory: str | Path) -> Path:
        """Write the twin into one folder (:mod:`steamtwin.twinfile`); returns the folder.

        TwinError when the spec's TOML text is unknown (a spec built in Python: give
        ``spec_toml``)."""
        from steamtwin.rom.romfile import save_rom

        folder = Path(directory)
        folder.mkdir(parents=True, exist_ok=True)
        written = [folder / SPEC_FILE]
        written[0].write_text(self._spec_text(), encoding="utf-8")
        params_path = folder / PARAMS_FILE
        if hasattr(self, "calibrator_"):
            written += self.calibrator_.save(params_path)
        elif getattr(self, "_params_text", None) is not None:
            params_path.write_text(self._params_text, encoding="utf-8")
            written.append(params_path)
        else:
            written.append(write_parameters_file(params_path, self.parameters, self.offsets))
        if self.blade_rom is not None:
            written.append(save_rom(self.blade_rom, folder / ROM_FILE))
        if hasattr(self, "windows_"):
            (folder / REPORTS).mkdir(exist_ok=True)
            written.append(folder / REPORTS / "calibration_windows.csv")
            self.windows_.summary().to_csv(written[-1], index=False)
        if hasattr(self, "validation_"):
            target = folder / REPORTS / "validation"
            self.validation_.write(target)
            written += sorted(p for p in target.rglob("*") if p.is_file())
        write_manifest(folder, written, self.spec, self.parameters, self.steps)
        return folder

    @classmethod
    def load(cls, directory: str | Path) -> Twin:
        """Read a twin folder :meth:`save` wrote, checking every file against ``twin.json``
        and the ROM against the spec and parameters (TwinError naming the file otherwise)."""
        parts = read_folder(directory)
        twin = cls(parts.spec, parts.params, rom=parts.rom, spec_toml=parts.spec_text,
                   sensor_offsets=parts.offsets,
                   provenance=[*parts.provenance, _step("load", folder=str(directory))])
        twin._params_text = parts.params_text
        return twin

    # -- helpers ----------------------------------------------------------------------------

    def _spec_text(self) -> str:
        text = self.spec_toml if self.spec_toml is not None else builtin_spec_text(self.spec)
        if text is None:
            raise TwinError(f"turbine {self.spec.name!r}: its TOML text is unknown; build the "
                            "twin with Twin.from_spec(path) or give spec_toml")
        return text

    def _rom_or_error(self) -> BladeRom:
        if self.blade_rom is None:
            raise TwinError("the twin has no blade ROM: call build_rom(...) or give rom=")
        return self.blade_rom

    def __repr__(self) -> str:
        p = self.parameters
        rom = "ROM" if self.blade_rom is not None else "no ROM"
        return (f"Twin({self.spec.name!r}, flow {p.flow_coefficient:.4f}, friction "
                f"{p.friction_coefficient:.4f}, heat transfer "
                f"{p.heat_transfer_coefficient:.4f}, {rom})")


def _step(name: str, **details: Any) -> dict[str, Any]:
    """One provenance entry: the step, when (UTC), with what."""
    return {"step": name, "time": datetime.now(UTC).isoformat(timespec="seconds"), **details}


def _check_history(history: object, method: str) -> None:
    if not isinstance(history, History):
        raise TypeError(f"Twin.{method} takes histories from steamtwin.load_history(path, "
                        f"tag_map) (got {type(history).__name__})")


def sensor_model(spec: TurbineSpec, histories: Sequence[History]) -> FullOrderModel:
    """The FOM read through the plant's sensors as every mode reads it
    (:func:`~steamtwin.model.sensor_setup.sensor_setup`: the tag map's time constants and
    thermocouple depth, typical thermowells' otherwise); every history's tag map must agree."""
    setups = [sensor_setup(spec, history.tag_map) for history in histories]
    for history, setup in zip(histories[1:], setups[1:], strict=True):
        if setup != setups[0]:
            raise ValueError(
                f"the tag maps {histories[0].tag_map.source} and {history.tag_map.source} give "
                "different sensor time constants or thermocouple depths; one calibration runs "
                "one model: give the files' sensors the same time_constant and depth")
    return setups[0].model(spec)


def monitoring_model(spec: TurbineSpec, monitor: str, sensor_lag: bool, tag_map: TagMap | None,
                     offsets: dict[str, float]) -> FullOrderModel | None:
    """The FOM that monitors the steam path (None: the ROM does), read through the plant's
    sensors (:func:`~steamtwin.model.sensor_setup.sensor_setup`) and the calibration's sensor
    ``offsets`` (K)."""
    if monitor != "fom":
        return None
    setup = dataclasses.replace(sensor_setup(spec, tag_map), offsets=offsets)
    if not sensor_lag:
        return FullOrderModel(setup.spec_for(spec), sensor_offsets=offsets or None)
    return setup.model(spec)


def rom_sensors(spec: TurbineSpec, monitor: str, sensor_lag: bool, tag_map: TagMap | None,
                offsets: dict[str, float]) -> SensorSetup | None:
    """The sensors the ROM's steady temperatures are read through when the ROM monitors
    (None when the FOM does: it reads through its own): the tag map's lags unless
    ``sensor_lag`` is False, and the calibration's ``offsets`` (K)."""
    if monitor != "rom":
        return None
    if not sensor_lag:
        return SensorSetup({}, {}, offsets=offsets)
    return dataclasses.replace(sensor_setup(spec, tag_map), offsets=offsets)


def _check_windows(bundle: BladeRom, windows: Mapping[str, pd.DataFrame]) -> None:
    """Every window needs at least one sample with all ROM inputs present."""
    inputs = [str(name) for name in bundle.rom.input_names_]
    for name, frame in windows.items():
        if not np.isfinite(frame[inputs].to_numpy(dtype=float)).all(axis=1).any():
            raise ValueError(f"window {name!r} ({frame.index[0]} … {frame.index[-1]}): no "
                             f"sample has all ROM inputs {inputs} valid")


def _reference_fields(bundle: BladeRom, spec: TurbineSpec,
                      windows: Mapping[str, pd.DataFrame]) -> Any:
    """FOM blade fields at each window's mean boundary conditions, with the ROM's parameters."""
    from steamtwin.rom.provenance import rom_parameters
    from steamtwin.rom.snapshots import generate_snapshots

    conditions = pd.DataFrame([frame[list(INPUT_SIGNALS)].mean() for frame in windows.values()])
    if conditions.isna().any().any():
        raise ValueError("--field-check: a window has no valid sample of "
                         f"{list(INPUT_SIGNALS)}")
    return generate_snapshots(spec, bundle.mesh, conditions, rom_parameters(bundle),
                              max_workers=1)
