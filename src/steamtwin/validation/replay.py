"""One continuous run of the monitoring model over a whole historian file.

A user runs the twin over the plant's history as it comes: the model starts once, at steady
state at the first complete input row, and carries its dynamic state — the casing and rotor
metal's stored heat and each thermowell's first-order lag — through every ramp that follows.
A validation window is then a *selection* of that run's samples. Started afresh at a window's
first sample instead (what :func:`~steamtwin.validation.monitor.monitor_windows` does without
``replay_over``), the model assumes the metal in equilibrium with the steam there; after a
load ramp it is not: a lumped wall follows its steam with the time constant τ = ρcV/(hA)
(Incropera & DeWitt, *Fundamentals of Heat and Mass Transfer*, §5.1), tens of minutes for a
casing wall, so a steady start right after a ramp charges the twin with a transient the plant
has and the start removed.

:func:`replay` is that one run; the run is cut only where the model cannot bridge the data: an
input dropout longer than ``max_input_gap_s`` (the calibration's own gap policy,
:func:`~steamtwin.calibration.windowset.split_at_input_dropouts`), after which it restarts at
steady state. Its ``replay_elapsed_s`` column says how long the run had been going at each
sample, so a reader can tell a sample the model reached through the history from one right
after a restart.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from steamtwin.calibration.settings import MAX_INPUT_GAP_S
from steamtwin.calibration.windowprep import prepare_window
from steamtwin.calibration.windowset import split_at_input_dropouts
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import Simulator

__all__ = ["ELAPSED", "WARM_UP_S", "replay", "replay_span"]

ELAPSED = "replay_elapsed_s"
"""Column of :func:`replay`: seconds (s) since the run reaching the sample started (NaN where
the model did not run)."""


WARM_UP_S = 3.0 * 3600.0
"""How long (s) :func:`replay_span` runs the model before the first window: six time constants
of the reference unit's casing wall (τ ≈ 30 min, ρcV/(hA) of its lumped metal), after which a
steady start's error has decayed to e⁻⁶ ≈ 0.25 % of itself (Incropera & DeWitt §5.1)."""


def replay_span(data: pd.DataFrame, windows: Sequence[pd.DataFrame],
                warm_up_s: float = WARM_UP_S) -> pd.DataFrame:
    """The rows of ``data`` (indexed by time) a continuous replay over ``windows`` needs: from
    ``warm_up_s`` (s) before the earliest window's first sample, or ``data``'s first row, to the
    latest window's last sample."""
    if not windows:
        raise ValueError("replay_span needs at least one window")
    start = min(frame.index[0] for frame in windows) - pd.Timedelta(seconds=warm_up_s)
    end = max(frame.index[-1] for frame in windows)
    return data.loc[(data.index >= start) & (data.index <= end)]


def replay(simulator: Simulator, data: pd.DataFrame, params: ModelParameters | None = None, *,
           name: str = "data", max_input_gap_s: float = MAX_INPUT_GAP_S) -> pd.DataFrame:
    """The ``simulator`` run continuously over all of ``data`` (canonical SI, indexed by
    time), its dynamic state carried from the first complete input row to the last.

    Input dropouts of at most ``max_input_gap_s`` (s) are held (filled forward, as
    :func:`~steamtwin.calibration.windowprep.prepare_window` does); a longer one cuts the run,
    which restarts at steady state at the next complete row. Returns a frame on ``data``'s
    index with the simulator's ``output_signals`` (SI: K, Pa, W) and :data:`ELAPSED` (s since
    the run, or its restart, began); rows the model did not run (before the first complete
    input row, inside a cut dropout) are NaN. ``params``: the model parameters (default: the
    design multipliers). ``name`` names ``data`` in errors.
    """
    if not isinstance(data, pd.DataFrame) or data.empty:
        raise ValueError(f"{name}: expected a non-empty DataFrame of canonical SI signals")
    missing = [s for s in simulator.input_signals if s not in data.columns]
    if missing:
        raise ValueError(f"{name}: lacks the model's input column(s) {missing}")
    params = ModelParameters() if params is None else params
    runs = []
    for number, piece in enumerate(split_at_input_dropouts(data, max_input_gap_s, 1)):
        complete = piece[list(simulator.input_signals)].notna().all(axis=1)
        if not complete.any():
            continue  # nothing the model can start from: those rows stay NaN
        prepared = prepare_window(piece, simulator, (), max_input_gap_s,
                                  name=f"{name}, run {number + 1} from {piece.index[0]}",
                                  min_samples=1)
        outputs = simulator.simulate(prepared.inputs, params)
        runs.append(outputs.assign(**{ELAPSED: _elapsed_s(prepared.inputs.index)}))
    if not runs:
        raise ValueError(f"{name}: no row has every input {list(simulator.input_signals)}")
    return pd.concat(runs).reindex(data.index)


def _elapsed_s(index: pd.Index) -> np.ndarray:
    """Seconds since ``index``'s first entry (a DatetimeIndex, or seconds)."""
    if isinstance(index, pd.DatetimeIndex):
        return ((index - index[0]) / pd.Timedelta(seconds=1)).to_numpy(dtype=float)
    values = np.asarray(index, dtype=float)
    return values - values[0]
