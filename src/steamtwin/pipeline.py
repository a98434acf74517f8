"""The end-to-end run behind ``steamtwin demo``, stage by stage, on the Python API.

Every stage goes through the calls a Python user makes — :class:`steamtwin.Twin`
(``from_spec``, ``simulate``, ``calibrate``, ``build_rom``, ``held_out_fields``, ``validate``,
``save``) and :func:`steamtwin.load_history` on the virtual plant's historian files — on any
turbine spec (built-in name or TOML path) and blade row. Stages (each timed; every number in the
report is computed in the run):

1. **Full-order model**: design point against the spec's heat balance, the off-design line at
   30/50/75/100 % load, a 100 → 30 % ramp with three heat-transfer settings.
2. **Geometry**: virtual scan of the blade row → cleaning and registration → B-spline surface
   → watertight STL → deviation and row metrics against the exact blade → tetrahedral mesh of
   the *reconstructed* blade (the mesh the blade ROM is built on) → the scan-uncertainty study
   per row (±0.05 mm → the row's throat → its stage → HP-exhaust temperature; hp1 and hp13).
3. **Virtual plant** (the built-in reference unit's: the plant stages need that spec): the
   ``deep-peak-30`` and ``deep-peak-50`` runs (10 min at 100 %, ramp at 3 %/min, hold) for
   calibration, and a ``day`` of load following with the same instruments (same seed: same
   sensor errors, another day) for validation; written as historian files and read back with
   :func:`~steamtwin.dcs.history.load_history` (cleaned as the DCS layer does: spikes and
   out-of-range samples rejected and counted, nothing filled).
4. **Calibration** (:meth:`Twin.calibrate`) on both deep-peak runs, ramps and holds:
   surrogate-assisted by default, the method's GA (P 50 × G 200) in full mode; Table 6 on the
   two holds, Figure 8, the identifiability check; Table 7 and Figure 7 from GA runs (quick
   mode: G = 10 on windows thinned to 10 s, stated in the report).
5. **Blade ROM** (:meth:`Twin.build_rom`) on the reconstructed mesh with the calibrated
   parameters; Figure 9 and its errors at held-out conditions the ROM was not built on.
6. **Monitoring** (:meth:`Twin.validate`): the day run's 30 % and 50 % holds (data neither
   the calibration nor the ROM saw): Table 5, Table 8, Figure 10.
7. **Rotor life** (:func:`steamtwin.rotor.report.rotor_stress`): the HP rotor's thermal stress
   and the life it consumed over the day run, with the twin's (calibrated) parameters; its own
   report in ``rotor/`` (with the fitted model, ``rotor-model.npz``), the life table and two
   figures in the demo's.
8. **Sensitivity**: Sobol' indices of the three parameters on the 50 % run's ramp, and the
   propagation of main-steam temperature noise (σ = 0.5 and 1.0 K) on the 50 % hold.
9. **Live twin**: a deep-peak-50 run published over OPC UA on loopback and read by the live
   service (gate, streamed FOM, blade ROM probes, the rotor model of stage 7, residuals, DuckDB)
   with the dashboard served beside it; a screenshot of each page in the report.

:func:`run_demo` writes everything into one folder: the twin (:meth:`Twin.save`: ``spec.toml``,
``params.json``, ``rom.npz``, ``twin.json``) and ``report.html``/``report.json``; the library
never prints — progress goes to a :data:`~steamtwin.progress.ProgressCallback`.

(Over 500 lines for a reason: one function per stage, in the order of the run, so the report's
chain reads top to bottom in one file; what a stage computes lives in the library it calls.)
"""

from __future__ import annotations

import asyncio
import json
import socket
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from steamtwin.calibration import Calibrator, GeneticSearch
from steamtwin.calibration.evaluation import make_evaluator
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.calibration.report import (
    convergence_figure,
    ga_sensitivity_table,
    rmse_table,
    temperature_comparison_figure,
)
from steamtwin.dcs.history import History, load_history
from steamtwin.dcs.plant import PlantRun, plant_tag_map, run_plant, write_plant
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.config import ServiceConfig, SourceConfig, UnitConfig
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.plant_server import PlantServer, PlantServerSettings, plant_node_ids
from steamtwin.live.runner import run_service
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.parameters import ModelParameters
from steamtwin.progress import ProgressCallback
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rotor.report import MODEL_FILE, life_table, rotor_stress
from steamtwin.spec import TurbineSpec, load_spec
from steamtwin.spec.fingerprint import spec_hash
from steamtwin.twin import Twin
from steamtwin.twinfile import write_parameters_file
from steamtwin.validation.html import (
    FigureSection,
    NotesSection,
    Section,
    TableSection,
    ValidationReport,
)
from steamtwin.validation.noise import noise_figure, noise_propagation
from steamtwin.validation.sensitivity import sobol_indices
from steamtwin.validation.tables import quality_section

__all__ = ["STAGES", "DemoResult", "DemoSettings", "run_demo"]

STAGES: tuple[str, ...] = (
    "full-order model", "geometry", "virtual plant", "calibration", "GA sensitivity (Table 7)",
    "blade ROM", "rotor life", "Sobol indices and noise propagation", "live twin",
    "monitoring and report",
)
"""Stage names in order; each progress message starts with its stage's name."""

#: Stage → the stages it needs. "monitoring and report" always runs (it writes the report);
#: it monitors when the virtual plant and the blade ROM ran. The blade ROM is built on the
#: reconstructed mesh when the geometry stage ran, else on the exact blade's.
NEEDS: dict[str, tuple[str, ...]] = {
    "calibration": ("virtual plant",),
    "GA sensitivity (Table 7)": ("calibration",),
    "Sobol indices and noise propagation": ("virtual plant",),
    "rotor life": ("virtual plant",),
}
#: Stages on the virtual plant, which simulates the built-in reference unit.
PLANT_STAGES = ("virtual plant", "calibration", "GA sensitivity (Table 7)", "rotor life",
                "Sobol indices and noise propagation", "live twin")

VALIDATION_LOADS = (0.30, 0.50)
#: Rows of the demo's scan-uncertainty study, each through its own stage.
UNCERTAINTY_ROWS = ("hp1", "hp13")


@dataclass(frozen=True)
class DemoSettings:
    """Sizes of the demo's stages. :meth:`quick` (the default), :meth:`full` (the method's).

    ``spec``: a built-in turbine's name or a spec TOML path; ``row``: the blade row scanned,
    reconstructed and modelled by the ROM (one of the spec's :attr:`Twin.blade_rows`, checked
    by :func:`run_demo`); ``stages``: the stages to run (:data:`STAGES`; each with the stages
    it needs, :data:`NEEDS`; the plant stages need the reference unit's spec).
    """

    mode: str = "quick"
    spec: str | Path = "reference"
    row: str = "hp1"
    stages: tuple[str, ...] = STAGES
    hold_hours: float = 2.0  # h, the holds of the plant runs and the validation windows
    scan_points: int = 60_000  # virtual scan, all views
    mesh_element_size: float | None = None  # m; None: the mesher's default for the blade
    uncertainty_samples: int = 10
    calibration: str = "surrogate"  # or "ga"
    evaluations: int = 150  # model runs of the surrogate calibration
    population: int = 50
    generations: int = 200
    table7_generations: int = 10
    table7_thinning_s: int = 10  # s, sample spacing of the Table-7 windows (1: as measured)
    snapshots: int = 16
    held_out: int = 4  # FOM fields at conditions the ROM was not built on (Figure 9)
    sobol_n_base: int = 64
    noise_repeats: int = 2
    random_state: int = 0
    workers: int | None = None  # local processes; None: every core

    @classmethod
    def quick(cls, **changes: object) -> DemoSettings:
        """Minutes on two cores: surrogate calibration, 16 snapshots, small Table 7 and Sobol."""
        return replace(cls(), **changes)

    @classmethod
    def full(cls, **changes: object) -> DemoSettings:
        """The method's settings: GA P 50 × G 200, 32 snapshots, ~200k-node mesh, 150k-point
        scan, Table 7 at G = 200 on the 1-s windows, Sobol N = 256 (hours on two cores)."""
        return replace(cls(mode="full", scan_points=150_000, mesh_element_size=0.65e-3,
                           uncertainty_samples=20, calibration="ga", table7_generations=200,
                           table7_thinning_s=1, snapshots=32, held_out=8, sobol_n_base=256,
                           noise_repeats=4), **changes)

    def __post_init__(self) -> None:
        if self.calibration not in ("surrogate", "ga"):
            raise ValueError(f"calibration must be 'surrogate' or 'ga' (got {self.calibration!r})")
        if not 0.05 <= self.hold_hours <= 12.0:
            raise ValueError(f"hold_hours must lie within [0.05, 12] h (got {self.hold_hours})")
        positive = ("scan_points", "uncertainty_samples", "evaluations", "population",
                    "generations", "table7_generations", "table7_thinning_s", "snapshots",
                    "held_out", "sobol_n_base", "noise_repeats")
        bad = [name for name in positive if int(getattr(self, name)) < 1]
        if bad:
            raise ValueError(f"{bad} must be ≥ 1")
        if self.held_out < 4 or self.snapshots < 4:
            raise ValueError("snapshots and held_out must be ≥ 4 (one per load level)")
        unknown = [stage for stage in self.stages if stage not in STAGES]
        if unknown:
            raise ValueError(f"stages {unknown} unknown; the demo's stages: {list(STAGES)}")
        for stage in self.stages:
            lacking = [need for need in NEEDS.get(stage, ()) if need not in self.stages]
            if lacking:
                raise ValueError(f"stage {stage!r} needs {lacking}: add it to stages")
        ordered = tuple(stage for stage in STAGES
                        if stage in self.stages or stage == "monitoring and report")
        object.__setattr__(self, "stages", ordered)

    def twin(self) -> Twin:
        """The twin of :attr:`spec`, with :attr:`row` and the plant stages checked against it
        (ValueError listing the spec's rows, or the stages the spec can run)."""
        twin = Twin.from_spec(self.spec)
        twin.blade_design(self.row)
        plant = [stage for stage in self.stages if stage in PLANT_STAGES]
        if plant and spec_hash(twin.spec) != spec_hash(load_spec("reference")):
            raise ValueError(
                f"stages {plant} run the virtual plant, which simulates the built-in reference "
                f"unit, not spec {twin.spec.name!r} ({self.spec}); leave them out (stages="
                f"{[s for s in self.stages if s not in PLANT_STAGES]})")
        return twin


@dataclass
class DemoResult:
    """What a run produced: the report (``report.html``, ``report.json`` in ``out``), the
    twin (saved in ``out``), its parameters, the tables by name and the stage timings (s)."""

    out: Path
    report: ValidationReport
    params: ModelParameters
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    twin: Twin | None = None


class _Clock:
    """Stage timings, and the run's progress: each stage an equal share of [0, 1], each
    message starting with the stage's name."""

    def __init__(self, progress: ProgressCallback | None, stages: tuple[str, ...]) -> None:
        self.timings: dict[str, float] = {}
        self.progress = progress
        self.stages = stages

    @contextmanager
    def stage(self, name: str) -> Iterator[Callable[..., None]]:
        start = time.perf_counter()
        index = self.stages.index(name)

        def report(fraction: float, message: str = "") -> None:
            if self.progress is not None:
                done = (index + min(max(float(fraction), 0.0), 1.0)) / len(self.stages)
                self.progress(done, f"{name}: {message}" if message else name)

        report(0.0)
        yield report
        self.timings[name] = time.perf_counter() - start
        report(1.0)


def run_demo(out: str | Path, settings: DemoSettings | None = None,
             progress: ProgressCallback | None = None) -> DemoResult:
    """Run the selected stages (all by default) on ``settings.spec`` and ``settings.row`` and
    write the twin and the report into ``out``.

    ``progress(fraction, message)``: the share of the run done (each stage an equal part) and
    a message starting with the stage's name (:data:`STAGES`). ValueError before any work for
    an unknown row (listing the spec's rows) or plant stages on another spec than the
    reference unit's.
    """
    settings = settings or DemoSettings.quick()
    twin = settings.twin()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    clock = _Clock(progress, settings.stages)
    run = set(settings.stages)
    sections: list[Section] = []
    messages: list[str] = []
    plant = mesh = reference = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", IdentifiabilityWarning)
        warnings.simplefilter("always", ExtrapolationWarning)
        if "full-order model" in run:
            with clock.stage("full-order model") as report:
                sections += _model_stage(twin, out, report)
        if "geometry" in run:
            with clock.stage("geometry") as report:
                mesh, geometry_sections = _geometry_stage(twin.spec, twin.full_order_model,
                                                          settings, out, report)
                sections += geometry_sections
        if "virtual plant" in run:
            with clock.stage("virtual plant") as report:
                plant = _plant_stage(settings, out, report)
                sections += plant.sections
        if "calibration" in run:
            with clock.stage("calibration") as report:
                sections += _calibration_stage(twin, plant, settings, out, report)
        if "GA sensitivity (Table 7)" in run:
            with clock.stage("GA sensitivity (Table 7)") as report:
                sections += _table7_stage(twin, plant, settings, out, report)
        if "blade ROM" in run:
            with clock.stage("blade ROM") as report:
                reference = _rom_stage(twin, mesh, settings, report,
                                       held_out="virtual plant" in run)
        if "rotor life" in run:
            with clock.stage("rotor life") as report:
                sections += _rotor_stage(twin, plant, out, report)
        if "Sobol indices and noise propagation" in run:
            with clock.stage("Sobol indices and noise propagation") as report:
                sections += _sensitivity_stage(twin, plant, settings, out, report)
        if "live twin" in run:
            with clock.stage("live twin") as report:
                sections += _live_stage(twin, settings, out, report,
                                        instruments=None if plant is None else plant.instruments)
        with clock.stage("monitoring and report") as report:
            twin.save(out)
            for warning in caught:
                messages.append(f"{warning.category.__name__}: {warning.message}")
            if messages:
                sections.append(NotesSection("Warnings raised during the run", tuple(messages)))
            result = _report(twin, plant, reference, sections, settings, clock.timings, out)
            report(1.0)
    result.timings = {**result.timings, **clock.timings}  # the last stage's time included
    result.write(out)
    return DemoResult(out=out, report=result, params=twin.parameters, tables=result.tables,
                      timings=dict(clock.timings), warnings=messages, twin=twin)


def _report(twin: Twin, plant: _PlantData | None, reference: object, sections: list[Section],
            settings: DemoSettings, timings: dict[str, float], out: Path) -> ValidationReport:
    """The monitoring replay of the day run's holds (:meth:`Twin.validate`) heading the
    stages' sections; without the plant or the ROM, those sections alone."""
    title = f"steamtwin demo: {twin.spec.name}, blade {settings.row}, end to end"
    header = {**asdict(settings), "turbine": twin.spec.name}
    if plant is None or twin.blade_rom is None:
        report = ValidationReport(title, settings=header, timings=dict(timings))
        for section in sections:
            report.add(section)
        return report
    return twin.validate(
        plant.validation, out, windows=plant.validation_spans, hours=settings.hold_hours,
        field_check=reference if reference is not None else False, title=title,
        settings={**header,
                  "calibration data": "deep-peak-30 and deep-peak-50 runs (ramp + "
                  f"{settings.hold_hours:g}-h hold), instruments seed {settings.random_state}",
                  "validation data": f"day run, last {settings.hold_hours:g} h of the "
                  "30 % and 50 % holds, same instruments"},
        timings=timings, extra_sections=sections)


# ------------------------------------------------------------------------------------------
# live twin


LIVE_HOURS = 0.1
"""Length of the live stage's hold (h): the deep-peak-50 ramp and a short hold, over OPC UA."""


LIVE_WAIT_S = 120.0
"""The longest the live stage waits for the service to store what the plant published (s)."""
LOOK_AHEAD_SAMPLES = 61 + 60
"""Samples the streaming gate may still hold when the stage stops: its 60-s look-ahead and
one, and the open 60-s clock bin it judges whole."""


def _instruments(random_state: int) -> pd.DataFrame:
    """The virtual plant's instruments (calibration errors, drift rates) that the plant stage
    draws with ``random_state``: every run of one seed has the same ones (``measure``)."""
    return run_plant("deep-peak-50", hours=LIVE_HOURS, random_state=random_state).injected.sensors


def _stored(database: Path) -> int:
    """Samples the live service has committed so far (its database, read beside the writer)."""
    if not database.exists():
        return 0
    with LiveHistorian(database) as historian:
        return historian.connection.execute(
            "SELECT count(DISTINCT time) FROM series").fetchone()[0]


def _live_stage(twin: Twin, settings: DemoSettings, out: Path, report: Callable[..., None],
                instruments: pd.DataFrame | None = None) -> list[Section]:
    """The virtual plant published over OPC UA on loopback, the live service reading it with
    the calibrated parameters (and the blade ROM, when built) into ``out/live.duckdb`` and
    serving the dashboard on a free loopback port: what was stored, what the twin said, and a
    screenshot of each dashboard page (``out/dashboard/``) once the run is stored."""
    # imported here: the web service (FastAPI, uvicorn) loads only when this stage runs
    from steamtwin.rom.romfile import save_rom
    from steamtwin.web.screenshots import DASHBOARD_PAGES, dashboard_sections, screenshot_pages
    from steamtwin.web.server import HttpSettings, http_companion

    # the plant's own instruments (calibration errors the twin was calibrated against) on a
    # new run: noise and faults drawn anew; without the plant stage's record, its seed's
    run = run_plant("deep-peak-50", hours=LIVE_HOURS, random_state=settings.random_state + 1000,
                    instruments=instruments if instruments is not None
                    else _instruments(settings.random_state))
    report(0.3)
    tags = out / "live-tags.toml"
    write_tag_map(plant_node_ids(plant_tag_map()), tags)
    params_path = out / "live-params.json"
    write_parameters_file(params_path, twin.parameters, twin.offsets)  # the offsets too
    with socket.socket() as probe:  # a free loopback port
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server_settings = PlantServerSettings(port=port, speed=None)
    database = out / "live.duckdb"
    database.unlink(missing_ok=True)
    rom_path = None if twin.blade_rom is None else save_rom(twin.blade_rom, out / "live-rom.npz")
    # the rotor model the rotor stage fitted (and its allowable), when that stage ran
    rotor_path, rotor_allowable = out / "rotor" / MODEL_FILE, None
    if rotor_path.is_file():
        life = json.loads((out / "rotor" / "rotor_life.json").read_text(encoding="utf-8"))
        rotor_allowable = float(life["allowable_pa"])
    config = ServiceConfig(database=database, source=out / "live (demo)", units=(UnitConfig(
        name="unit1", turbine=str(settings.spec), tags=tags, params=params_path, rom=rom_path,
        block_samples=60, source=SourceConfig("opcua", endpoint=server_settings.endpoint,
                                              allow_insecure=True),
        rotor=rotor_path if rotor_path.is_file() else None, rotor_allowable=rotor_allowable),))
    bound: dict[str, int] = {}
    unit_pages = [page for page in DASHBOARD_PAGES if page.name != "Fleet"  # one unit
                  and (page.name != "Rotor" or rotor_allowable is not None)]
    dashboard = http_companion(HttpSettings(port=0), config,
                               on_bound=lambda _host, http_port: bound.update(port=http_port))

    async def live() -> tuple[dict, list]:
        stop = asyncio.Event()
        async with PlantServer(run.measured, plant_tag_map(), server_settings) as server:
            service = asyncio.create_task(run_service(config, stop, companions=[dashboard]))
            await server.wait_for_subscribers(len(plant_tag_map().signals))
            await server.publish()
            # until every sample but the gate's last look-ahead minute is stored (on a loaded
            # machine a fixed wait stopped the service early), at most LIVE_WAIT_S
            deadline = time.perf_counter() + LIVE_WAIT_S
            while (_stored(database) < len(run.measured) - LOOK_AHEAD_SAMPLES
                   and time.perf_counter() < deadline and not service.done()):
                await asyncio.sleep(0.25)
            # the dashboard as the run left it, drawn by the service still serving (in a
            # thread: the service's loop answers the browser meanwhile)
            shots = await asyncio.to_thread(screenshot_pages, f"http://127.0.0.1:{bound['port']}",
                                            "unit1", out / "dashboard", unit_pages)
            stop.set()
            return await service, shots

    clock = time.perf_counter()
    summaries, shots = asyncio.run(live())
    summary = summaries["unit1"]
    elapsed = time.perf_counter() - clock
    report(0.9)
    with LiveHistorian(database) as historian:
        wide = historian.series("unit1")
    exhaust = wide.get("residual/hp_exhaust_temperature", pd.Series(dtype=float)).dropna()
    table = pd.DataFrame({
        "quantity": ["samples published over OPC UA", "samples stored", "without a twin value "
                     "(an input the gate rejected)", "source and gate findings",
                     "HP-exhaust residual, mean abs (K)", "HP-exhaust residual, max abs (K)",
                     "wall time of the live stage (s)", "of which dashboard screenshots (s)"],
        "value": [len(run.measured), summary.samples, summary.without_twin, summary.findings,
                  float(exhaust.abs().mean()) if len(exhaust) else float("nan"),
                  float(exhaust.abs().max()) if len(exhaust) else float("nan"), elapsed,
                  sum(shot.seconds for shot in shots)]})
    report(1.0)
    note = ("The live service's dashboard (`steamtwin serve --http-port`) at 1366 × 768, "
            "taken while the service still ran, after the plant's run was stored; the unit "
            "steps the rotor model of the rotor stage (Rotor page). The Fleet "
            "page is not shown: with one unit it forwards to that unit's page. The Calibration "
            "page shows the parameters the unit started with (reason \"start\"); no swap "
            "follows: this unit runs without recalibration.")
    return [TableSection("live_twin", table, "Live twin: the virtual plant's deep-peak-50 run "
                         "published over OPC UA on 127.0.0.1 (asyncua, no security: a test plant) "
                         "and read by `steamtwin serve`'s runner with the calibrated parameters — "
                         "gate, streamed full-order model, residuals, DuckDB (live.duckdb); the "
                         "last minute waits for the gate's look-ahead when the stage stops"),
            *dashboard_sections(shots, note)]




# ------------------------------------------------------------------------------------------
# 1. full-order model


def _model_stage(twin: Twin, out: Path, report: Callable[..., None]) -> list[Section]:
    spec, model = twin.spec, twin.full_order_model
    design = model.simulate_detailed(model.design_inputs(), stages=False).diagnostics.iloc[0]
    heat_balance = spec.design
    check = pd.DataFrame([
        {"quantity": "control-stage pressure (MPa)",
         "spec": heat_balance.control_stage_pressure / 1e6,
         "model": design.control_stage_pressure / 1e6},
        {"quantity": "HP-exhaust temperature (°C)",
         "spec": heat_balance.hp_exhaust_temperature - 273.15,
         "model": design.hp_exhaust_temperature - 273.15},
        {"quantity": "HP power (MW)", "spec": heat_balance.hp_power / 1e6,
         "model": design.hp_power / 1e6},
    ])
    check["difference"] = check["model"] - check["spec"]
    report(0.3, "design point")
    loads = [0.30, 0.50, 0.75, 1.00]
    line = pd.concat(  # each load its own run: a steady state, metal in equilibrium
        [model.simulate_detailed(load_profile_inputs(spec, [load]), stages=False).diagnostics
         for load in loads], ignore_index=True)
    line.insert(0, "load_fraction", loads)
    report(0.6, "off-design line")
    ramp_inputs = load_profile_inputs(spec, ramp_profile(1.0, 0.3, 0.03, 600.0, 7200.0))
    ramps = {h: twin.simulate(ramp_inputs, ModelParameters(heat_transfer_coefficient=h))
             for h in (0.5, 1.0, 2.0)}
    figure = _ramp_figure(ramp_inputs, ramps, out / "ramp_simulation.png", spec.name)
    return [
        TableSection("design_point", check, "Design point of the full-order model against the "
                     "spec's heat balance"),
        TableSection("off_design_line", _off_design_table(line), "Off-design line along the "
                     "sliding-pressure line (steady states)"),
        FigureSection(figure, "Ramp 100 → 30 % load at 3 %/min with three heat-transfer "
                      "coefficients: the metal's lag (full-order model)"),
    ]


def _off_design_table(line: pd.DataFrame) -> pd.DataFrame:
    """The off-design line in the units engineers read (MPa, °C, MW)."""
    return pd.DataFrame({
        "load_fraction": line["load_fraction"],
        "control_stage_pressure_MPa": line["control_stage_pressure"] / 1e6,
        "control_stage_temperature_degC": line["control_stage_temperature"] - 273.15,
        "hp_exhaust_temperature_degC": line["hp_exhaust_temperature"] - 273.15,
        "hp_inner_casing_temperature_degC": line["hp_inner_casing_temperature"] - 273.15,
        "hp_power_MW": line["hp_power"] / 1e6,
        "control_stage_efficiency": line["control_stage_efficiency"],
        "active_admission_arc": line["active_admission_arc"],
    })


def _ramp_figure(inputs: pd.DataFrame, runs: dict[float, pd.DataFrame], path: Path,
                 turbine: str) -> Path:
    minutes = (inputs.index - inputs.index[0]).total_seconds() / 60.0
    figure = Figure(figsize=(9, 9))
    axes = figure.subplots(3, 1, sharex=True)
    axes[0].plot(minutes, inputs["main_steam_flow"] * 3.6, color="black")
    axes[0].set_ylabel("main-steam flow (t/h)")
    for multiplier, outputs in runs.items():
        label = f"heat-transfer coefficient × {multiplier:g}"
        axes[1].plot(minutes, outputs["hp_exhaust_temperature"] - 273.15, label=label)
        axes[2].plot(minutes, outputs["hp_inner_casing_temperature"] - 273.15, label=label)
    axes[1].set_ylabel("HP-exhaust steam (°C)")
    axes[2].set_ylabel("inner-casing metal (°C)")
    axes[2].set_xlabel("time (min)")
    axes[2].legend()
    figure.suptitle(f"{turbine}: ramp 100 % → 30 % load at 3 %/min (full-order model)")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    return path


# ------------------------------------------------------------------------------------------
# 3. virtual plant


@dataclass
class _PlantData:
    calibration: dict[str, History]  # condition → the whole deep-peak run, read and cleaned
    holds: dict[str, pd.DataFrame]  # condition → its hold (the last hold_hours)
    validation: History  # the day run, read and cleaned
    validation_spans: dict[str, tuple[pd.Timestamp, pd.Timestamp]]  # its 30/50 % holds
    ramp: pd.DataFrame  # the 50 % run from 90 % demand down to 30 min into the hold
    instruments: pd.DataFrame  # the runs' instruments (one seed: the same in every run)
    sections: list[Section]


def _read_back(run: PlantRun, folder: Path) -> tuple[History, Section]:
    """The run's historian file and tag map, read and cleaned as a user's export is."""
    files = write_plant(run, folder)
    history = load_history(files["historian"], files["tag_map"])
    source = folder.name.removeprefix("plant-")
    return history, quality_section(history.report, f"Data quality of the {source} run "
                                    "(DCS cleaning: what was rejected and why)",
                                    name=f"data_quality_{source}")


def _plant_stage(settings: DemoSettings, out: Path, report: Callable[..., None]) -> _PlantData:
    samples = round(settings.hold_hours * 3600.0)
    calibration, holds, sections = {}, {}, []
    for k, load in enumerate(VALIDATION_LOADS):
        name = f"{round(load * 100)} % load"
        scenario = f"deep-peak-{round(load * 100)}"
        run = run_plant(scenario, hours=settings.hold_hours, random_state=settings.random_state)
        history, quality = _read_back(run, out / f"plant-{scenario}")
        calibration[name] = history
        holds[name] = history.data.iloc[-samples:]
        sections.append(quality)
        if load == 0.50:
            ramp = _ramp_window(run, history.data)
        report((k + 1) / 4.0, scenario)
    day = run_plant("day", hours=max(settings.hold_hours * 1.25, settings.hold_hours + 0.25),
                    random_state=settings.random_state)
    history, quality = _read_back(day, out / "plant-day")
    sections.append(quality)
    spans = {}
    demand = day.true_inputs["load_demand"]  # the dispatch schedule: where the holds are
    for load in VALIDATION_LOADS:
        at_level = np.isclose(demand.to_numpy(), load)
        run_id = np.cumsum(~at_level)  # constant along each run of samples at the level
        lengths = pd.Series(at_level).groupby(run_id).transform("sum").to_numpy()
        longest = at_level & (lengths == lengths[at_level].max()) if at_level.any() else at_level
        if longest.sum() < samples:
            raise RuntimeError(f"the day run has no {load:.0%} hold of {settings.hold_hours:g} h")
        hold_index = demand.index[longest][-samples:]
        spans[f"{round(load * 100)} % load"] = (hold_index[0], hold_index[-1])
    report(1.0, "day")
    return _PlantData(calibration, holds, history, spans, ramp, run.injected.sensors, sections)


def _ramp_window(run: PlantRun, data: pd.DataFrame) -> pd.DataFrame:
    """The ramp of a deep-peak run from 90 % demand to 30 min into the hold (filled inputs).

    From 90 %, not 100 %: at rated flow the wide-open valves cannot pass the flow with a flow
    coefficient below ≈ 0.935, and Sobol' needs every parameter set of the bounds to run.
    """
    demand = run.true_inputs["load_demand"]
    start = demand.index[np.argmax(demand.to_numpy() <= 0.90)]
    hold_start = demand.index[np.argmax(np.isclose(demand.to_numpy(), demand.iloc[-1]))]
    end = hold_start + pd.Timedelta(minutes=30)
    return data.loc[(data.index >= start) & (data.index <= end)].ffill().bfill()


# ------------------------------------------------------------------------------------------
# 4. calibration


def _calibration_stage(twin: Twin, plant: _PlantData, settings: DemoSettings, out: Path,
                       report: Callable[..., None]) -> list[Section]:
    """:meth:`Twin.calibrate` on both deep-peak runs: their ramps and their holds."""
    hold_s = settings.hold_hours * 3600.0
    twin.calibrate(list(plant.calibration.values()), method=settings.calibration,
                   min_steady_s=0.5 * hold_s, max_steady_s=hold_s,
                   population=settings.population, generations=settings.generations,
                   max_evaluations=settings.evaluations, random_state=settings.random_state,
                   workers=settings.workers, sensor_bias=True,
                   progress=lambda fraction, message="": report(0.9 * fraction, message))
    report(0.9, "Table 6, Figure 8")
    model, calibrator, p = twin.model_, twin.calibrator_, twin.params_
    table6 = rmse_table(model, {name: [hold] for name, hold in plant.holds.items()}, p,
                        delivered=twin.delivered_model)
    figure8 = temperature_comparison_figure(model, plant.holds["50 % load"], p,
                                            out / "figure8_temperatures.png",
                                            title="Predicted vs measured, 50 % load (Figure 8)")
    intervals = calibrator.posterior_.table()
    parameters = pd.DataFrame([
        {"parameter": name, "calibrated": getattr(p, name),
         "low_95": float(intervals.loc[name, "low"]),
         "high_95": float(intervals.loc[name, "high"]),
         "prior_low_95": float(intervals.loc[name, "prior_low"]),
         "prior_high_95": float(intervals.loc[name, "prior_high"]),
         "identifiable": bool(calibrator.identifiability_.loc[name, "identifiable"])}
        for name in ("flow_coefficient", "friction_coefficient", "heat_transfer_coefficient")])
    method = (f"GA P {settings.population} × G {settings.generations}"
              if settings.calibration == "ga" else
              f"surrogate-assisted GA, ≤ {settings.evaluations} model runs")
    return [
        TableSection("table6_rmse", table6.reset_index(),
                     f"Table 6 — RMSE (K) of the three DCS temperatures on the "
                     f"{settings.hold_hours:g}-h holds with empirical constants (1, 1, 1) and "
                     "calibrated, and the reduction; then the calibrated twin as it is "
                     "delivered (`rmse_delivered_K`: the thermocouples' offsets the "
                     "calibration estimated within their class-1 tolerance applied, as "
                     "validate and predict apply them)"),
        TableSection("calibrated_parameters", parameters,
                     f"Calibrated parameters (MAP under the default priors; {method}, "
                     f"{calibrator.n_evaluations_} model runs, on both deep-peak runs' "
                     f"{len(twin.windows_)} windows: ramps and holds), their 95 % posterior "
                     "(Laplace) and prior intervals, and whether the data identify them"),
        TableSection("identifiability", calibrator.identifiability_.reset_index(),
                     "Identifiability check of the calibrated parameters"),
        FigureSection(figure8, "Figure 8 — predicted vs measured temperatures at 50 % load, "
                      "empirical constants and calibrated"),
    ]


def _table7_stage(twin: Twin, plant: _PlantData, settings: DemoSettings, out: Path,
                  report: Callable[..., None]) -> list[Section]:
    step = settings.table7_thinning_s
    windows = [history.data.iloc[::step] for history in plant.calibration.values()]
    base = {"population": settings.population, "generations": settings.table7_generations}
    # thinned windows run in milliseconds: starting a process pool per GA run would cost more
    # than it saves
    workers = settings.workers if step == 1 else 1
    model = twin.model_  # the calibration's model, read through the plant's sensors
    fitted: dict[tuple, Calibrator] = {}
    runs = 8  # at most: the base and seven variations

    def fit(setting: dict[str, object]) -> Calibrator:
        key = tuple(sorted(setting.items()))
        if key not in fitted:
            fitted[key] = Calibrator(model, search=GeneticSearch(**setting),
                                     random_state=settings.random_state,
                                     workers=workers).fit(windows)
            report(len(fitted) / runs, f"GA run {len(fitted)}")
        return fitted[key]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        base_run = fit(base)
        table7 = ga_sensitivity_table(fit, base)
    figure7 = convergence_figure(base_run.history_, out / "figure7_convergence.png")
    spacing = "as measured (1 s)" if step == 1 else f"thinned to {step} s"
    return [
        TableSection("table7_ga_sensitivity", table7,
                     f"Table 7 — calibrated RMSE (K) for GA settings varied one at a time "
                     f"around P {settings.population}, G {settings.table7_generations} "
                     f"(deep-peak runs {spacing})"),
        FigureSection(figure7, f"Figure 7 — GA convergence, P {settings.population} × G "
                      f"{settings.table7_generations} (deep-peak runs {spacing})"),
    ]


# ------------------------------------------------------------------------------------------
# 5. blade ROM


def _rom_stage(twin: Twin, mesh: object | None, settings: DemoSettings,
               report: Callable[..., None], *, held_out: bool) -> object | None:
    """:meth:`Twin.build_rom` on the reconstructed mesh (None: the exact blade row's, meshed
    at ``mesh_element_size``) with the twin's parameters (the calibrated ones when calibration
    ran); returns the held-out FOM fields of Figure 9 when they are wanted (``held_out``)."""
    twin.build_rom(mesh, row=settings.row, element_size=settings.mesh_element_size,
                   n_snapshots=settings.snapshots, workers=settings.workers,
                   random_state=settings.random_state,
                   progress=lambda fraction, message="": report(0.7 * fraction, message))
    if not held_out:
        return None
    return twin.held_out_fields(
        settings.held_out, random_state=settings.random_state + 1000, workers=settings.workers,
        progress=lambda fraction, message="": report(0.7 + 0.3 * fraction, message))


# ------------------------------------------------------------------------------------------
# 7. rotor life


def _rotor_stage(twin: Twin, plant: _PlantData, out: Path,
                 report: Callable[..., None]) -> list[Section]:
    """The HP rotor over the day run (``steamtwin rotor stress`` on its historian file): the
    life consumed, the peak groove stress against the default allowable, two figures."""
    result = rotor_stress([plant.validation], twin.spec, out / "rotor", params=twin.parameters,
                          settings={"data": "the virtual plant's day run"},
                          progress=lambda fraction, message="": report(fraction, message))
    index = plant.validation.data.index
    hours = (index[-1] - index[0]).total_seconds() / 3600.0
    table = life_table(result.life)
    peak = float(result.frame["groove_von_mises"].max())
    table["peak_groove_von_mises_MPa"] = peak / 1e6
    table["allowable_MPa"] = result.allowable_pa / 1e6
    return [
        TableSection("rotor_life_day", table,
                     f"HP rotor life consumed by the day run ({hours:.1f} h of the 24-h "
                     "load-following programme: its holds scaled with the demo's hold length), "
                     f"{len(result.life.per_ramp)} ramps; allowable "
                     f"{result.allowable_source}; full rotor report in rotor/report.html"),
        FigureSection(result.files["report.html"].with_name("rotor_stress.png"),
                      "HP rotor: stress at the groove root and the bore over the day run"),
        *([FigureSection(result.files["report.html"].with_name("rotor_ramps.png"),
                         "HP rotor: life consumed per load ramp of the day run")]
          if len(result.life.per_ramp) else []),
    ]


# ------------------------------------------------------------------------------------------
# 8. sensitivity


def _sensitivity_stage(twin: Twin, plant: _PlantData, settings: DemoSettings, out: Path,
                       report: Callable[..., None]) -> list[Section]:
    model, params, seed = twin.full_order_model, twin.parameters, settings.random_state
    sobol = sobol_indices(model, plant.ramp, n_base=settings.sobol_n_base, random_state=seed,
                          evaluator=make_evaluator(settings.workers, None),
                          progress=lambda fraction, message="": report(0.8 * fraction, message))
    sobol_png = sobol.figure(out / "sobol_indices.png")
    hold = plant.holds["50 % load"].ffill().bfill()
    noise = noise_propagation(model, hold, params, repeats=settings.noise_repeats,
                              random_state=seed)
    noise_png = noise_figure(model, hold, out / "noise_propagation.png", params,
                             random_state=seed)
    report(1.0)
    return [
        TableSection("sobol_indices", sobol.table().reset_index(),
                     f"Sobol' indices of the three parameters (N = {settings.sobol_n_base}, "
                     f"{sobol.model_runs} model runs, parameters uniform within their bounds) "
                     "for the HP-exhaust and inner-casing temperatures over the 50 % run's "
                     "ramp from 90 % demand to 30 min into the hold: time-mean and lag (RMS of "
                     "output − quasi-steady output)"),
        FigureSection(sobol_png, "Sobol' indices with 95 % bootstrap intervals"),
        TableSection("noise_propagation", noise.reset_index(),
                     "White noise of σ on the main-steam temperature → deviation of each "
                     "output from the noise-free run (50 % hold, calibrated parameters)"),
        FigureSection(noise_png, "Main-steam temperature noise (σ = 1 K) and the output "
                      "deviations it causes"),
    ]


# ------------------------------------------------------------------------------------------
# 2. geometry


def _geometry_stage(spec: TurbineSpec, model: FullOrderModel, settings: DemoSettings,
                    out: Path, report: Callable[..., None]) -> tuple[object, list[Section]]:
    """Scan → fused cloud → B-spline surface → STL → fidelity → mesh → scan uncertainty, the
    chain of :mod:`steamtwin.geometry.workflow` (as ``steamtwin geometry`` runs it)."""
    from steamtwin.geometry.mesh_io import write_stl
    from steamtwin.geometry.meshing import mesh_quality, mesh_stl
    from steamtwin.geometry.profile import make_blade
    from steamtwin.geometry.reconstruction_report import (
        reconstruction_fidelity,
        write_deviation_map,
    )
    from steamtwin.geometry.uncertainty import scan_uncertainty
    from steamtwin.geometry.volume_mesh import write_volume_mesh
    from steamtwin.geometry.workflow import preprocess_scan, reconstruct_cloud, scan_row

    row = settings.row
    scanned = scan_row(spec, row, out / f"scan-{row}", points=settings.scan_points,
                       random_state=settings.random_state)
    blade, scan = scanned.blade, scanned.scan
    report(0.15)
    fused = preprocess_scan(scan)  # keeps 8/15 of the points: the method's 150k → 80k
    steps = fused.report
    report(0.35)
    reconstruction = reconstruct_cloud(fused.cloud, blade).reconstruction  # best fit to row
    stl = write_stl(reconstruction, out / f"blade-{row}.stl")
    fidelity = reconstruction_fidelity(blade, reconstruction.vertices, reconstruction.triangles,
                                       random_state=settings.random_state)
    deviation_png = write_deviation_map(reconstruction, out / f"deviation_map_{row}.png", blade)
    report(0.55)
    mesh = mesh_stl(stl, element_size=settings.mesh_element_size)  # from the STL, as a user would
    write_volume_mesh(mesh, out / f"blade-{row}.msh")
    quality = mesh_quality(mesh)
    report(0.7)
    # per row: hp1, the reconstructed control-stage rotor, sets no flow in the model (its
    # throat spread only); hp13, the last pressure-stage rotor, through its own stage
    uncertainty = [
        scan_uncertainty(make_blade(spec, row), model, samples=settings.uncertainty_samples,
                         random_state=settings.random_state,
                         progress=lambda f, _message, k=k: report(0.7 + 0.15 * (k + f)))
        for k, row in enumerate(UNCERTAINTY_ROWS)]
    summary = reconstruction.summary()
    d = fidelity.deviation
    chain = pd.DataFrame([
        {"step": "scan", "result": f"{sum(len(v.points) for v in scan.views)} points in "
         f"{len(scan.views)} views"},
        {"step": "statistical outliers (50 neighbours, 2 σ)",
         "result": f"{sum(steps.outliers_removed)} removed"},
        {"step": "registration, fusion, downsampling",
         "result": f"{sum(steps.input_points)} → {len(fused.cloud)} points"},
        {"step": "region growing", "result": ", ".join(
            f"{name} {count}" for name, count in summary["patch_points"].items())},
        {"step": "B-spline surface", "result": f"side fit RMS {summary['side_fit_rms_mm']:.4f} "
         f"mm, {summary['breakpoints']} breakpoints round the profile"},
        {"step": "STL", "result": f"{summary['triangles']} triangles, watertight, "
         f"{summary['volume_cm3']:.3f} cm³ (exact blade {blade.volume * 1e6:.3f} cm³)"},
        {"step": "volume mesh (gmsh HXT)", "result": f"{quality.node_count} nodes, "
         f"{quality.tetrahedron_count} tetrahedra, min dihedral "
         f"{quality.min_dihedral_angle:.1f}°, max aspect ratio {quality.max_aspect_ratio:.2f}"},
    ])
    deviation = pd.DataFrame([{"mean_mm": d.mean * 1e3, "rms_mm": d.rms * 1e3,
                               "p95_mm": d.p95 * 1e3, "max_mm": d.max * 1e3,
                               "hausdorff_mm": d.hausdorff * 1e3}])
    metrics = pd.DataFrame([{**row, "section": section["section"]}
                            for section in fidelity.extra["sections"]
                            for row in section["metrics"]])
    spread = [study.as_dict() for study in uncertainty]
    return mesh, [
        TableSection("geometry_chain", chain, f"Reverse geometric modelling of blade {row}: "
                     f"the chain and what each step did (STL: {stl.name})"),
        TableSection("geometry_fidelity", deviation, "Deviation of the reconstructed surface "
                     "from the exact blade (mm)"),
        TableSection("geometry_row_metrics", metrics, "Row metrics of the reconstructed blade "
                     "against the exact sections at hub, mid-span and tip"),
        FigureSection(deviation_png, "Deviation map: fit residual of the scan points and "
                      "distance of the reconstructed surface from the exact blade (mm)"),
        TableSection("scan_uncertainty", pd.DataFrame(spread),
                     f"Scan uncertainty per row: ±{spread[0]['bound_mm']:g} mm scan errors → "
                     "the row's throat area → its own stage's flow capacity → HP-exhaust "
                     "temperature at the design point (spread = max − min over "
                     f"{spread[0]['samples']} samples; max deviation = largest "
                     "|T − T(exact blade)|, the method's < 0.3 °C); hp1, the control-stage "
                     "rotor, sets no flow in the model (nozzle governing): throat spread only"),
    ]
