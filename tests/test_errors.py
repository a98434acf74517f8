"""One error family (issue 20, item 5): every exception steamtwin defines derives from
SteamtwinError and keeps its built-in base; one MeshError for the blade and geometry code."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

import steamtwin
from steamtwin.errors import MeshError, SteamtwinError


def _steamtwin_exceptions() -> dict[str, type]:
    found: dict[str, type] = {}
    for module_info in pkgutil.walk_packages(steamtwin.__path__, "steamtwin."):
        module = importlib.import_module(module_info.name)
        for _, value in inspect.getmembers(module, inspect.isclass):
            if (issubclass(value, Exception) and not issubclass(value, Warning)
                    and value.__module__.startswith("steamtwin")):
                found[f"{value.__module__}.{value.__qualname__}"] = value
    return found


def test_every_steamtwin_exception_is_a_steamtwin_error():
    exceptions = _steamtwin_exceptions()
    assert len(exceptions) >= 25  # the walk did see the package
    outside = sorted(name for name, cls in exceptions.items()
                     if not issubclass(cls, SteamtwinError))
    assert outside == []
    meshes = {cls for name, cls in exceptions.items() if name.endswith(".MeshError")}
    assert meshes == {MeshError}


@pytest.mark.parametrize(("module", "name", "builtin"), [
    ("steamtwin.dcs.tagmap", "TagMapError", ValueError),
    ("steamtwin.rom.romfile", "RomFileError", ValueError),
    ("steamtwin.spec.loader", "SpecError", ValueError),
    ("steamtwin.rom.estimator", "NotFittedError", RuntimeError),
    ("steamtwin.blade.conduction", "SolverError", RuntimeError),
])
def test_the_builtin_bases_are_kept(module, name, builtin):
    """Code that caught ValueError/RuntimeError before the family still catches them."""
    cls = getattr(importlib.import_module(module), name)
    assert issubclass(cls, builtin) and issubclass(cls, SteamtwinError)
    with pytest.raises(SteamtwinError):
        raise cls("refused")
