"""PodRbfRom on analytic fields: exactness, error split, validation, extrapolation."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.rom.estimator import ExtrapolationWarning, NotFittedError, PodRbfRom
from steamtwin.rom.validation import leave_one_out, rom_errors

NAMES = ("main_steam_pressure", "main_steam_temperature", "control_stage_pressure")
X = np.linspace(0.0, 1.0, 400)


def field(c: np.ndarray) -> np.ndarray:
    """A smooth two-pattern field (K) of the scaled conditions c (n, 3)."""
    c = np.atleast_2d(c)
    p, t, q = (c[:, i:i + 1] for i in range(3))
    return 700.0 + 30.0 * p + 10.0 * t + 3.0 * np.sin(2 * p + q) * np.cos(3 * X) + \
        (1.0 + q**2) * X**2


def conditions(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.0, 1.0, (n, 3))


def physical(c):
    return np.column_stack([10e6 + 5e6 * c[:, 0], 790.0 + 20 * c[:, 1], 6e6 + 5e6 * c[:, 2]])


def test_interpolates_snapshots_exactly_and_converges_held_out():
    c = conditions(40, 0)
    rom = PodRbfRom(energy=1.0).fit(field(c), physical(c), NAMES)
    np.testing.assert_allclose(rom.predict(physical(c)), field(c), atol=1e-8)
    test = np.random.default_rng(9).uniform(0.1, 0.9, (20, 3))
    small = PodRbfRom(energy=1.0).fit(field(c[:15]), physical(c[:15]), NAMES)
    big = rom_errors(rom, field(test), physical(test)).table["total"].max()
    coarse = rom_errors(small, field(test), physical(test)).table["total"].max()
    assert big < coarse and big < 0.015 * rom.field_range_


def test_error_split_is_orthogonal():
    c = conditions(25, 1)
    rom = PodRbfRom(energy=0.99).fit(field(c), physical(c), NAMES)
    test = conditions(8, 2)
    x = field(test)
    projected = rom.project(x)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        interpolated = rom.predict_coefficients(physical(test))
    e_p = x - rom.reconstruct(projected)
    e_i = (interpolated - projected) @ rom.modes_
    e = x - rom.reconstruct(interpolated)
    np.testing.assert_allclose(e, e_p - e_i, atol=1e-9)
    np.testing.assert_allclose((e**2).sum(1), (e_p**2).sum(1) + (e_i**2).sum(1), rtol=1e-8)
    report = rom_errors(rom, x, physical(test)).table
    assert np.all(report["total"] <= report["projection"] + report["interpolation"] + 1e-12)
    assert np.all(report["relative_total"] == report["total"] / rom.field_range_)


def test_energy_threshold_sets_modes():
    c = conditions(25, 1)
    loose = PodRbfRom(energy=0.9).fit(field(c), physical(c), NAMES)
    tight = PodRbfRom(energy=0.999999).fit(field(c), physical(c), NAMES)
    assert loose.n_modes_ < tight.n_modes_
    assert loose.energy_captured_ >= 0.9 and tight.energy_captured_ >= 0.999999
    assert tight.modes_.shape == (tight.n_modes_, X.size)


def test_leave_one_out_reports_each_snapshot():
    c = conditions(12, 4)
    rom = PodRbfRom(energy=1.0).fit(field(c), physical(c), NAMES)
    report = leave_one_out(rom, field(c), physical(c)).table
    assert len(report) == 12 and set(report["snapshot"]) == set(range(12))
    assert report["total"].max() > 0  # a left-out snapshot is not reproduced exactly


def test_validation_of_arguments_and_state():
    rom = PodRbfRom()
    assert not hasattr(rom, "modes_")  # no work in __init__
    with pytest.raises(NotFittedError):
        rom.predict(np.zeros(3))
    c = conditions(10, 0)
    with pytest.raises(ValueError, match="energy"):
        PodRbfRom(energy=1.5).fit(field(c), physical(c), NAMES)
    with pytest.raises(ValueError, match="kernel"):
        PodRbfRom(kernel="spline").fit(field(c), physical(c), NAMES)
    with pytest.raises(ValueError, match="conditions must have shape"):
        PodRbfRom().fit(field(c), physical(c)[:5], NAMES)
    with pytest.raises(ValueError, match="do not vary"):
        flat = physical(c)
        flat[:, 1] = 800.0
        PodRbfRom().fit(field(c), flat, NAMES)
    fitted = PodRbfRom().fit(field(c), physical(c), NAMES)
    with pytest.raises(ValueError, match="not finite"):
        fitted.predict(np.array([np.nan, 800.0, 8e6]))
    with pytest.raises(ValueError, match="3 columns"):
        fitted.predict(np.zeros((2, 2)))


@settings(max_examples=20, deadline=None)
@given(offset=st.floats(0.05, 2.0), axis=st.integers(0, 2))
def test_extrapolation_warns_with_distance(offset, axis):
    c = conditions(20, 5)
    rom = PodRbfRom().fit(field(c), physical(c), NAMES)
    point = physical(np.array([[0.5, 0.5, 0.5]]))
    span = rom.input_span_[axis]
    point[0, axis] = rom.input_min_[axis] + span * (1.0 + offset)
    with pytest.warns(ExtrapolationWarning, match="scaled units outside") as record:
        rom.predict(point)
    assert f"{offset:.3f}"[:3] in str(record[0].message) or offset > 0
    assert rom.extrapolation_distance(point)[0] == pytest.approx(offset, rel=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExtrapolationWarning)
        rom.predict(physical(c[:1]))  # a snapshot's own condition: no warning


def test_projection_tolerance_adds_modes_until_the_snapshots_fit():
    c = conditions(25, 1)
    x = field(c)
    loose = PodRbfRom(energy=0.5).fit(x, physical(c), NAMES)
    for tolerance in (0.5, 0.05, 1e-3):
        rom = PodRbfRom(energy=0.5, projection_tolerance=tolerance).fit(x, physical(c), NAMES)
        residual = x - rom.reconstruct(rom.project(x))
        assert np.abs(residual).max() <= tolerance
        fewer = PodRbfRom(energy=0.5, max_modes=rom.n_modes_ - 1).fit(x, physical(c), NAMES) \
            if rom.n_modes_ > 1 else None
        if fewer is not None and fewer.n_modes_ >= loose.n_modes_:
            # the smallest such rank: one mode less leaves a snapshot outside the tolerance
            assert np.abs(x - fewer.reconstruct(fewer.project(x))).max() > tolerance
        assert rom.n_modes_ >= loose.n_modes_
    assert PodRbfRom(energy=0.5, projection_tolerance=1e-3).fit(
        x, physical(c), NAMES).n_modes_ > loose.n_modes_
    with pytest.raises(ValueError, match="projection_tolerance"):
        PodRbfRom(projection_tolerance=-1.0).fit(x, physical(c), NAMES)
    with pytest.raises(ValueError, match="features"):
        PodRbfRom(features="control_stage").fit(x, physical(c), NAMES)
