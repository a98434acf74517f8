"""``steamtwin rotor``: HP rotor thermal stress and fatigue life (issue 23).

One module per command: ``stress`` (:mod:`steamtwin.cli.rotor_stress`) — stress and life over
a historian record, as a report; ``advise`` (:mod:`steamtwin.cli.rotor_advise`) — the fastest
load ramp within the allowable stress, and what it costs. Each command parses its options, makes
one library call and prints the result.
"""

from __future__ import annotations

import typer

from steamtwin.cli.rotor_advise import rotor_advise
from steamtwin.cli.rotor_stress import stress

rotor_app = typer.Typer(
    help="HP rotor thermal stress and fatigue life: stress and life over historian records, "
         "and the fastest load ramp the allowable stress permits.",
    no_args_is_help=True,
)

rotor_app.command()(stress)
rotor_app.command("advise")(rotor_advise)
