"""Fixtures of the HTTP service's tests: the filled historian (built once, copied per test)
and its serve configuration (:mod:`web_fixtures`)."""

from __future__ import annotations

import shutil

import pytest
from web_fixtures import fill, write_serve_config


@pytest.fixture(scope="session")
def pristine_db(tmp_path_factory):
    path = tmp_path_factory.mktemp("historian") / "twin.duckdb"
    fill(path)
    return path


@pytest.fixture
def filled_db(tmp_path, pristine_db):
    """A fresh copy of the filled historian (tests may acknowledge and append)."""
    path = tmp_path / "twin.duckdb"
    shutil.copyfile(pristine_db, path)
    return path


@pytest.fixture
def serve_config(tmp_path, filled_db):
    """:func:`write_serve_config` on ``filled_db``."""
    return write_serve_config(tmp_path, filled_db)
