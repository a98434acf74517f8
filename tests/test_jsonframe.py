"""A frame through JSON and back is the same frame, NaN and time zone included."""

import json

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.jsonframe import frame_from_json, frame_to_json


@settings(max_examples=30, deadline=None)
@given(st.lists(st.one_of(st.floats(allow_infinity=False), st.just(float("nan"))),
                min_size=1, max_size=40),
       st.sampled_from(["UTC", "Asia/Shanghai", "Etc/GMT+5"]))
def test_a_frame_survives_json_exactly(values, zone):
    index = pd.date_range("2026-05-01 12:00:00.25", periods=len(values), freq="1500ms", tz=zone)
    frame = pd.DataFrame({"a": values, "b": np.arange(len(values), dtype=float)}, index=index)
    back = frame_from_json(json.loads(json.dumps(frame_to_json(frame))))
    pd.testing.assert_frame_equal(back, frame, check_freq=False, check_index_type=False)
    assert str(back.index.tz) == zone


def test_an_empty_frame_comes_back_empty():
    assert frame_from_json(frame_to_json(pd.DataFrame())).empty
