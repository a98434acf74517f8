"""Resampling onto a uniform grid with flags and counts (steamtwin.dcs.resample)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.dcs.quality import Flag
from steamtwin.dcs.resample import COUNT_KINDS, ResampleFlag, resample

START = pd.Timestamp("2024-03-01 08:00", tz="Asia/Shanghai")  # 00:00 UTC
AVG, ONE, INT, GAP = (int(f) for f in ResampleFlag)


def frame(seconds: list[float], values: list[float], start: pd.Timestamp = START,
          name: str = "load") -> pd.DataFrame:
    index = start + pd.to_timedelta(seconds, unit="s")
    return pd.DataFrame({name: np.asarray(values, dtype=float)}, index=index)


def test_codes_do_not_collide_with_quality_flags() -> None:
    assert [int(f) for f in ResampleFlag] == [512, 1024, 2048, 4096]
    assert all(int(f) & int(g) == 0 for f in ResampleFlag for g in Flag)
    assert max(int(g) for g in Flag) == 256  # BAD_QUALITY, the highest quality bit


def test_bad_quality_flag_is_carried_and_higher_codes_refused() -> None:
    data = frame([0, 1, 2, 3], [np.nan, np.nan, 3.0, 4.0])
    codes = pd.DataFrame({"load": [Flag.BAD_QUALITY | Flag.REMOVED, Flag.MISSING, 0, 0]},
                         index=data.index, dtype=np.uint16)
    result = resample(data, 2.0, flags=codes)  # the empty bin tells why it is empty
    assert list(result.flags["load"]) == [GAP | Flag.BAD_QUALITY | Flag.REMOVED | Flag.MISSING,
                                          AVG]
    with pytest.raises(ValueError, match="0–511"):
        resample(data, 2.0, flags=codes.assign(load=[0, int(ResampleFlag.AVERAGED), 0, 0]))


def test_mean_exact_bin_averages_labelled_by_bin_start() -> None:
    data = frame([0, 10, 20, 30, 40, 50, 60, 70, 80, 90],
                 [1.0, 2.0, 3.0, 4.0, np.nan, 6.0, np.nan, np.nan, np.nan, 10.0])
    result = resample(data, 30.0)
    assert list(result.data.index) == [START + pd.Timedelta(seconds=s) for s in (0, 30, 60, 90)]
    np.testing.assert_array_equal(result.data["load"], [2.0, 5.0, np.nan, 10.0])
    assert list(result.flags["load"]) == [AVG, AVG, GAP, ONE]
    assert result.counts.loc["load"].to_dict() == {
        "averaged": 2, "single": 1, "interpolated": 0, "gap": 1
    }


def test_mean_grid_is_aligned_to_utc_multiples_and_keeps_time_zone() -> None:
    start = pd.Timestamp("2024-03-01 08:10:07", tz="Asia/Kolkata")  # UTC+05:30
    data = frame([0, 1800, 3600], [1.0, 2.0, 3.0], start=start)
    result = resample(data, 3600.0)
    assert str(result.data.index.tz) == "Asia/Kolkata"
    assert all(t.tz_convert("UTC").minute == 0 and t.second == 0 for t in result.data.index)
    assert result.data.index[0] == pd.Timestamp("2024-03-01 07:30", tz="Asia/Kolkata")
    np.testing.assert_array_equal(result.data["load"], [1.0, 2.5])


def test_linear_exact_interpolation_and_copies() -> None:
    data = frame([0, 10, 25], [0.0, 10.0, 40.0])
    result = resample(data, 5.0, method="linear")
    np.testing.assert_array_equal(result.data["load"], [0, 5, 10, 20, 30, 40])
    assert list(result.flags["load"]) == [ONE, INT, ONE, INT, INT, ONE]
    assert result.counts.loc["load", "interpolated"] == 3


def test_linear_grid_does_not_extrapolate_beyond_the_data() -> None:
    data = frame([3, 13, 23], [3.0, 13.0, 23.0])
    result = resample(data, 5.0, method="linear")
    assert list(result.data.index) == [START + pd.Timedelta(seconds=s) for s in (5, 10, 15, 20)]
    np.testing.assert_allclose(result.data["load"], [5, 10, 15, 20])


def test_linear_gap_longer_than_max_gap_stays_nan_and_is_counted() -> None:
    data = frame([0, 10, 20, 100, 110], [0.0, 1.0, np.nan, 10.0, 11.0])
    result = resample(data, 10.0, method="linear", max_gap_s=30.0)
    values, codes = result.data["load"].to_numpy(), result.flags["load"].to_numpy()
    assert np.isnan(values[2:10]).all()
    assert (codes[2:10] == GAP).all()
    assert result.counts.loc["load"].to_dict() == {
        "averaged": 0, "single": 4, "interpolated": 0, "gap": 8
    }
    # default max_gap = 3 × step = 30 s: a 20 s hole (one NaN sample) is bridged
    short = resample(frame([0, 10, 20, 30], [0.0, 1.0, np.nan, 3.0]), 10.0, method="linear")
    assert short.data["load"].iloc[2] == pytest.approx(2.0)
    assert short.flags["load"].iloc[2] == INT
    # a gap of exactly max_gap is bridged, one just longer is not
    edge = frame([0, 30, 70], [0.0, 3.0, 7.0])
    bridged = resample(edge, 10.0, method="linear", max_gap_s=30.0)
    assert list(bridged.flags["load"]) == [ONE, INT, INT, ONE, GAP, GAP, GAP, ONE]


def test_mean_empty_bins_stay_nan_whatever_max_gap() -> None:
    data = frame([0, 100], [1.0, 2.0])
    result = resample(data, 10.0, max_gap_s=1000.0)
    assert result.counts.loc["load", "gap"] == 9
    assert np.isnan(result.data["load"].iloc[1:10]).all()


def test_input_flags_are_carried_from_contributing_samples() -> None:
    data = frame([0, 10, 20, 30, 40, 50], [1.0, np.nan, 3.0, np.nan, np.nan, 6.0])
    codes = [Flag.STUCK, Flag.SPIKE | Flag.REMOVED, 0, Flag.MISSING,
             Flag.OUT_OF_RANGE | Flag.REMOVED, Flag.DUPLICATE]
    quality = pd.DataFrame({"load": codes}, index=data.index, dtype=np.uint8)
    mean = resample(data, 20.0, flags=quality)
    # bin [0,20): 1 valid sample (STUCK); the removed spike did not contribute
    assert list(mean.flags["load"]) == [
        ONE | Flag.STUCK,
        ONE,  # [20,40): 3.0 only; the MISSING sample did not contribute
        ONE | Flag.DUPLICATE,  # [40,60): 6.0; the removed sample did not contribute
    ]
    holes = frame([0, 10, 20], [np.nan, np.nan, 5.0])
    why = pd.DataFrame({"load": [Flag.MISSING, Flag.SPIKE | Flag.REMOVED, 0]}, index=holes.index,
                       dtype=np.uint8)
    empty = resample(holes, 20.0, flags=why)
    # an empty bin carries the flags of its (rejected) samples: why it is empty
    assert empty.flags["load"].iloc[0] == GAP | Flag.MISSING | Flag.SPIKE | Flag.REMOVED
    linear = resample(data, 5.0, method="linear", max_gap_s=20.0, flags=quality)
    assert linear.flags["load"].iloc[1] == INT | Flag.STUCK  # between 0 s and 20 s
    assert linear.flags["load"].iloc[0] == ONE | Flag.STUCK


def test_flags_and_counts_agree_and_nan_iff_gap() -> None:
    rng = np.random.default_rng(1)
    seconds = np.cumsum(rng.integers(1, 40, size=400)).astype(float)
    values = rng.normal(size=400)
    values[rng.random(400) < 0.2] = np.nan
    data = pd.DataFrame({"load": values, "main_steam_flow": values[::-1]},
                        index=START + pd.to_timedelta(seconds, unit="s"))
    for method in ("mean", "linear"):
        result = resample(data, 15.0, method=method)
        codes = result.flags.to_numpy() & 0x1E00
        # exactly one resample code per value
        assert np.isin(codes, [AVG, ONE, INT, GAP]).all()
        for kind, code in COUNT_KINDS.items():
            assert (result.counts[kind] == (codes == int(code)).sum(axis=0)).all()
        assert (result.counts.sum(axis=1) == len(result.data)).all()
        np.testing.assert_array_equal(np.isnan(result.data.to_numpy()), codes == GAP)


@given(
    values=st.lists(st.floats(-1e9, 1e9, allow_nan=False), min_size=1, max_size=50),
    step=st.sampled_from([0.5, 1.0, 10.0, 60.0, 3600.0]),
    offset=st.integers(-1000, 1000),
    method=st.sampled_from(["mean", "linear"]),
)
def test_series_on_grid_is_returned_unchanged(values: list[float], step: float, offset: int,
                                              method: str) -> None:
    seconds = (np.arange(len(values)) + offset) * step
    data = frame(list(seconds), values)
    result = resample(data, step, method=method)  # type: ignore[arg-type]
    assert result.data.index.equals(data.index)
    np.testing.assert_array_equal(result.data["load"].to_numpy(), np.asarray(values))
    assert (result.flags["load"] == ONE).all()
    assert result.counts.loc["load", "single"] == len(values)


def test_numeric_index_in_seconds() -> None:
    data = pd.DataFrame({"load": [1.0, 3.0, 5.0]}, index=pd.Index([1.0, 2.0, 7.0]))
    result = resample(data, 5.0)
    assert list(result.data.index) == [0.0, 5.0]
    np.testing.assert_array_equal(result.data["load"], [2.0, 5.0])


def test_empty_frame() -> None:
    data = pd.DataFrame({"load": []}, index=pd.DatetimeIndex([], tz="UTC"), dtype=float)
    result = resample(data, 10.0)
    assert result.data.empty and result.counts.loc["load"].sum() == 0


@pytest.mark.parametrize("step", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_step(step: float) -> None:
    with pytest.raises(ValueError, match="step_s"):
        resample(frame([0, 1], [1.0, 2.0]), step)


def test_bad_arguments() -> None:
    data = frame([0, 1], [1.0, 2.0])
    with pytest.raises(ValueError, match="method"):
        resample(data, 1.0, method="nearest")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="max_gap_s"):
        resample(data, 1.0, max_gap_s=0.0)
    with pytest.raises(ValueError, match="same index"):
        resample(data, 1.0, flags=pd.DataFrame({"load": [0, 0, 0]}))
    with pytest.raises(TypeError, match="DatetimeIndex"):
        resample(pd.DataFrame({"load": [1.0]}, index=["a"]), 1.0)


def test_unsorted_or_duplicated_index_asks_for_cleaning() -> None:
    with pytest.raises(ValueError, match=r"not sorted.*quality\.clean"):
        resample(frame([0, 20, 10], [1.0, 2.0, 3.0]), 10.0)
    with pytest.raises(ValueError, match=r"duplicate.*quality\.clean"):
        resample(frame([0, 10, 10], [1.0, 2.0, 3.0]), 10.0)


def test_works_on_clean_output() -> None:
    from steamtwin.dcs.quality import clean

    seconds = np.arange(0, 600, 1.0)
    values = 300e6 + 1e5 * np.sin(seconds / 30)
    values[100] = np.nan
    raw = frame(list(seconds), list(values))
    cleaned = clean(raw)
    result = resample(cleaned.data, 60.0, flags=cleaned.flags)
    assert result.counts.loc["load", "averaged"] == 10
    assert cleaned.flags["load"].iloc[100] == Flag.MISSING
    assert result.flags["load"].iloc[1] == AVG  # the missing sample did not contribute
