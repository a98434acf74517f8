"""``steamtwin turbine show|check|derive|fit|update``: a turbine spec, the model's own design
point and line, a spec derived from a heat balance, its part-load laws fitted to it and the
throat areas of scanned rows taken into it.

``show`` and ``check`` run the full-order model on the spec (``model.design_check``): ``show``
puts its design point beside the heat balance, ``check`` also refuses a spec that cannot pass
its rated flow, runs the off-design line and, with ``--heat-balance``, puts the model beside
every point of a thermal kit; ``derive`` writes a spec built from an OEM thermal kit
(``spec.derive``); ``fit`` adjusts the spec's ``[part_load]`` laws to the kit
(``model.design_fit``); ``update`` scales the flow capacities of the stages whose rotor rows
were reconstructed (``geometry.into_spec``). Tables in engineering units (MPa, °C, t/h, MW, %).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from steamtwin.cli.paths import prepare_output_file
from steamtwin.model.design_check import (
    DEFAULT_LOADS,
    DesignError,
    checked_loads,
    consistency_problems,
    design_line,
    design_point,
)
from steamtwin.model.design_fit import (
    RESIDUALS,
    DesignFit,
    DesignFitError,
    fit_design,
    fitted_spec_toml,
    point_residuals,
)
from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import (
    BUILT_IN,
    DeriveError,
    HeatBalance,
    HeatBalanceError,
    HeatBalancePoint,
    SpecError,
    TurbineSpec,
    derive_spec,
    load_heat_balance,
    load_spec,
)

turbine_app = typer.Typer(help="Inspect and check turbine specs.", no_args_is_help=True)

_PREPARING = "running the model's design step (the first run compiles it, ~20 s)"
_KELVIN = 273.15

# design-line columns in engineering units: SI column → (header, CSV column, SI → shown)
_LINE_COLUMNS = {
    "main_steam_pressure": ("p0 (MPa)", "main_steam_pressure_MPa", lambda x: x / 1e6),
    "main_steam_temperature": ("T0 (°C)", "main_steam_temperature_degC", lambda x: x - _KELVIN),
    "main_steam_flow": ("flow (t/h)", "main_steam_flow_t_per_h", lambda x: x * 3.6),
    "control_stage_pressure": ("p1 (MPa)", "control_stage_pressure_MPa", lambda x: x / 1e6),
    "control_stage_temperature": ("T1 (°C)", "control_stage_temperature_degC",
                                  lambda x: x - _KELVIN),
    "hp_exhaust_pressure": ("p ex (MPa)", "hp_exhaust_pressure_MPa", lambda x: x / 1e6),
    "hp_exhaust_temperature": ("T ex (°C)", "hp_exhaust_temperature_degC",
                               lambda x: x - _KELVIN),
    "hp_power": ("HP power (MW)", "hp_power_MW", lambda x: x / 1e6),
    "control_stage_efficiency": ("η cs (%)", "control_stage_efficiency_pct", lambda x: x * 100),
    "admission_arc": ("arc (%)", "admission_arc_pct", lambda x: x * 100),
}


@turbine_app.command("show")
def show(
    turbine: str = typer.Argument(..., help="'reference' or a path to a turbine spec TOML."),
) -> None:
    """Print the design heat balance beside the model's own design point, the valves and the
    stage table. Exit code 1, with the reason, if the model cannot run the spec.

    Example: steamtwin turbine show reference
    """
    spec = _load(turbine)
    console = Console()
    console.print(f"[bold]{spec.name}[/bold]: {spec.description}")
    try:
        with Console(stderr=True).status(_PREPARING):
            model_point = design_point(spec)
    except DesignError as error:
        model_point = None
        reason = str(error)
    console.print(_heat_balance_table(spec, model_point))
    console.print(_valve_table(spec))
    console.print(_stage_table(spec))
    if model_point is None:
        typer.echo(f"error: the model cannot run this spec: {reason}", err=True)
        raise typer.Exit(code=1)


@turbine_app.command("check")
def check(
    turbine: str = typer.Argument(..., help="'reference' or a path to a turbine spec TOML."),
    loads: str = typer.Option(
        ",".join(f"{load:g}" for load in DEFAULT_LOADS), "--loads",
        help="Comma-separated fractions of rated load along the sliding-pressure line "
             "(0.2 up to the line's end)."),
    csv: Path | None = typer.Option(
        None, "--csv", help="Also write the design line to this CSV (engineering units, the "
                            "unit in each column name)."),
    heat_balance: Path | None = typer.Option(
        None, "--heat-balance", help="Thermal kit (TOML, docs/heat-balance.md, or "
        "'example-600mw'): also run the model at every point's inputs and put it beside the "
        "kit's figures."),
) -> None:
    """Check that the model can pass the spec's rated flow, then print its design point beside
    the heat balance and its steady off-design line (MPa, °C, t/h, MW, %).

    With --heat-balance the model runs at each point's main-steam pressure, temperature and flow
    and HP-exhaust pressure, beside the kit's control-stage pressure and temperature and
    HP-exhaust temperature; points outside ±0.5 % / ±1.0 K are marked.

    Exit code 1 with the reason when the spec cannot pass its rated flow (e.g. every governing
    valve open at design) or the model cannot run one of the loads or points.

    Example: steamtwin turbine check unit.toml --heat-balance kit.toml --csv line.csv
    """
    if csv is not None:
        prepare_output_file(csv, "--csv")
    spec = _load(turbine)
    load_values = _parse_loads(spec, loads)
    kit = _load_heat_balance(heat_balance) if heat_balance is not None else None
    model = FullOrderModel(spec)
    with Console(stderr=True).status(_PREPARING):
        problems = consistency_problems(spec, model)
    if problems:
        typer.echo(f"{spec.name}: cannot pass its rated flow", err=True)
        for problem in problems:
            typer.echo(f"error: {problem}", err=True)
        raise typer.Exit(code=1)
    try:
        model_point = design_point(spec, model=model)
        line = design_line(spec, load_values, model=model)
    except DesignError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    console = Console()
    console.print(f"{spec.name}: consistent: the model passes the rated flow "
                  f"({spec.design.main_steam_flow * 3.6:.0f} t/h) with a governing valve "
                  "left for overload")
    console.print(_design_point_table(model_point))
    console.print(_line_table(spec, line))
    if csv is not None:
        _line_in_engineering_units(spec, line).to_csv(csv, float_format="%.6g")
        console.print(f"wrote the design line ({len(line)} loads) to {csv}")
    if kit is not None:
        try:
            residuals = point_residuals(spec, kit)
        except DesignFitError as error:
            typer.echo(f"error: {error}", err=True)
            raise typer.Exit(code=1) from None
        console.print(_kit_table(kit, residuals, f"The model at the points of {kit.source}"))
        _say_outside(residuals)


@turbine_app.command("fit")
def fit(
    turbine: str = typer.Argument(..., help="'reference' or a path to a turbine spec TOML "
                                  "(e.g. from 'steamtwin turbine derive')."),
    heat_balance: Path = typer.Option(..., "--heat-balance", help="Thermal kit (TOML, "
                                      "docs/heat-balance.md, or 'example-600mw') whose points "
                                      "the model must meet."),
    out: Path = typer.Option(..., "--out", help="Spec TOML to write: the input with its "
                             "[part_load] table replaced by the fitted laws."),
    parameters: str | None = typer.Option(
        None, "--parameters", help="Comma-separated [part_load] fields to fit (default: all; "
        "see docs/spec.md)."),
) -> None:
    """Fit the spec's part-load laws so the model meets every point of a thermal kit.

    Bounded least squares on the model − kit residuals (control-stage pressure %, control-stage
    and HP-exhaust temperature K) weighted by the acceptance band ±0.5 % / ±1.0 K; prints the
    residuals before and after, the fitted laws and which points pin each one down, and writes
    the fitted spec. Exit code 1 when a residual stays outside the band (the spec is written).

    Example: steamtwin turbine fit unit.toml --heat-balance kit.toml --out fitted.toml
    """
    prepare_output_file(out, "--out")
    spec = _load(turbine)
    text = _spec_text(turbine)
    kit = _load_heat_balance(heat_balance)
    names = (tuple(name.strip() for name in parameters.split(",") if name.strip())
             if parameters is not None else None)
    try:
        with Console(stderr=True).status(f"fitting the part-load laws to {len(kit.points)} "
                                         "points"):
            result = (fit_design(spec, kit) if names is None
                      else fit_design(spec, kit, parameters=names))
    except DesignFitError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    out.write_text(fitted_spec_toml(text, result.part_load), encoding="utf-8")
    console = Console()
    console.print(_kit_table(kit, result.initial_residuals, "Before the fit"))
    console.print(_kit_table(kit, result.residuals, "After the fit"))
    console.print(_fit_table(result))
    typer.echo(f"{result.evaluations} model evaluations in {result.wall_time_s:.1f} s; "
               f"wrote {out}")
    _say_outside(result.residuals)


@turbine_app.command("derive")
def derive(
    heat_balance: Path = typer.Argument(..., help="Heat-balance TOML (the OEM thermal kit, "
                                        "see docs/heat-balance.md), or 'example-600mw' (the "
                                        "shipped kit of an independent unit)."),
    out: Path = typer.Option(..., "--out", help="Spec TOML to write."),
    name: str | None = typer.Option(None, "--name", help="Name of the unit in the spec "
                                    "(default: the heat balance's name)."),
) -> None:
    """Build a complete turbine spec from a heat balance, every derived figure commented with
    how it was obtained (docs/heat-balance.md, 'Deriving a spec from a heat balance').

    Exit code 2, with the point and field named, if no valid spec can be derived.

    Example: steamtwin turbine derive heat-balance.toml --out unit.toml --name "Unit 3"
    """
    prepare_output_file(out, "--out")
    try:
        derived = derive_spec(load_heat_balance(heat_balance), name=name)
    except (HeatBalanceError, DeriveError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    out.write_text(derived.toml, encoding="utf-8")
    for note in derived.notes:
        typer.echo(f"note: {note}")
    spec = load_spec(out)
    typer.echo(f"wrote {out}: {spec.name!r}, {len(spec.stages)} pressure stages, "
               f"{len(spec.control_stage.valves)} governing valves, design "
               f"{spec.design.generator_power / 1e6:.0f} MW at "
               f"{spec.design.main_steam_flow * 3.6:.0f} t/h; check it with "
               f"'steamtwin turbine check {out}'")


@turbine_app.command("update")
def update(
    turbine: str = typer.Argument(..., help="Spec TOML to update (or a built-in name)."),
    scans: Path = typer.Option(..., "--scans", help="Folder of reconstruction reports "
                               "('geometry reconstruct … --report BASE' writes BASE.json)."),
    out: Path = typer.Option(..., "--out", help="Updated spec TOML to write."),
) -> None:
    """Take the throat areas of reconstructed rows into the spec: the measured / design
    throat-area ratio of rotor row hpK scales stages[K−1].flow_capacity, each changed line
    commented with the row, the report file and the ratio (docs/geometry.md).

    hp1 (the control-stage rotor) sets no flow in the model and IP rows are not in it: they
    are listed, not applied. Exit code 2, naming the file and row, for a ratio outside
    0.8–1.2, a report of another design blade or without the throat area.

    Example: steamtwin turbine update unit.toml --scans scans/ --out updated.toml
    """
    from steamtwin.geometry.into_spec import ScanUpdateError, update_spec_from_scans

    prepare_output_file(out, "--out")
    spec = _load(turbine)
    try:
        result = update_spec_from_scans(_spec_text(turbine), spec, scans, source=turbine)
    except ScanUpdateError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    out.write_text(result.toml, encoding="utf-8")
    for row, stage, path, ratio, old, new in result.applied:
        typer.echo(f"{row}: stages[{stage}].flow_capacity {old:.6g} → {new:.6g} m² (throat-area "
                   f"ratio {ratio:.5f}, {path})")
    for row, reason in result.not_applied.items():
        typer.echo(f"{row}: {reason}")
    if result.missing:
        typer.echo(f"no report for: {', '.join(result.missing)} (flow capacities unchanged)")
    typer.echo(f"wrote {out}: {len(result.applied)} flow capacities from {scans}")


_BAND = {"control_stage_pressure_pct": 0.5, "control_stage_temperature_k": 1.0,
         "hp_exhaust_temperature_k": 1.0}
"""Issue 17's acceptance band of the design model against a thermal kit (% or K)."""


def _load_heat_balance(path: Path) -> HeatBalance:
    try:
        return load_heat_balance(path)
    except HeatBalanceError as error:
        raise typer.BadParameter(str(error), param_hint="--heat-balance") from None


def _spec_text(turbine: str) -> str:
    """The spec's TOML text (the built-in's from the package)."""
    if turbine in BUILT_IN:
        from importlib import resources

        return (resources.files("steamtwin.spec") / "data" / f"{turbine}.toml").read_text(
            encoding="utf-8")
    return Path(turbine).read_text(encoding="utf-8-sig")


def _kit_value(point: HeatBalancePoint, column: str) -> float | None:
    """The kit's figure behind a residual column, in MPa or °C (None: not given)."""
    if column == "control_stage_pressure_pct":
        return point.control_stage_pressure_pa / 1e6
    kelvin = (point.control_stage_temperature_k if column == "control_stage_temperature_k"
              else point.hp_exhaust_temperature_k)
    return None if kelvin is None else kelvin - _KELVIN


def _kit_table(kit: HeatBalance, residuals: pd.DataFrame, title: str) -> Table:
    """Kit vs model per point: p1 (MPa), T1 and T ex (°C) with the difference; '!' outside the
    acceptance band."""
    table = Table(title=title)
    table.add_column("point")
    table.add_column("load (MW)", justify="right")
    for header in ("p1 (MPa)", "T1 (°C)", "T ex (°C)"):
        table.add_column(f"{header} kit → model", justify="right")
    for point, (label, row) in zip(kit.points, residuals.iterrows(), strict=True):
        cells = [str(label), f"{point.load_w / 1e6:.1f}"]
        for column in RESIDUALS:
            given, difference = _kit_value(point, column), float(row[column])
            if given is None or not math.isfinite(difference):
                cells.append("–")
                continue
            flag = " !" if abs(difference) > _BAND[column] else ""
            if column == "control_stage_pressure_pct":
                model = given * (1.0 + difference / 100.0)
                cells.append(f"{given:.3f} → {model:.3f} ({difference:+.2f} %){flag}")
            else:
                cells.append(f"{given:.1f} → {given + difference:.1f} ({difference:+.2f} K)"
                             f"{flag}")
        table.add_row(*cells)
    return table


def _fit_table(result: DesignFit) -> Table:
    """Fitted laws, their start values and the points that pin each one down (share ≥ 20 %)."""
    table = Table(title=escape("Fitted [part_load] laws (docs/spec.md)"))
    for header in ("law", "spec", "fitted", "identified mostly by"):
        table.add_column(header, justify="left" if header in ("law", "identified mostly by")
                         else "right")
    for name in result.parameters:
        shares = result.identified_share[name]
        strong = ", ".join(f"{label} {share:.0%}" for label, share
                           in shares.sort_values(ascending=False).items() if share >= 0.2)
        bound = result.bound_reached(name)
        if bound is not None:
            strong = f"at its {bound} bound: the points push it further ({strong or '–'})"
        elif name in result.unidentified:
            strong = "not identified by these points (kept near its start)"
        table.add_row(name, f"{getattr(result.initial_part_load, name):.4g}",
                      f"{getattr(result.part_load, name):.4g}", strong or "–")
    return table


def _say_outside(residuals: pd.DataFrame) -> None:
    """Exit 1 naming the points outside the acceptance band."""
    outside = [f"{label} ({column.rsplit('_', 1)[0]} {float(row[column]):+.2f} "
               f"{'%' if column.endswith('pct') else 'K'})"
               for label, row in residuals.iterrows() for column in RESIDUALS
               if math.isfinite(float(row[column])) and abs(float(row[column])) > _BAND[column]]
    if outside:
        typer.echo(f"outside ±0.5 % / ±1.0 K: {'; '.join(outside)}", err=True)
        raise typer.Exit(code=1)


def _load(turbine: str) -> TurbineSpec:
    try:
        return load_spec(turbine)
    except SpecError as error:
        raise typer.BadParameter(str(error), param_hint="TURBINE") from None


def _parse_loads(spec: TurbineSpec, text: str) -> np.ndarray:
    try:
        return checked_loads(spec, [float(item) for item in text.split(",")])
    except DesignError as error:
        raise typer.BadParameter(str(error), param_hint="--loads") from None
    except ValueError:
        raise typer.BadParameter(f"{text!r}: expected comma-separated load fractions, e.g. "
                                 "1,0.75,0.5", param_hint="--loads") from None


def _heat_balance_table(spec: TurbineSpec, model_point: pd.DataFrame | None) -> Table:
    design = spec.design
    title = "Design heat balance (rated load)" + (
        ", the model's own design point beside it" if model_point is not None else "")
    table = Table(title=title)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    if model_point is not None:
        table.add_column("model", justify="right")
        table.add_column("model − spec", justify="right")
    predicted = _design_point_rows(model_point) if model_point is not None else {}
    rows = [
        ("main-steam pressure", f"{design.main_steam_pressure / 1e6:.2f} MPa"),
        ("main-steam temperature", f"{design.main_steam_temperature - _KELVIN:.1f} °C"),
        ("main-steam flow", f"{design.main_steam_flow * 3.6:.0f} t/h"),
        ("control-stage pressure", f"{design.control_stage_pressure / 1e6:.2f} MPa"),
        ("HP-exhaust pressure", f"{design.hp_exhaust_pressure / 1e6:.2f} MPa"),
        ("HP-exhaust temperature", f"{design.hp_exhaust_temperature - _KELVIN:.1f} °C"),
        ("HP power", f"{design.hp_power / 1e6:.1f} MW"),
        ("generator power", f"{design.generator_power / 1e6:.0f} MW"),
        ("speed", f"{design.rotational_speed * 60 / (2 * math.pi):.0f} rpm"),
    ]
    for extraction in spec.extractions:
        rows.append((f"bleed '{extraction.name}' after stage {extraction.after_stage}",
                     f"{extraction.design_flow * 3.6:.0f} t/h at "
                     f"{extraction.design_pressure / 1e6:.2f} MPa"))
    for name, value in rows:
        extra = predicted.get(name, ("", "", ""))[1:] if model_point is not None else ()
        table.add_row(name, value, *extra)
    return table


def _design_point_rows(model_point: pd.DataFrame) -> dict[str, tuple[str, str, str]]:
    """Quantity → (spec, model, model − spec) in engineering units."""
    p1, t_ex, power = (model_point.loc[name] for name in
                       ("control_stage_pressure", "hp_exhaust_temperature", "hp_power"))
    return {
        "control-stage pressure": (
            f"{p1.spec / 1e6:.2f} MPa", f"{p1.model / 1e6:.3f} MPa",
            f"{p1.difference / 1e6:+.3f} MPa ({p1.difference / p1.spec:+.2%})"),
        "HP-exhaust temperature": (
            f"{t_ex.spec - _KELVIN:.1f} °C", f"{t_ex.model - _KELVIN:.2f} °C",
            f"{t_ex.difference:+.2f} K"),
        "HP power": (
            f"{power.spec / 1e6:.1f} MW", f"{power.model / 1e6:.2f} MW",
            f"{power.difference / 1e6:+.2f} MW ({power.difference / power.spec:+.2%})"),
    }


def _design_point_table(model_point: pd.DataFrame) -> Table:
    table = Table(title="Design point (rated load): heat balance and model")
    for column in ("quantity", "spec", "model", "model − spec"):
        table.add_column(column, justify="right" if column != "quantity" else "left")
    for name, values in _design_point_rows(model_point).items():
        table.add_row(name, *values)
    return table


def _line_in_engineering_units(spec: TurbineSpec, line: pd.DataFrame) -> pd.DataFrame:
    """The design line with the unit in each column name (MPa, degC, t/h, MW, %)."""
    shown = pd.DataFrame({csv_name: convert(line[name].to_numpy())
                          for name, (_, csv_name, convert) in _LINE_COLUMNS.items()})
    for valve in spec.control_stage.valves:
        shown[f"{valve.name}_opening_pct"] = line[f"{valve.name}_opening"].to_numpy() * 100
    shown.insert(0, "load_pct", line.index.to_numpy() * 100)
    return shown.set_index("load_pct")


def _line_table(spec: TurbineSpec, line: pd.DataFrame) -> Table:
    table = Table(title="The model's steady off-design line (sliding pressure); a valve's "
                        "opening is its lift, % of full lift (control_stage.valve_characteristic "
                        "gives its flow)")
    shown = _line_in_engineering_units(spec, line)
    table.add_column("load")
    for load in shown.index:
        table.add_column(f"{load:g} %", justify="right")
    headers = [*(header for header, _, _ in _LINE_COLUMNS.values()),
               *(f"{valve.name} opening (%)" for valve in spec.control_stage.valves)]
    decimals = [2, 1, 0, 3, 1, 3, 1, 1, 1, 1] + [1] * len(spec.control_stage.valves)
    for header, column, d in zip(headers, shown.columns, decimals, strict=True):
        table.add_row(header, *(f"{value:.{d}f}" for value in shown[column]))
    return table


def _valve_table(spec: TurbineSpec) -> Table:
    table = Table(title="Governing valves (nozzle governing)")
    for column in ("valve", "opening order", "admission arc", "open at design"):
        table.add_column(column, justify="right")
    for valve in spec.control_stage.valves:
        table.add_row(valve.name, str(valve.opening_order), f"{valve.admission_arc:.2f}",
                      "yes" if valve.open_at_design else "no")
    return table


def _stage_table(spec: TurbineSpec) -> Table:
    table = Table(title="Stages")
    for column in ("stage", "d (m)", "l (mm)", "blades", "reaction", "α1 (°)",
                   "η peak", "flow capacity K (cm²)"):
        table.add_column(column, justify="right")
    cs = spec.control_stage
    rows = [("control", cs.blading, "nozzle groups")]
    rows += [(str(i), stage.blading, f"{stage.flow_capacity * 1e4:.1f}")
             for i, stage in enumerate(spec.stages, start=1)]
    for name, blading, capacity in rows:
        table.add_row(name, f"{blading.mean_diameter:.4f}", f"{blading.blade_height * 1e3:.1f}",
                      str(blading.blade_count), f"{blading.reaction:.2f}",
                      f"{math.degrees(blading.nozzle_exit_angle):.1f}",
                      f"{blading.peak_blade_efficiency:.3f}", capacity)
    return table
