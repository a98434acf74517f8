"""``steamtwin rotor advise``: the fastest load ramp within the rotor's allowable stress, one call
into :class:`steamtwin.rotor.advisor.RampAdvisor`; prints the rate, peak stress vs allowable and
the life the ramp costs."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from steamtwin.errors import SteamtwinError
from steamtwin.rotor.advisor import advise_ramp

__all__ = ["rotor_advise"]


def rotor_advise(
    from_load: float = typer.Option(..., "--from", help="Present load, % of rated."),
    to_load: float = typer.Option(..., "--to", help="Target load, % of rated."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML with a "
                                "[rotor] section."),
    params: Path | None = typer.Option(None, help="Parameter JSON (default: empirical)."),
    model: Path | None = typer.Option(None, help="A fitted rotor model (RotorModel.save); "
                                      "default: fit one for --turbine (slow)."),
    state: Path | None = typer.Option(None, help="Rotor state JSON (RotorState.to_dict, e.g. "
                                      "from serve); default: steady at --from."),
    allowable: str | None = typer.Option(None, help="Allowable equivalent stress magnitude, "
                                         "e.g. 400MPa (instead of --cycles)."),
    cycles: float | None = typer.Option(None, help="Design cycles per ramp: the allowable from "
                                        "the steel's strain-life curve with ASME III factors "
                                        "(default 10000 when --allowable is not given)."),
    max_rate: float = typer.Option(10.0, help="Fastest rate offered, %/min."),
    hold: float = typer.Option(3600.0, help="Hold after the ramp included in the check, s."),
    curve: bool = typer.Option(False, "--curve", help="Also a start-up/shut-down curve: the "
                               "fastest rate per 10 % load band."),
    json_out: Path | None = typer.Option(None, "--json", help="Write the advice as JSON here."),
) -> None:
    """Advise the fastest constant load ramp that keeps the HP rotor's groove and bore
    equivalent stress within the allowable over the ramp and the hold after it, and the life
    (fatigue and creep damage) it costs.

    Example: steamtwin rotor advise --from 50 --to 30 --cycles 10000 --json advice.json
    """
    try:
        result = advise_ramp(turbine, from_load / 100.0, to_load / 100.0, params_file=params,
                             model_file=model, state_file=state, allowable=allowable,
                             cycles=cycles, max_rate=max_rate / 100.0, hold_after_s=hold,
                             curve=curve)
    except (SteamtwinError, OSError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    summary = result.advice.summary()
    typer.echo(f"ramp {from_load:g} % → {to_load:g} %: {summary['rate_percent_per_min']:.2f} %/min "
               f"({summary['ramp_s'] / 60:.1f} min; limited by {summary['limited_by']})")
    for location, peak in result.advice.peak_pa.items():
        lower, upper = summary["allowable_pa"][location]
        typer.echo(f"  {location}: peak {peak / 1e6:.1f} MPa, allowable {lower / 1e6:.1f} … "
                   f"{upper / 1e6:.1f} MPa")
    if not summary["monotone"]:
        typer.echo("  note: the peak stress did not grow monotonically with the rate; a faster "
                   "window may exist that is not offered (docs/rotor.md)")
    for location in result.advice.peak_pa:
        typer.echo(f"  life cost at the {location}: fatigue "
                   f"{summary['fatigue_damage'][location]:.3g}, creep "
                   f"{summary['creep_damage'][location]:.3g} (Miner / Robinson fractions)")
    document: dict[str, object] = {"advice": summary}
    if result.curve is not None:
        table = result.curve.table
        document["curve"] = table.to_dict(orient="records")
        typer.echo("start-up/shut-down curve:")
        for row in table.itertuples():
            typer.echo(f"  {100 * row.from_load:.0f} → {100 * row.to_load:.0f} %: "
                       f"{100 * row.rate_per_min:.2f} %/min ({row.limited_by})")
    if json_out is not None:
        json_out.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
