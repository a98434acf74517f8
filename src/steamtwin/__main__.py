"""``python -m steamtwin``: the ``steamtwin`` command."""

from steamtwin.cli.main import app

app(prog_name="steamtwin")
