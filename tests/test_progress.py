"""The one progress signature: ``scaled`` maps a sub-step onto its share of the whole."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.progress import scaled


def test_scaled_maps_the_sub_step_onto_its_range_with_its_prefix() -> None:
    calls: list[tuple[float, str]] = []
    sub = scaled(lambda f, m: calls.append((f, m)), 0.25, 0.75, "rom: ")
    sub(0.0, "start")
    sub(0.5, "half")
    sub(1.0)
    assert calls == [(0.25, "rom: start"), (0.5, "rom: half"), (0.75, "rom: ")]


def test_scaled_passes_none_on_and_refuses_a_range_outside_zero_one() -> None:
    assert scaled(None, 0.0, 1.0) is None
    with pytest.raises(ValueError, match="within"):
        scaled(lambda f, m: None, 0.5, 1.5)


@given(st.floats(0, 1), st.floats(0, 1), st.floats(-2, 3, allow_nan=False))
def test_scaled_never_leaves_its_range(a: float, b: float, fraction: float) -> None:
    start, stop = sorted((a, b))
    seen: list[float] = []
    scaled(lambda f, m: seen.append(f), start, stop)(fraction, "")
    assert start - 1e-12 <= seen[0] <= stop + 1e-12
