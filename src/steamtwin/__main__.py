"""``python -m steamtwin``: the ``steamtwin`` command."""

from steamtwin.cli.main import app

if __name__ == "__main__":
    app(prog_name="steamtwin")
