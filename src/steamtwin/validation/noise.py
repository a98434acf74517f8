"""Propagation of main-steam temperature noise through the full-order model.

Zero-mean white Gaussian noise of standard deviation σ (K) — independent per sample and per
repeat — is added to the ``main_steam_temperature`` input; each output signal of the noisy run is
compared with the noise-free run of the same parameters, sample by sample.

What the physics predicts
    The steam path is quasi-steady, so the steam temperatures answer each sample's inlet
    temperature at once. At a fixed pressure ratio an expansion keeps T_out/T_in nearly
    constant, so ∂T_out/∂T_in ≈ T_out/T_in: close to 1 at the control stage, ~0.7 at the HP
    exhaust (≈ 585 K / 811 K at rated load). The steam temperatures therefore carry the noise
    with a gain (RMS deviation / σ) of about 0.7–1. The casing metal integrates the heat it
    receives over its thermal time constant (minutes to hours) and so filters white noise: its
    deviation is a small fraction of the steam's. Pressures and power move only through the
    specific volume and the enthalpy drop, by ~0.05–0.3 % per K.

Measured on the reference unit (ramps to 30–40 % load at 3 %/min, 1-s samples): gain 1.01 at
the control stage, 0.68 at the HP exhaust, 0.07–0.08 for the casing metal; σ = 1 K gives twice
the deviation of σ = 0.5 K to within 1 % (``tests/validation/test_noise.py``,
``benchmarks/bench_sensitivity.py``).

Design choices
    The first sample is left noise-free: the model starts the metal in equilibrium with it, and
    a noisy start would offset the metal for its whole time constant. Every σ reuses the same
    unit-normal draws (common random numbers), so the ratio of deviations between two σ
    measures the model's nonlinearity alone, not the sampling scatter of the noise.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import Simulator

__all__ = ["NOISY_INPUT", "noise_figure", "noise_propagation"]

NOISY_INPUT = "main_steam_temperature"
"""The input the noise is added to (K)."""


def _unit_noise(samples: int, repeats: int, random_state: int) -> np.ndarray:
    """Standard-normal draws (repeats, samples), the first sample of each repeat zero."""
    noise = np.random.default_rng(random_state).standard_normal((repeats, samples))
    noise[:, 0] = 0.0
    return noise


def _check(simulator: Simulator, inputs: pd.DataFrame, sigmas_K: Sequence[float], repeats: int,
           random_state: int) -> tuple[float, ...]:
    if not isinstance(inputs, pd.DataFrame) or len(inputs) < 2:
        raise ValueError("inputs must be a DataFrame of canonical SI signals with ≥ 2 rows")
    if NOISY_INPUT not in simulator.input_signals or NOISY_INPUT not in inputs.columns:
        raise ValueError(f"inputs (and the simulator's input signals) must include "
                         f"{NOISY_INPUT!r}")
    sigmas = tuple(float(s) for s in sigmas_K)
    if not sigmas or not all(np.isfinite(s) and s > 0.0 for s in sigmas):
        raise ValueError(f"sigmas_K must be finite standard deviations > 0 K (got {sigmas_K!r})")
    for name, value in (("repeats", repeats), ("random_state", random_state)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
            raise ValueError(f"{name} must be an integer ≥ 0 (got {value!r})")
    if repeats < 1:
        raise ValueError("repeats must be ≥ 1")
    return sigmas


def _deviation(simulator: Simulator, inputs: pd.DataFrame, params: ModelParameters,
               clean: np.ndarray, noise_K: np.ndarray) -> np.ndarray:
    """Outputs of the run with ``noise_K`` added to the noisy input, minus ``clean``."""
    noisy = inputs.copy()
    noisy[NOISY_INPUT] = inputs[NOISY_INPUT].to_numpy(dtype=float) + noise_K
    outputs = simulator.simulate(noisy, params)[list(simulator.output_signals)]
    return outputs.to_numpy(dtype=float) - clean


def noise_propagation(simulator: Simulator, inputs: pd.DataFrame,
                      params: ModelParameters | None = None, *,
                      sigmas_K: Sequence[float] = (0.5, 1.0), repeats: int = 4,
                      random_state: int = 0) -> pd.DataFrame:
    """Deviation of every output signal when white noise of σ (K) is added to the main-steam
    temperature (see the module docstring for the method and the physics to expect).

    One row per (``sigma_K``, ``output``), pooled over ``repeats`` noisy runs and all samples:
    ``mean_abs_deviation``, ``max_abs_deviation`` and ``rms_deviation`` (unit of the output:
    K, Pa, W) and ``gain`` = rms_deviation/σ (output unit per K). The same ``random_state``
    gives the same table. Runs 1 + repeats·len(sigmas_K) simulations.
    """
    sigmas = _check(simulator, inputs, sigmas_K, repeats, random_state)
    params = params or ModelParameters()
    clean = simulator.simulate(inputs, params)[list(simulator.output_signals)].to_numpy(
        dtype=float)
    unit = _unit_noise(len(inputs), int(repeats), int(random_state))
    rows = []
    for sigma in sigmas:
        deviation = np.concatenate([_deviation(simulator, inputs, params, clean, sigma * draw)
                                    for draw in unit])
        rms = np.sqrt(np.mean(deviation**2, axis=0))
        for k, output in enumerate(simulator.output_signals):
            rows.append({"sigma_K": sigma, "output": output,
                         "mean_abs_deviation": float(np.mean(np.abs(deviation[:, k]))),
                         "max_abs_deviation": float(np.max(np.abs(deviation[:, k]))),
                         "rms_deviation": float(rms[k]), "gain": float(rms[k] / sigma)})
    return pd.DataFrame(rows).set_index(["sigma_K", "output"])


def noise_figure(simulator: Simulator, inputs: pd.DataFrame, path: str | Path,
                 params: ModelParameters | None = None, *, sigma_K: float = 1.0,
                 minutes: float = 5.0, random_state: int = 0,
                 outputs: Sequence[str] = ("hp_exhaust_temperature",
                                           "hp_inner_casing_temperature")) -> Path:
    """Write a PNG of the first ``minutes`` of ``inputs``: the main-steam temperature noise (K)
    above, the deviation of ``outputs`` (temperatures, K) from the noise-free run below."""
    _check(simulator, inputs, (sigma_K,), 1, random_state)
    unknown = [name for name in outputs if name not in simulator.output_signals]
    if unknown or not outputs:
        raise ValueError(f"outputs must be some of {list(simulator.output_signals)} "
                         f"(got {list(outputs)})")
    index = inputs.index
    if isinstance(index, pd.DatetimeIndex):
        index = index - index[0]
    seconds = (index.total_seconds().to_numpy(dtype=float) if isinstance(index, pd.TimedeltaIndex)
               else np.asarray(index, dtype=float) - float(index[0]))
    window = inputs.iloc[: max(2, int(np.searchsorted(seconds, 60.0 * minutes, "right")))]
    params = params or ModelParameters()
    clean = simulator.simulate(window, params)[list(simulator.output_signals)].to_numpy(
        dtype=float)
    noise = float(sigma_K) * _unit_noise(len(window), 1, int(random_state))[0]
    deviation = _deviation(simulator, window, params, clean, noise)
    minute = seconds[: len(window)] / 60.0
    path = Path(path)
    figure = Figure(figsize=(8.0, 5.5))
    top, bottom = figure.subplots(2, 1, sharex=True)
    top.plot(minute, noise, color="0.4", lw=0.7)
    top.set(ylabel="main-steam temperature\nnoise (K)",
            title=f"White noise σ = {sigma_K:g} K on the main-steam temperature")
    for name in outputs:
        k = simulator.output_signals.index(name)
        rms = float(np.sqrt(np.mean(deviation[:, k] ** 2)))
        bottom.plot(minute, deviation[:, k], lw=0.8,
                    label=f"{name.replace('_', ' ')} (RMS {rms:.3f})")
    bottom.set(xlabel="time (min)", ylabel="output − noise-free run (K)")
    bottom.legend(fontsize=8)
    for axis in (top, bottom):
        axis.axhline(0.0, color="black", lw=0.6)
        axis.grid(alpha=0.3)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    return path
