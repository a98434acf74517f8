"""The ``steamtwin`` command: one sub-command per pipeline stage, plus ``demo``.

Every command runs under one error handler (:class:`HandledGroup`): an exception that escapes a
command becomes a one-line ``error: ...`` on stderr and an exit code (:data:`EXIT_CODES`);
``steamtwin --debug <command>`` shows the full traceback instead.
"""

from __future__ import annotations

import errno
import inspect
import re
from typing import Any

import typer
from typer.core import TyperGroup

from steamtwin.cli.calibrate import calibrate
from steamtwin.cli.calibrate_online import calibrate_online
from steamtwin.cli.dcs import dcs_app
from steamtwin.cli.demo import demo
from steamtwin.cli.geometry import geometry_app
from steamtwin.cli.history import history_app
from steamtwin.cli.monitor import monitor_app
from steamtwin.cli.plant import plant_app
from steamtwin.cli.rom import rom_app
from steamtwin.cli.rotor import rotor_app
from steamtwin.cli.serve import serve
from steamtwin.cli.simulate import simulate
from steamtwin.cli.turbine import turbine_app
from steamtwin.cli.validate import validate

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130
EXIT_CODES = {
    EXIT_OK: "success",
    EXIT_FAILURE: "the command failed: a check found errors, or an internal error",
    EXIT_USAGE: "bad usage or input: an unknown option, an unreadable or invalid file, a value "
                "out of range, an output path that cannot be written",
    EXIT_INTERRUPTED: "interrupted (Ctrl-C)",
}


def exit_code_for(error: BaseException) -> int:
    """The exit code of an exception that escaped a command: 2 for bad input (``ValueError``,
    ``OSError`` and their subclasses, e.g. a spec or CSV error, a missing file), 1 otherwise."""
    return EXIT_USAGE if isinstance(error, ValueError | OSError) else EXIT_FAILURE


def one_line(error: BaseException) -> str:
    """The exception's message on one line (its type name when it has no message, or when it
    is not an input error and the type says what went wrong, e.g. ``KeyError: 'x'``)."""
    message = " ".join(str(error).split())
    if exit_code_for(error) == EXIT_USAGE and message:
        return message
    return f"{type(error).__name__}: {message}" if message else type(error).__name__


class HandledGroup(TyperGroup):
    """The top-level command group: exceptions escaping a sub-command become one-line errors.

    typer's own exceptions (usage errors, ``typer.Exit``, ``typer.Abort``) keep their
    behaviour and exit codes; a broken pipe (``steamtwin ... | head``) is left to typer.
    """

    def invoke(self, ctx: typer.Context) -> Any:
        try:
            return super().invoke(ctx)
        except (typer.TyperException, typer.Exit, typer.Abort):
            raise
        except KeyboardInterrupt:
            typer.echo("\nerror: interrupted", err=True)
            raise typer.Exit(EXIT_INTERRUPTED) from None
        except Exception as error:
            if ctx.params.get("debug") or (isinstance(error, OSError)
                                           and error.errno == errno.EPIPE):
                raise
            hint = "" if exit_code_for(error) == EXIT_USAGE else (
                " (unexpected; 'steamtwin --debug ...' shows the traceback)")
            typer.echo(f"error: {one_line(error)}{hint}", err=True)
            raise typer.Exit(exit_code_for(error)) from None


_HELP = (
    "Digital twin of a steam turbine in deep peak-shaving operation.\n\n"
    "Example: steamtwin demo --out demo-output\n\n"
    "Exit codes: " + "; ".join(f"{code} {text}" for code, text in EXIT_CODES.items()) + ".\n\n"
    "An error is one line on stderr; 'steamtwin --debug COMMAND ...' shows its traceback."
)

app = typer.Typer(
    name="steamtwin",
    cls=HandledGroup,
    help=_HELP,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@app.callback()
def _options(
    debug: bool = typer.Option(False, "--debug", help="Show the full traceback of an error "
                               "instead of the one-line message."),
) -> None:
    """Options for every command (read by :class:`HandledGroup`)."""


app.add_typer(turbine_app, name="turbine")
app.add_typer(dcs_app, name="dcs")
app.add_typer(geometry_app, name="geometry")
app.add_typer(rom_app, name="rom")
app.add_typer(rotor_app, name="rotor")
app.add_typer(history_app, name="history")
app.add_typer(monitor_app, name="monitor")
app.command()(simulate)
app.add_typer(plant_app, name="plant")
app.command()(calibrate)
app.command("calibrate-online")(calibrate_online)
app.command()(validate)
app.command()(demo)
app.command()(serve)


_LIST_ITEM = re.compile(r"^\s*(?:[-*•]|\d+[.)])\s")


def reflow_help(text: str) -> str:
    """A command's docstring as one line per paragraph, so that the terminal formatter (rich,
    through typer) wraps it to the terminal's width instead of keeping the source's 100-column
    breaks; list items (``-``, ``*``, ``1.``) keep their own lines."""
    paragraphs = []
    for paragraph in inspect.cleandoc(text).split("\n\n"):
        lines = paragraph.splitlines()
        joined: list[str] = []
        for line in lines:
            if joined and not _LIST_ITEM.match(line):
                joined[-1] = f"{joined[-1]} {line.strip()}"
            else:
                joined.append(line.rstrip())
        paragraphs.append("\n".join(joined))
    return "\n\n".join(paragraphs)


def _reflow_commands(typer_app: typer.Typer) -> None:
    """Reflow the help of every command of ``typer_app`` and its sub-apps (see reflow_help)."""
    callback = typer_app.registered_callback
    if callback is not None and callback.callback is not None and not isinstance(
            typer_app.info.help, str) and (callback.help or inspect.getdoc(callback.callback)):
        callback.help = reflow_help(callback.help or inspect.getdoc(callback.callback) or "")
    for command in typer_app.registered_commands:
        text = command.help or inspect.getdoc(command.callback) or ""
        command.help = reflow_help(text)
    for group in typer_app.registered_groups:
        _reflow_commands(group.typer_instance)


_reflow_commands(app)
