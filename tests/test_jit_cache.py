"""``import steamtwin`` leaves numba's settings alone (issue 20, item 6); steamtwin's own
kernels still cache in the folder keyed by their sources (steamtwin.cache)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

_PROBE = """
import json, numba
default = numba.config.CACHE_DIR
import steamtwin
from steamtwin.cache import jit_cache_dir
from steamtwin.model.measurement import lag
import numpy as np
after_import = numba.config.CACHE_DIR
lag(np.arange(5.0), np.ones(5), 3.0)  # compiles, caches
print(json.dumps({"default": default, "after": after_import,
                  "folder": str(jit_cache_dir())}))
"""


def test_import_keeps_numba_settings_and_kernels_cache_in_steamtwins_folder(tmp_path):
    env = {key: value for key, value in os.environ.items() if key != "NUMBA_CACHE_DIR"}
    env["STEAMTWIN_CACHE_DIR"] = str(tmp_path)
    done = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                          env=env, timeout=300, check=True)
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    assert seen["after"] == seen["default"]  # numba's own default, untouched
    folder = Path(seen["folder"])
    assert folder.is_relative_to(tmp_path / "numba")
    assert any(path.suffix == ".nbi" and "measurement" in path.name
               for path in folder.rglob("*"))


def test_a_user_numba_cache_dir_is_used(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "user"),
           "STEAMTWIN_CACHE_DIR": str(tmp_path / "ours")}
    subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, env=env,
                   timeout=300, check=True)
    assert any(path.suffix == ".nbi" for path in (tmp_path / "user").rglob("*"))
    assert not (tmp_path / "ours" / "numba").exists()
