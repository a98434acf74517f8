"""Where steamtwin keeps what it computes once: steam tables and compiled (numba) kernels.

The folder is ``$STEAMTWIN_CACHE_DIR`` if set, else ``~/.cache/steamtwin``.

Numba's own cache checks only the source file of each compiled function, not the functions it
inlines from other modules: after an edit of ``steam/tables.py`` it would reuse a stale kernel
of ``model/kernel.py``. So the compiled kernels live in a folder named after a digest of every
source file that numba compiles; any edit starts a fresh folder. A ``NUMBA_CACHE_DIR`` set by the
user is left alone.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

_COMPILED_PACKAGES = ("steam", "model")


def cache_root() -> Path:
    """The steamtwin cache folder (not created here)."""
    return Path(os.environ.get("STEAMTWIN_CACHE_DIR") or Path.home() / ".cache" / "steamtwin")


def configure_jit_cache() -> None:
    """Point numba's cache at a folder keyed by the compiled sources (call before they load)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    import numba

    package = Path(__file__).parent
    digest = hashlib.sha256()
    for name in _COMPILED_PACKAGES:
        for source in sorted((package / name).glob("*.py")):
            digest.update(source.name.encode())
            digest.update(source.read_bytes())
    numba.config.CACHE_DIR = str(cache_root() / "numba" / digest.hexdigest()[:16])
