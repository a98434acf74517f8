"""Fixed, clock-aligned blocks of a stream: residuals, load and inputs per 60-s bin.

The residual monitor works on block means (:func:`~steamtwin.live.residuals.block_means`).
In the live service the samples arrive in pieces whose edges fall anywhere — the gate's
look-ahead, the source's chunks, a restart — so a block cut per piece would depend on how the
data happened to arrive. :class:`BlockAccumulator` bins samples by ``floor(t / block_s)`` on the
UTC clock, holds the open bin, and releases a bin only once a sample at or past its end has
arrived: the same blocks, with the same means, however the stream is cut (tested), and its
carry is part of the service's saved state.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from steamtwin.jsonframe import frame_from_json, frame_to_json

__all__ = ["Block", "BlockAccumulator"]


@dataclass(frozen=True)
class Block:
    """One closed bin: ``end`` (the bin's right edge, UTC — the label
    :func:`~steamtwin.live.residuals.block_means` gives), ``means`` (per column, NaN where the
    bin has no finite sample), ``counts`` (finite samples per column) and ``rows`` (the bin's
    samples, for what needs them: the model's sensitivity over the bin's inputs)."""

    end: pd.Timestamp
    means: pd.Series
    counts: pd.Series
    rows: pd.DataFrame


class BlockAccumulator:
    """Cut a stream into clock-aligned blocks of ``block_s`` seconds (module docstring)."""

    def __init__(self, block_s: float = 60.0) -> None:
        if not (isinstance(block_s, int | float) and math.isfinite(block_s) and block_s > 0):
            raise ValueError(f"block_s must be a positive number of seconds (got {block_s!r})")
        self.block_s = float(block_s)
        self._carry = pd.DataFrame()

    def push(self, frame: pd.DataFrame) -> list[Block]:
        """Add samples (tz-aware DatetimeIndex, after every sample pushed before); return the
        blocks they close, oldest first."""
        if frame.empty:
            return []
        if not isinstance(frame.index, pd.DatetimeIndex) or frame.index.tz is None:
            raise ValueError("blocks need a time-zone aware DatetimeIndex")
        if not self._carry.empty and frame.index[0] <= self._carry.index[-1]:
            raise ValueError(f"samples at {frame.index[0]} do not follow the last one "
                             f"({self._carry.index[-1]})")
        data = frame if self._carry.empty else pd.concat([self._carry, frame])
        bins = self._bins(data.index)
        open_bin = bins[-1]
        closed = bins < open_bin
        self._carry = data[~closed]
        return self._blocks(data[closed], bins[closed])

    def flush(self) -> list[Block]:
        """The end of the stream: the open bin, as it is."""
        data, self._carry = self._carry, pd.DataFrame()
        if data.empty:
            return []
        return self._blocks(data, self._bins(data.index))

    def _bins(self, index: pd.DatetimeIndex) -> np.ndarray:
        return np.floor_divide(index.tz_convert("UTC").as_unit("ns").asi8, self._step_ns)

    @property
    def _step_ns(self) -> int:
        return round(self.block_s * 1e9)

    def _blocks(self, data: pd.DataFrame, bins: np.ndarray) -> list[Block]:
        blocks = []
        if data.empty:
            return blocks
        edges = np.flatnonzero(np.diff(bins)) + 1
        for rows in np.split(np.arange(len(data)), edges):
            part = data.iloc[rows]
            end = pd.Timestamp((int(bins[rows[0]]) + 1) * self._step_ns, unit="ns", tz="UTC")
            blocks.append(Block(end, part.mean(), part.count(), part))
        return blocks

    def get_state(self) -> dict[str, object]:
        """JSON-ready carry (the open bin's samples) to restart from."""
        return frame_to_json(self._carry)

    def set_state(self, state: Mapping[str, object]) -> BlockAccumulator:
        """Restore :meth:`get_state`'s output exactly."""
        self._carry = frame_from_json(state)
        return self
