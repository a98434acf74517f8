"""Where steamtwin keeps what it computes once: steam tables and compiled (numba) kernels.

The folder is ``$STEAMTWIN_CACHE_DIR`` if set, else ``~/.cache/steamtwin``.

Numba's own cache checks only the source file of each compiled function, not the functions it
inlines from other modules: after an edit of ``steam/tables.py`` it would reuse a stale kernel
of ``model/kernel.py``. So steamtwin's compiled kernels live in a folder named after a digest
of every source file of the compiled packages; any edit starts a fresh folder. Only
steamtwin's own functions go there: :func:`njit` sets numba's cache folder while numba builds
each function's cache locator (numba reads ``numba.config.CACHE_DIR`` once, when a
``cache=True`` function is decorated) and restores it at once, so importing steamtwin leaves
the process's numba settings as they were. A ``NUMBA_CACHE_DIR`` set by the user is left
alone and used for steamtwin's kernels too.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any

import numba

__all__ = ["cache_root", "jit_cache_dir", "njit"]

_COMPILED_PACKAGES = ("steam", "model", "rom", "rotor")


def cache_root() -> Path:
    """The steamtwin cache folder (not created here)."""
    return Path(os.environ.get("STEAMTWIN_CACHE_DIR") or Path.home() / ".cache" / "steamtwin")


@lru_cache(maxsize=1)
def jit_cache_dir() -> Path:
    """The folder of steamtwin's compiled kernels, keyed by the compiled packages' sources."""
    package = Path(__file__).parent
    digest = hashlib.sha256()
    for name in _COMPILED_PACKAGES:
        for source in sorted((package / name).glob("*.py")):
            digest.update(source.name.encode())
            digest.update(source.read_bytes())
    return cache_root() / "numba" / digest.hexdigest()[:16]


def njit(**options: Any) -> Callable[[Callable], Callable]:
    """``numba.njit(**options)`` whose ``cache=True`` functions cache in :func:`jit_cache_dir`
    (unless the user set ``NUMBA_CACHE_DIR``); numba's global setting is restored after each
    decoration."""
    def decorate(function: Callable) -> Callable:
        if not options.get("cache") or os.environ.get("NUMBA_CACHE_DIR"):
            return numba.njit(**options)(function)
        previous = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = str(jit_cache_dir())
        try:
            return numba.njit(**options)(function)
        finally:
            numba.config.CACHE_DIR = previous
    return decorate
