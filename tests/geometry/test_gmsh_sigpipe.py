"""gmsh's initialize must not leave SIGPIPE at its default action (terminate): after a mesh, a
write to a closed pipe raises BrokenPipeError as Python promises, instead of killing the
process (it killed a test worker and would kill the demo's servers)."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

WRITE_AFTER_MESHING = """
import os
from steamtwin.geometry.volume_mesh import gmsh_session
with gmsh_session() as gmsh:
    pass
reader, writer = os.pipe()
os.close(reader)
try:
    os.write(writer, b"x")
except BrokenPipeError:
    print("BrokenPipeError")
"""


@pytest.mark.skipif(not hasattr(signal, "SIGPIPE"), reason="no SIGPIPE on this platform")
def test_a_closed_pipe_after_meshing_is_an_error_not_a_kill():
    # in a child process: on failure it is the child that dies (−SIGPIPE), not the test run
    result = subprocess.run([sys.executable, "-c", WRITE_AFTER_MESHING], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, f"exit {result.returncode}: {result.stderr[-500:]}"
    assert result.stdout.strip() == "BrokenPipeError"
