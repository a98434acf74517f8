"""The packages' public names (issue 20, item 1): every name a package lists resolves, on first
use, to the object of the module it names, and an unknown name is an AttributeError."""

import importlib
import subprocess
import sys

import pytest

PACKAGES = ["steamtwin", "steamtwin.dcs", "steamtwin.model", "steamtwin.live",
            "steamtwin.geometry"]


@pytest.mark.parametrize("name", PACKAGES)
def test_every_listed_name_resolves_to_its_module_object(name):
    package = importlib.import_module(name)
    for public in package.__all__:
        if public == "__version__":
            continue
        value = getattr(package, public)
        assert public in dir(package)
        home = importlib.import_module(value.__module__) if hasattr(value, "__module__") \
            else None
        if home is not None and hasattr(home, public):
            assert getattr(home, public) is value
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        package.nonexistent  # noqa: B018


def test_importing_a_package_imports_none_of_its_modules():
    code = ("import sys, steamtwin.dcs, steamtwin.model, steamtwin.live; "
            "print(sorted(m for m in sys.modules if m.startswith('steamtwin.')))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True).stdout
    assert loaded.strip() == "['steamtwin.dcs', 'steamtwin.lazy', 'steamtwin.live', " \
                             "'steamtwin.model']"
