"""The sensor lag computes its first-order-hold weights once per step length (DCS data repeat
one step): the readings are those of weights computed at every sample, to the bit, whatever
the steps do."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.model.measurement import lag


def _lag_every_sample(x, steps, tau, before=None):
    """τ·dy/dt + y = x under a first-order hold, weights from each sample's own step."""
    y = np.empty_like(x)
    for k in range(x.size):
        if k == 0 and before is None:
            y[0] = x[0]
            continue
        ratio = steps[k] / tau
        a, one_minus_a = math.exp(-ratio), -math.expm1(-ratio)
        b0 = 1.0 - one_minus_a / ratio
        y_last, x_last = before if k == 0 else (y[k - 1], x[k - 1])
        y[k] = a * y_last + (one_minus_a - b0) * x_last + b0 * x[k]
    return y


@given(st.lists(st.sampled_from([1.0, 1.0, 1.0, 2.0, 0.5, 10.0]), min_size=2, max_size=40),
       st.sampled_from([0.7, 5.0, 30.0]), st.booleans())
def test_weights_kept_per_step_length_give_the_same_bits(steps, tau, resume):
    steps = np.array(steps)
    x = 800.0 + 5.0 * np.sin(np.arange(steps.size))
    before = (801.0, 799.5) if resume else None
    np.testing.assert_array_equal(lag(x, steps, tau, before=before),
                                  _lag_every_sample(x, steps, tau, before))
