"""One unit's live twin: source → gate → streamed model → residuals → historian (issue 21).

Kept as one module because it is one class, :class:`LiveTwin`, whose final and provisional
chains share its model state, gate and historian.

:class:`LiveTwin` takes the blocks a :class:`~steamtwin.live.sources.Source` yields and, for each:

1. the data-quality gate (:class:`~steamtwin.live.gate.StreamGate`) passes the samples whose
   verdict is final — bad ones flagged and NaN, never fed to the model as good;
2. the full-order model advances over the samples whose inputs are all good
   (:meth:`~steamtwin.model.fom.FullOrderModel.simulate_stream`, read through the unit's
   sensors: lags and the calibration's offsets); samples with a missing input get no twin
   value (NaN, counted) and the model steps over them;
3. the ROM, when given, adds the blade probe temperatures for those samples, and the rotor
   model, when given (:class:`~steamtwin.live.rotor_stream.LiveRotor`), steps once per such
   sample on the FOM's stage states and adds the rotor's groove/bore temperature and stress;
4. residuals (measured − twin) of every monitored sensor the model predicts, and, when a
   :class:`~steamtwin.live.residuals.ResidualMonitor` is given, its alarms on clock-aligned
   60-s blocks (:class:`~steamtwin.live.blocks.BlockAccumulator`), with the load and, given a
   :class:`~steamtwin.live.sensitivity.SensitivityCache`, the twin's J for the degradation
   hypotheses; an alarm has a start, an end and an acknowledgement (:meth:`LiveTwin.acknowledge`);
5. given a :class:`~steamtwin.live.recalibration.LiveRecalibration`, the good samples feed its
   filter, and the parameters it swaps in (on schedule, or step by step while a degradation
   alarm is active) apply from the next sample on — when a block holds several filter steps,
   the last step's set (which includes the earlier ones' changes) is the one applied and the
   only one recorded: the earlier ones never applied to a sample;
6. the DuckDB historian stores measured, twin and residual series with the gate's flags, the
   alarms started and ended, the parameter swaps, and the state (model, gate context, monitor,
   open block, J cache, filter, live parameters) — all in one transaction per block; the
   unit's first block also records the parameters it starts with (reason ``"start"``, at its
   first sample), so the parameter history is complete from the first stored sample on.

Latency: the gate's final verdict waits for its look-ahead (60 s at 1 Hz; why, in
:mod:`steamtwin.live.gate`). With ``provisional=True`` (the service's choice for an OPC UA or
paced source) :meth:`LiveTwin.receive` stores, as soon as a sample arrives, its provisional
measured, twin (ROM probes included) and residual rows in the historian's ``provisional`` table,
from the verdicts that need no look-ahead and a provisional model state continued from the last
final one; :meth:`LiveTwin.settle` later stores the final rows, which delete the provisional ones
in the same transaction. The final chain never sees a provisional value: when the final verdicts
fed the model other inputs than the provisional ones (a spike or stuck run found) or the
parameters were swapped, the provisional chain restarts from the final state. Provisional rows
live outside ``series``, ``progress`` and the state, so a restart gives the uninterrupted
run's database (tested).

Restart: the state is saved with the block that crosses each ``snapshot_every_s`` of data
(default 10 min; serialising the gate's context, the filter's data and the rewind buffer every
block would cost more than the model), and with the last block of a finished stream. A new
LiveTwin on the same database continues from the last saved state
(:meth:`LiveTwin.resume_after` says from where the source must replay): the samples between it
and the last committed one are computed again — the chain is deterministic — but not stored
again, so no sample is lost, none stored twice, and the stored series, alarms and swaps equal an
uninterrupted run's (tested; checkpoint and replay, as a write-ahead log's recovery redoes
what follows its checkpoint: Gray & Reuter, *Transaction Processing*, 1993, §11.3).
"""

from __future__ import annotations

import functools
import math
import threading
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from steamtwin.live.blocks import Block, BlockAccumulator
from steamtwin.live.gate import StreamGate
from steamtwin.live.historian import (
    Alarm,
    AlarmEnd,
    BlockEvents,
    LiveHistorian,
    ProvisionalRows,
)
from steamtwin.live.recalibration import LiveRecalibration, ParameterSwap, swap_values
from steamtwin.live.residuals import AlarmEvent, ResidualMonitor
from steamtwin.live.rewind import RewindBuffer
from steamtwin.live.rotor_stream import ROTOR_SIGNALS, LiveRotor
from steamtwin.live.sensitivity import SensitivityCache
from steamtwin.live.sources import Source, SourceBlock
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.model.stream_state import StreamState
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.reconstruction import FLAG_EXTRAPOLATED, FLAG_INVALID, predict_series
from steamtwin.rom.romfile import BladeRom

__all__ = ["LiveSummary", "LiveTwin"]

_WARNING_FILTERS = threading.Lock()
"""Held around ``warnings.catch_warnings`` (not thread-safe: it swaps the module-global filter
list; Python docs, ``warnings.catch_warnings``): the service predicts provisional values on its
event loop and final ones on its final-work thread."""

MONITORED = ("control_stage_pressure", "control_stage_temperature", "hp_exhaust_temperature",
             "hp_inner_casing_temperature")
"""Sensors whose residuals are stored and monitored when the data and the model have them."""


@dataclass
class LiveSummary:
    """What a run did: samples stored, samples without a twin value (an input missing), rows
    written, alarms raised, findings the source and gate reported, parameter swaps, and
    samples whose ROM probes were extrapolated beyond the snapshots (flagged by the ROM)."""

    samples: int = 0
    without_twin: int = 0
    rows: int = 0
    alarms: int = 0
    findings: int = 0
    swaps: int = 0
    rom_extrapolated: int = 0


class LiveTwin:
    """The live twin of unit ``name`` (see the module docstring).

    ``model``: the unit's FOM read through its sensors; ``params``: the live parameters;
    ``gate``: the stream's quality gate; ``historian``: the open database; ``rom``: optional
    blade ROM (probe temperatures); ``monitor``: an optional fitted residual monitor;
    ``sensitivity``: J per load band for its degradation hypotheses (without it the monitor
    tells sensor faults only); ``recalibration``: optional online recalibration;
    ``snapshot_every_s``: data seconds between saved states (0: every block);
    ``provisional``: also store a provisional twin value of each sample as soon as it arrives
    (the ``provisional`` table), replaced by the final row once the gate has judged it;
    ``rotor``: optional rotor model stepped on every accepted sample (final rows only: the
    provisional rows carry no rotor values).
    """

    def __init__(self, name: str, model: FullOrderModel, params: ModelParameters,
                 gate: StreamGate, historian: LiveHistorian, rom: BladeRom | None = None,
                 monitor: ResidualMonitor | None = None,
                 monitored: Sequence[str] = MONITORED,
                 sensitivity: SensitivityCache | None = None,
                 recalibration: LiveRecalibration | None = None,
                 snapshot_every_s: float = 600.0, provisional: bool = False,
                 rotor: LiveRotor | None = None) -> None:
        self.name = name
        self.model = model
        self.params = params
        self.gate = gate
        self.historian = historian
        self.rom = rom
        self.monitor = monitor
        self.monitored = tuple(monitored)
        self.sensitivity = sensitivity
        self.recalibration = recalibration
        self.rotor = rotor
        self._state: StreamState | None = None
        self._blocks: BlockAccumulator | None = None
        self._rewind = RewindBuffer()
        self.snapshot_every_s = snapshot_every_s
        self._started = False
        self._replay_from: pd.Timestamp | None = None
        self._committed: pd.Timestamp | None = None
        self._last_snapshot: pd.Timestamp | None = None
        self.provisional = provisional
        self._provisional_state: StreamState | None = None
        self._provisional_until: pd.Timestamp | None = None
        # what the provisional chain fed the model, chunk by chunk (times in ns since the epoch,
        # inputs with NaN rows where it had no twin value): one small array per sample, joined
        # only when a final block is checked against it
        self._provisional_times: list[np.ndarray] = []
        self._provisional_fed: list[np.ndarray] = []

    def start(self) -> LiveTwin:
        """Open the historian and continue from its last saved state, if any."""
        if not (math.isfinite(self.snapshot_every_s) and self.snapshot_every_s >= 0.0):
            raise ValueError(f"snapshot_every_s must be ≥ 0 s (got {self.snapshot_every_s!r})")
        self.historian.open()
        self._started = True
        self._committed = self.historian.resume_time(self.name)
        if self.monitor is not None:
            self._blocks = BlockAccumulator(self.monitor.settings.block_s)
        if self.recalibration is not None:
            self.recalibration.start()
        latest = self.historian.latest_state(self.name)
        if latest is None:
            return self
        self._replay_from, document = latest
        self._last_snapshot = self._replay_from
        if document.get("model") is not None:
            self._state = StreamState.from_dict(document["model"])
        self.gate.set_state(document.get("gate", {}))
        if document.get("params") is not None:
            self.params = ModelParameters(**document["params"])
        parts = ((self.monitor, "monitor"), (self._blocks, "blocks"), (self._rewind, "rewind"),
                 (self.sensitivity, "sensitivity"), (self.recalibration, "recalibration"),
                 (self.rotor, "rotor"))
        for part, key in parts:
            if part is not None and document.get(key) is not None:
                part.set_state(document[key])
        return self

    def acknowledge(self, alarm_id: int, by: str, at: pd.Timestamp | None = None) -> None:
        """Acknowledge stored alarm ``alarm_id`` as operator ``by`` at ``at`` (default: now,
        UTC); KeyError if there is no such alarm."""
        if not self._started:
            self.start()
        self.historian.acknowledge(alarm_id, by, at if at is not None
                                   else pd.Timestamp.now(tz="UTC"))

    def close(self) -> None:
        """Close the historian (what is committed stays; a restart continues from it)."""
        self.historian.close()
        self._started = False

    def resume_after(self) -> pd.Timestamp | None:
        """The time of the last saved state (UTC): the source must replay what comes after
        it (what was stored after it is recomputed, not stored again)."""
        if not self._started:
            latest = self.historian.latest_state(self.name)
            return None if latest is None else latest[0]
        return self._replay_from

    async def run(self, source: Source) -> LiveSummary:
        """Process every block ``source`` yields, then what the gate still holds."""
        if not self._started:
            self.start()
        summary = LiveSummary()
        async for block in source.blocks():
            self.process(block, summary)
        self.finish(summary)
        return summary

    def process(self, block: SourceBlock, summary: LiveSummary | None = None) -> LiveSummary:
        """One source block through gate, model, residuals and historian: :meth:`receive`
        then :meth:`settle`."""
        summary = self.receive(block, summary)
        return self.settle(summary)

    def receive(self, block: SourceBlock, summary: LiveSummary | None = None) -> LiveSummary:
        """Take a source block into the gate and, with ``provisional``, store the twin's
        provisional values of the samples still waiting for their look-ahead — the fast half
        of :meth:`process` (the service runs every unit's before any unit's :meth:`settle`)."""
        summary = summary if summary is not None else LiveSummary()
        rows = self.receive_rows(block, summary)
        if rows is not None:
            self.historian.store_provisional_many([rows])
        return summary

    def receive_rows(self, block: SourceBlock, summary: LiveSummary) -> ProvisionalRows | None:
        """:meth:`receive` without the write: the provisional rows for the caller to store
        (the service stores every unit's of a moment in one transaction,
        :meth:`LiveHistorian.store_provisional_many`) before this twin's next
        :meth:`receive_rows` or :meth:`settle`; None when there are none."""
        if not self._started:
            self.start()
        summary.findings += len(block.findings)
        if len(block.frame) == 0:
            return None
        resume = self._replay_from
        frame, bad = block.frame, block.bad
        if resume is not None and frame.index[0] <= resume:  # what the state has seen already
            keep = frame.index > resume
            frame, bad = frame[keep], bad[keep]
        if len(frame) == 0:
            return None
        self.gate.add(frame, bad)
        return self._provisional_rows() if self.provisional else None

    def settle(self, summary: LiveSummary | None = None, min_samples: int = 1) -> LiveSummary:
        """Judge, model and store the samples whose look-ahead is in, once there are at least
        ``min_samples`` of them (the slow half of :meth:`process`)."""
        summary = summary if summary is not None else LiveSummary()
        if self.gate.ready() >= max(min_samples, 1):
            self._store(self.gate.release(min_samples), summary)
        return summary

    def _provisional_rows(self) -> ProvisionalRows | None:
        """The twin on the gate's pending samples (verdicts that need no look-ahead: range,
        status, missing), continuing the provisional model state over the samples not yet
        given a value, or restarting it from the final state when the final verdicts took
        other inputs than the provisional ones (a spike or stuck run found), after a swap or
        a restart. The model state of the final chain is never touched. Positional slices and
        arrays throughout (a one-sample frame's label look-ups and boolean masks cost more
        than the model step: docs/benchmarks.md, "Latency, fourth pass")."""
        pending, flags = self.gate.pending()
        index = pending.index
        start = 0
        for after in (self.historian.resume_time(self.name), self._provisional_until):
            if after is not None:
                start = max(start, int(index.searchsorted(after, side="right")))
        if start >= len(index):
            return None
        index = index[start:]
        values = pending.to_numpy(dtype=float)[start:]
        inputs = values[:, _input_positions(pending.columns)]
        complete = ~np.isnan(inputs).any(axis=1)
        measured = pd.DataFrame(values, index=index, columns=pending.columns)
        first = self._provisional_state if self._provisional_until is not None else self._state
        twin, state, _ = self._predict(measured, complete, first, inputs=inputs)
        inputs[~complete] = np.nan
        self._provisional_times.append(index.as_unit("ns").asi8)
        self._provisional_fed.append(inputs)
        self._provisional_state, self._provisional_until = state, index[-1]
        return ProvisionalRows(self.name, {"measured": measured, "twin": twin,
                                           "residual": self._residual(measured, twin)},
                               _flag_objects(flags.iloc[start:]))

    def _check_provisional(self, data: pd.DataFrame, complete: np.ndarray) -> None:
        """Keep the provisional chain if the final samples ``data`` fed the model what the
        provisional values assumed; else restart it from the final state."""
        if not self._provisional_times:
            return
        times = np.concatenate(self._provisional_times)
        seen = np.concatenate(self._provisional_fed)
        final = _inputs(data)
        final[~complete] = np.nan
        final_times = data.index.as_unit("ns").asi8
        done = times <= final_times[-1]
        if np.array_equal(times[done], final_times) and np.array_equal(
                seen[done], final, equal_nan=True):
            self._provisional_times, self._provisional_fed = [times[~done]], [seen[~done]]
        else:
            self._reset_provisional()

    def _reset_provisional(self) -> None:
        self._provisional_state = None
        self._provisional_until = None
        self._provisional_times, self._provisional_fed = [], []

    def finish(self, summary: LiveSummary | None = None) -> LiveSummary:
        """The end of a stream: what the gate still holds (no more look-ahead)."""
        summary = summary if summary is not None else LiveSummary()
        self._store(self.gate.flush(), summary, final=True)
        return summary

    def _store(self, passed, summary: LiveSummary, final: bool = False) -> None:
        data = passed.data
        if data.empty:
            return
        summary.findings += len(passed.findings)
        starting = self.params  # before any swap this block makes
        complete = _complete(data)
        if self.provisional:
            self._check_provisional(data, complete)
        if complete.any() and self.recalibration is not None:
            self._rewind.keep(self._state, data[list(INPUT_SIGNALS)][complete],
                              2.0 * self.recalibration.tracker.step_s)
        twin, self._state, extrapolated = self._predict(data, complete, self._state,
                                                        rotor=self.rotor)
        summary.rom_extrapolated += extrapolated
        residual = self._residual(data, twin)
        alarms = [] if self.monitor is None else self._alarms(data, residual, final)
        swaps = [] if self.recalibration is None else self.recalibration.feed(data, self.params)
        if swaps:  # the last set applies from the next sample on; the block's earlier steps'
            swaps = swaps[-1:]  # sets applied to no sample, so only the last is recorded
            self._swap(swaps[0], data.index[-1])
        flags = _flag_objects(passed.flags)
        end = data.index[-1]
        snapshot = final or self._last_snapshot is None or (
            (end - self._last_snapshot).total_seconds() >= self.snapshot_every_s)
        committed = self._committed
        if committed is not None and data.index[0] <= committed:  # recomputed after a restart
            new = data.index > committed
            data, twin, residual, flags = data[new], twin[new], residual[new], flags[new]
            complete = complete[new]
            alarms = [a for a in alarms if (a.start if isinstance(a, Alarm) else a.end) > committed]
            swaps = [s for s in swaps if s.time > committed]
            if data.empty:
                return
        parameters = [(s.time, swap_values(s), s.reason, s.intervals) for s in swaps]
        if self.historian.resume_time(self.name) is None:  # the unit's first block
            parameters.insert(0, (data.index[0], {k: float(v) for k, v in
                                                  vars(starting).items()}, "start"))
        summary.rows += self.historian.commit_block(
            self.name, {"measured": data, "twin": twin, "residual": residual}, flags,
            state=self._snapshot() if snapshot else None,
            events=BlockEvents(tuple(alarms), tuple(parameters)))
        if snapshot:
            self._last_snapshot = end
        summary.alarms += sum(isinstance(alarm, Alarm) for alarm in alarms)
        summary.swaps += len(swaps)
        summary.samples += len(data)
        summary.without_twin += int((~complete).sum())

    def _predict(self, data: pd.DataFrame, complete: np.ndarray, state: StreamState | None,
                 rotor: LiveRotor | None = None, inputs: np.ndarray | None = None
                 ) -> tuple[pd.DataFrame, StreamState | None, int]:
        """Twin values of ``data`` (SI): the model's sensor readings, and the ROM's probe
        temperatures, where ``complete`` (all inputs good), NaN elsewhere; the model state
        after these samples (``state`` continued; unchanged without a complete sample); and the
        samples whose ROM probes were extrapolated; given ``rotor``, its signals
        (:data:`~steamtwin.live.rotor_stream.ROTOR_SIGNALS`) too. ``inputs``: the model inputs of
        ``data`` as :func:`_inputs` gives them, when the caller has them already. Built as one
        array (pandas ``.loc`` assignments per column cost more than the model on a 60-sample
        block)."""
        columns = list(self.model.output_signals)
        extra = [] if rotor is None else list(ROTOR_SIGNALS)
        if not complete.any():
            return (pd.DataFrame(np.nan, index=data.index, columns=columns + extra), state, 0)
        inputs = pd.DataFrame((_inputs(data) if inputs is None else inputs)[complete],
                              index=data.index[complete], columns=list(INPUT_SIGNALS))
        if rotor is None:
            outputs, state = self.model.simulate_stream(inputs, self.params, state)
        else:
            run, state = self.model.simulate_stream_detailed(inputs, self.params, state)
            outputs = run.outputs
        probes = [] if self.rom is None else [n for n in self.rom.probes if n not in columns]
        values = np.full((len(data), len(columns) + len(probes) + len(extra)), np.nan)
        values[complete, :len(columns)] = outputs.to_numpy(dtype=float)
        if rotor is not None:
            values[complete, values.shape[1] - len(extra):] = rotor.advance(
                self.model, inputs, run, self.params)
        extrapolated = 0
        if self.rom is not None:
            with _WARNING_FILTERS, warnings.catch_warnings():  # counted by the caller
                warnings.simplefilter("ignore", ExtrapolationWarning)
                predicted = predict_series(self.rom, data[complete]).sensors
            extrapolated = int(predicted[FLAG_EXTRAPOLATED].sum())
            valid = ~predicted[FLAG_INVALID].to_numpy(dtype=bool)
            rows = np.flatnonzero(complete)[valid]
            position = {name: j for j, name in enumerate(columns + probes)}
            for name in self.rom.probes:
                values[rows, position[name]] = predicted[name].to_numpy(dtype=float)[valid]
        return (pd.DataFrame(values, index=data.index, columns=columns + probes + extra), state,
                extrapolated)

    def _residual(self, data: pd.DataFrame, twin: pd.DataFrame) -> pd.DataFrame:
        """measured − twin (SI) of the monitored sensors both have."""
        sensors, measured, modelled = _shared(self.monitored, tuple(data.columns),
                                              tuple(twin.columns))
        return pd.DataFrame(data.to_numpy(dtype=float)[:, measured]
                            - twin.to_numpy(dtype=float)[:, modelled],
                            index=data.index, columns=sensors)

    def _swap(self, swap: ParameterSwap, last: pd.Timestamp) -> None:
        """Make ``swap``'s parameters live from the sample after ``last`` on. The model's
        carried state (metal temperatures, sensor lags) is recomputed with them from the start
        of the data the estimate rests on:
        a state grown under the old set would keep its metal a transient behind the plant's and
        show, for the casing's time constant, a residual that no sensor or parameter explains."""
        self.params = swap.params
        self._reset_provisional()
        if self.sensitivity is not None:
            self.sensitivity.clear()
        if self.monitor is not None:  # a degradation's swap is a known change: re-base
            self.monitor.restart(last if swap.reason.startswith("degradation") else None)
        assert self.recalibration is not None
        since = swap.time - pd.Timedelta(seconds=self.recalibration.tracker.step_s)
        replayed = self._rewind.replay(self.model, self.params, since)
        if replayed is not None:
            self._state = replayed

    def _snapshot(self) -> dict:
        parts = {"model": self._state, "monitor": self.monitor, "blocks": self._blocks,
                 "rewind": self._rewind if self.recalibration is not None else None,
                 "sensitivity": self.sensitivity, "recalibration": self.recalibration,
                 "rotor": self.rotor}
        state = {key: None if part is None else (part.to_dict() if key == "model"
                                                 else part.get_state())
                 for key, part in parts.items()}
        return {**state, "gate": self.gate.get_state(),
                "params": {k: float(v) for k, v in vars(self.params).items()}}

    def _alarms(self, data: pd.DataFrame, residual: pd.DataFrame, final: bool
                ) -> list[Alarm | AlarmEnd]:
        assert self.monitor is not None and self._blocks is not None
        frame = residual.join(data[list(INPUT_SIGNALS)])
        rated = self.model.spec.design.generator_power
        frame["load"] = data["load"] / rated if "load" in data.columns else np.nan
        blocks = self._blocks.push(frame) + (self._blocks.flush() if final else [])
        alarms: list[Alarm | AlarmEnd] = []
        for block in blocks:
            for event in self._monitor_block(block, list(residual.columns)):
                if self.recalibration is not None:
                    self.recalibration.on_alarm(event.kind, event.signal, event.time,
                                                event.ended)
                if event.ended:
                    alarms.append(AlarmEnd(event.kind, event.signal, event.time))
                else:
                    alarms.append(Alarm(self.name, event.kind, event.time, event.signal,
                                        evidence={"statistic": event.statistic,
                                                  "threshold": event.threshold,
                                                  "standardised": event.evidence}))
        return alarms

    def _monitor_block(self, block: Block, sensors: list[str]) -> list[AlarmEvent]:
        assert self.monitor is not None
        load = float(block.means["load"])
        sensitivity = (None if self.sensitivity is None
                       else self.sensitivity.get(load, block.rows, self.params))
        # a partial block (a gap, rejected samples, a stream's last bin) weighs less
        nominal = self.monitor.settings.block_s / self.gate.nominal_step_s
        return self.monitor.update(block.end, block.means[sensors], sensitivity,
                                   load=load if np.isfinite(load) else None,
                                   coverage=(block.counts[sensors] / nominal).to_dict())


def _inputs(data: pd.DataFrame) -> np.ndarray:
    """The model inputs of ``data`` as an array (columns in INPUT_SIGNALS order; positional
    look-ups: pandas' label indexing costs more than a one-sample model step)."""
    return data.to_numpy(dtype=float)[:, _input_positions(data.columns)]


def _input_positions(columns: pd.Index) -> list[int]:
    """Where the model inputs are among ``columns`` (INPUT_SIGNALS order)."""
    return _positions(tuple(columns))


@functools.lru_cache(maxsize=64)
def _positions(columns: tuple) -> list[int]:
    """:func:`_input_positions` by the columns' names (a stream's frames all have the same:
    the look-up is made once)."""
    where = {name: j for j, name in enumerate(columns)}
    missing = [name for name in INPUT_SIGNALS if name not in where]
    if missing:
        raise KeyError(f"the data lack the model input(s) {missing}")
    return [where[name] for name in INPUT_SIGNALS]


@functools.lru_cache(maxsize=64)
def _shared(sensors: tuple[str, ...], measured: tuple, modelled: tuple
            ) -> tuple[list[str], list[int], list[int]]:
    """The ``sensors`` found among both column tuples, and their positions in each (a
    stream's frames all have the same columns: the look-up is made once)."""
    found = [name for name in sensors if name in measured and name in modelled]
    return (found, [measured.index(name) for name in found],
            [modelled.index(name) for name in found])


def _complete(data: pd.DataFrame) -> np.ndarray:
    """True for the samples whose model inputs are all present (not NaN)."""
    return ~np.isnan(_inputs(data)).any(axis=1)


def _flag_objects(flags: pd.DataFrame) -> pd.DataFrame:
    """The gate's flag bits as the historian stores them: the code where set, None where 0."""
    codes = flags.to_numpy()
    return pd.DataFrame(np.where(codes != 0, codes.astype(float), np.nan).astype(object),
                        index=flags.index, columns=flags.columns)
