"""``steamtwin rotor``: HP rotor thermal stress and life commands (issue 23).

Minimal group holding ``advise``; the group's owner (``rotor stress``) registers it in
:mod:`steamtwin.cli.main` and adds its own commands."""

from __future__ import annotations

import typer

from steamtwin.cli.rotor_advise import rotor_advise

__all__ = ["rotor_app"]

rotor_app = typer.Typer(no_args_is_help=True)


@rotor_app.callback()
def rotor() -> None:
    """HP rotor thermal stress, fatigue life and ramp-rate advice."""


rotor_app.command("advise")(rotor_advise)
