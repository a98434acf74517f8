"""MAP and Laplace intervals on synthetic data from a small model with known parameters."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from steamtwin.calibration.calibrator import Calibrator, write_parameters
from steamtwin.calibration.objective import CalibrationProblem
from steamtwin.calibration.posterior import (
    InputUncertainty,
    fit_map,
    laplace_posterior,
    likelihood_tempering,
    metropolis,
)
from steamtwin.calibration.search import GeneticSearch
from steamtwin.calibration.settings import PARAMETER_NAMES, THERMOCOUPLE_BIAS, ObjectiveSettings
from steamtwin.calibration.windowprep import thermocouple_bias_spread
from steamtwin.calibration.windowset import CalibrationWindow, WindowSet
from steamtwin.model.parameters import (
    DEFAULT_PRIORS,
    ModelParameters,
    ParameterError,
    parse_prior,
    priors_from_dict,
    sensor_offsets_from_json,
)
from steamtwin.model.simulator import INPUT_SIGNALS

pytestmark = pytest.mark.slow  # 6 s of the full suite (2026-11-27): not in the quick loop

SENSORS = ("control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature")
RATED_FLOW = 500.0  # kg/s
TRUTH = ModelParameters(1.03, 1.25, 1.4)
SIGMA = {name: 0.5 for name in SENSORS}  # K
MAP = ObjectiveSettings(sensors=SENSORS, min_samples=30)  # the default priors
BIASED = replace(MAP, sensor_bias=THERMOCOUPLE_BIAS)
TWO = GeneticSearch(population=6, generations=2)
ONE = GeneticSearch(population=6, generations=1)


class LagSimulator:
    """Small model in which heat transfer acts only through the metal's lag.

    Control stage: T0 − 60 − 80·φ·(1.2 − f); exhaust: T0 − 250 + 15·ψ·√f + 5·φ (f = flow /
    rated); casing metal: the exhaust steam through a first-order lag of time constant
    900 s / h (exact discretisation), started in equilibrium — on constant inputs the metal
    equals the steam and h is invisible.
    """

    input_signals = INPUT_SIGNALS
    output_signals = SENSORS

    def check_inputs(self, inputs: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, float]:
        step = (inputs.index[1] - inputs.index[0]).total_seconds()  # uniform sampling
        return (inputs["main_steam_temperature"].to_numpy(dtype=float),
                inputs["main_steam_flow"].to_numpy(dtype=float) / RATED_FLOW, step)

    def simulate_checked(self, checked: tuple[np.ndarray, np.ndarray, float],
                         params: ModelParameters, signals: tuple[str, ...]) -> np.ndarray:
        t0, f, step = checked
        control = t0 - 60.0 - 80.0 * params.flow_coefficient * (1.2 - f)
        exhaust = (t0 - 250.0 + 15.0 * params.friction_coefficient * np.sqrt(f)
                   + 5.0 * params.flow_coefficient)
        a = math.exp(-step / (900.0 / params.heat_transfer_coefficient))
        metal, _ = lfilter([1.0 - a], [1.0, -a], exhaust, zi=[a * exhaust[0]])
        outputs = dict(zip(SENSORS, (control, exhaust, metal), strict=True))
        return np.column_stack([outputs[name] for name in signals])

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        values = self.simulate_checked(self.check_inputs(inputs), params, SENSORS)
        return pd.DataFrame(values, columns=list(SENSORS), index=inputs.index)


def _inputs(load: np.ndarray, start: str) -> pd.DataFrame:
    index = pd.date_range(start, periods=load.size, freq="10s", tz="UTC")
    return pd.DataFrame({"main_steam_pressure": 16.0e6 * load, "main_steam_temperature": 810.0,
                         "main_steam_flow": RATED_FLOW * load, "hp_exhaust_pressure": 3.5e6,
                         "load": 600.0e6 * load}, index=index)


def _measured(inputs: pd.DataFrame, random: np.random.Generator) -> pd.DataFrame:
    truth = LagSimulator().simulate(inputs, TRUTH)
    return pd.concat([inputs, truth + random.normal(0.0, 0.5, truth.shape)], axis=1)


def _steady(load: float, start: str, n: int = 90) -> pd.DataFrame:
    return _inputs(np.full(n, load), start)


def _ramp(start: str) -> pd.DataFrame:
    """10 min at 50 %, a 20-min ramp to 100 %, 30 min at 100 % (10-s samples)."""
    load = np.concatenate([np.full(60, 0.5), np.linspace(0.5, 1.0, 120), np.full(180, 1.0)])
    return _inputs(load, start)


STEADY = [(0.3, "2026-01-01"), (0.5, "2026-01-02"), (0.75, "2026-01-03"), (1.0, "2026-01-04")]


def _window_set(random: np.random.Generator, ramp: bool = True) -> WindowSet:
    frames = [(_measured(_steady(load, day), random), "steady", load) for load, day in STEADY]
    if ramp:
        frames.append((_measured(_ramp("2026-01-05"), random), "ramp", 0.75))
    return WindowSet(tuple(CalibrationWindow(f, kind, load, "synthetic", SIGMA)
                           for f, kind, load in frames))


def _objective(windows: WindowSet):
    return CalibrationProblem(LagSimulator(), windows, MAP).objective


def test_map_recovers_the_parameters_and_the_intervals_cover_the_truth():
    covered = dict.fromkeys(PARAMETER_NAMES, 0)
    draws = 20
    errors = []
    for seed in range(draws):
        objective = _objective(_window_set(np.random.default_rng(seed)))
        estimate = fit_map(objective)
        table = laplace_posterior(objective, estimate).table()
        assert abs(estimate.flow_coefficient - TRUTH.flow_coefficient) < 0.01
        assert abs(estimate.friction_coefficient - TRUTH.friction_coefficient) < 0.1
        errors.append([(getattr(estimate, n) - getattr(TRUTH, n))
                       / (table.loc[n, "high"] - table.loc[n, "low"]) for n in PARAMETER_NAMES])
        for name in PARAMETER_NAMES:
            covered[name] += table.loc[name, "low"] <= getattr(TRUTH, name) <= \
                table.loc[name, "high"]
            assert table.loc[name, "shrinkage"] < 0.5  # the ramp identifies all three
    for name in PARAMETER_NAMES:
        assert covered[name] >= 0.9 * draws, (name, covered)
    # not vacuous: the intervals are as wide as the scatter of the estimates, not wider
    # (a 95 % interval spans ≈ 4 σ; the estimates' spread is σ)
    spread = np.std(errors, axis=0)
    assert ((spread > 0.12) & (spread < 0.45)).all(), spread


def test_heat_transfer_unseen_on_steady_windows_stays_at_its_prior():
    objective = _objective(_window_set(np.random.default_rng(3), ramp=False))
    estimate = fit_map(objective)
    table = laplace_posterior(objective, estimate).table()
    prior = DEFAULT_PRIORS["heat_transfer_coefficient"]
    assert estimate.heat_transfer_coefficient == pytest.approx(prior.center, abs=1e-3)
    row = table.loc["heat_transfer_coefficient"]
    assert row["shrinkage"] == pytest.approx(1.0, abs=1e-3)
    assert (row["low"], row["high"]) == pytest.approx(prior.interval(), rel=1e-3)
    # the seen ones are still recovered and narrow
    assert abs(estimate.flow_coefficient - TRUTH.flow_coefficient) < 0.01
    assert table.loc["flow_coefficient", "shrinkage"] < 0.1


def test_duplicating_a_loads_windows_changes_nothing():
    random = np.random.default_rng(5)
    base = _window_set(random)
    fifty = base.windows[1]
    doubled = WindowSet((*base.windows, fifty, fifty))
    weights = doubled.sample_weights()
    bands = doubled.bands()
    n = np.array([len(w.data) for w in doubled])
    per_band = {b: sum(w * k for w, k, lab in zip(weights, n, bands, strict=True) if lab == b)
                for b in set(bands)}
    assert len(set(np.round(list(per_band.values()), 9))) == 1  # every band weighs the same
    one, two = _objective(base), _objective(doubled)
    for x in ([1.0, 1.0, 1.0], [1.05, 0.8, 1.6], [0.95, 1.7, 0.6]):
        assert two.evaluate(x).value == pytest.approx(one.evaluate(x).value, rel=1e-12)
        assert two.evaluate(x).rmse == pytest.approx(one.evaluate(x).rmse, rel=1e-12)
    map_one, map_two = fit_map(one), fit_map(two)
    for name in PARAMETER_NAMES:
        assert getattr(map_two, name) == pytest.approx(getattr(map_one, name), rel=1e-6)
    unweighted = CalibrationProblem(LagSimulator(), [w.data for w in doubled], MAP).objective
    assert unweighted.evaluate([1.05, 0.8, 1.6]).value != pytest.approx(
        one.evaluate([1.05, 0.8, 1.6]).value, rel=1e-6)  # without band weights it would


def test_metropolis_agrees_with_laplace():
    objective = _objective(_window_set(np.random.default_rng(11)))
    estimate = fit_map(objective)
    posterior = laplace_posterior(objective, estimate, inflate=False)
    priors = [DEFAULT_PRIORS[name] for name in PARAMETER_NAMES]

    def log_posterior(theta: np.ndarray) -> float:
        x = [p.from_internal(t) for p, t in zip(priors, theta, strict=True)]
        try:
            params = ModelParameters(*x)
        except ParameterError:
            return -math.inf
        residuals = objective.standardised_residuals(params)
        return -0.5 * (residuals @ residuals + (objective.prior_terms(x) ** 2).sum())

    chain = metropolis(log_posterior, posterior.theta, posterior.covariance, 2000,
                       random_state=1)[400:]
    laplace_std = np.sqrt(np.diag(posterior.covariance))
    np.testing.assert_array_less(np.abs(chain.mean(axis=0) - posterior.theta), 0.3 * laplace_std)
    np.testing.assert_allclose(chain.std(axis=0), laplace_std, rtol=0.3)


def test_parameter_file_carries_priors_and_intervals_and_old_files_load(tmp_path):
    objective = _objective(_window_set(np.random.default_rng(2)))
    estimate = fit_map(objective)
    posterior = laplace_posterior(objective, estimate)
    path, _ = write_parameters(tmp_path / "p.json", estimate, 0.5, SENSORS, 10, {},
                               pd.DataFrame({"generation": [1]}), DEFAULT_PRIORS, posterior)
    document = json.loads(path.read_text())
    assert document["schema_version"] == 2
    interval = document["posterior"]["intervals"]["flow_coefficient"]
    assert interval["low"] < estimate.flow_coefficient < interval["high"]
    assert ModelParameters.from_json(path) == estimate
    assert priors_from_dict(document["priors"]) == {
        name: prior for name, prior in DEFAULT_PRIORS.items()}
    old = tmp_path / "old.json"
    old.write_text(json.dumps({"parameters": {"flow_coefficient": 1.0,
                                              "friction_coefficient": 1.0,
                                              "heat_transfer_coefficient": 1.0}}))
    assert ModelParameters.from_json(old) == ModelParameters()
    newer = tmp_path / "newer.json"
    newer.write_text(json.dumps({**document, "schema_version": 3}))
    with pytest.raises(ParameterError, match="schema_version"):
        ModelParameters.from_json(newer)


def test_prior_overrides_are_checked():
    name, prior = parse_prior("flow_coefficient=normal:1.0:0.03")
    assert (name, prior.spread) == ("flow_coefficient", 0.03)
    with pytest.raises(ParameterError, match="unknown parameter"):
        parse_prior("flow=normal:1:0.1")
    with pytest.raises(ParameterError, match="expected NAME="):
        parse_prior("flow_coefficient=normal:1")
    with pytest.raises(ParameterError, match="> 0"):
        parse_prior("flow_coefficient=normal:1:-0.1")
    with pytest.raises(ParameterError, match=r"priors\.friction_coefficient"):
        priors_from_dict({"friction_coefficient": {"distribution": "uniform"}}, "p.json")
    with pytest.raises(ParameterError, match="did you mean"):
        priors_from_dict({"flow_coefficent": {"spread": 0.1}}, "p.json")


def _biased(seed: int) -> tuple[WindowSet, dict[str, float]]:
    """A window set whose thermocouples carry class-1 biases drawn uniformly in ± tolerance."""
    random = np.random.default_rng(100 + seed)
    windows = _window_set(random)
    bias = {}
    for sensor in SENSORS:
        level = np.mean(np.concatenate([w.data[sensor].to_numpy() for w in windows]))
        tolerance = thermocouple_bias_spread(level) * math.sqrt(3.0)
        bias[sensor] = random.uniform(-tolerance, tolerance)
    return WindowSet(tuple(
        CalibrationWindow(w.data.assign(**{s: w.data[s] + bias[s] for s in SENSORS}), w.kind,
                          w.load_fraction, w.source, w.sigma) for w in windows)), bias


def test_thermocouple_biases_are_integrated_out_and_intervals_stay_honest():
    covered = {mode: dict.fromkeys(PARAMETER_NAMES, 0) for mode in (THERMOCOUPLE_BIAS, None)}
    draws = 20
    for seed in range(draws):
        windows, bias = _biased(seed)
        for mode in covered:
            objective = CalibrationProblem(LagSimulator(), windows,
                                           replace(MAP, sensor_bias=mode)).objective
            estimate = fit_map(objective)
            table = laplace_posterior(objective, estimate).table()
            for name in PARAMETER_NAMES:
                covered[mode][name] += table.loc[name, "low"] <= getattr(TRUTH, name) <= \
                    table.loc[name, "high"]
            if mode is not None:
                # χ² is the sum of squares of the profiled residuals (the Gauss–Newton form)
                x = [getattr(estimate, n) for n in PARAMETER_NAMES]
                result = objective.evaluate(x)
                residuals = objective.standardised_residuals(estimate)
                assert result.value**2 * objective.weighted_count() == pytest.approx(
                    residuals @ residuals + (objective.prior_terms(x) ** 2).sum(), rel=1e-9)
                estimated = objective.sensor_biases(estimate)[0]
                np.testing.assert_allclose(estimated, [bias[s] for s in SENSORS], atol=0.15)
    assert all(n >= 0.9 * draws for n in covered[THERMOCOUPLE_BIAS].values()), covered
    # counted as noise, the biases pose as information: the intervals miss the truth
    assert all(n <= 0.5 * draws for n in covered[None].values()), covered


def test_a_model_missing_the_data_by_more_than_sigma_widens_the_intervals():
    """σ stated 3× too small (as when the twin's own error exceeds the instruments'): the
    Birge ratio restores coverage; without it the intervals are 3× too narrow."""
    covered = {True: 0, False: 0}
    draws = 20
    understated = {name: 0.5 / 3.0 for name in SENSORS}
    for seed in range(draws):
        windows = _window_set(np.random.default_rng(200 + seed))
        windows = WindowSet(tuple(CalibrationWindow(w.data, w.kind, w.load_fraction, w.source,
                                                    understated) for w in windows))
        objective = _objective(windows)
        estimate = fit_map(objective)
        for inflate in covered:
            row = laplace_posterior(objective, estimate, inflate=inflate).table().loc[
                "flow_coefficient"]
            covered[inflate] += row["low"] <= TRUTH.flow_coefficient <= row["high"]
        assert laplace_posterior(objective, estimate).scale_factor == pytest.approx(3.0, rel=0.1)
    assert covered[True] >= 0.9 * draws and covered[False] <= 0.7 * draws, covered


def test_likelihood_tempering_is_one_for_honest_residuals_and_shrinks_otherwise():
    honest = _objective(_window_set(np.random.default_rng(7)))
    assert likelihood_tempering(honest, TRUTH) == pytest.approx(1.0, abs=0.35)
    windows = WindowSet(tuple(CalibrationWindow(w.data, w.kind, w.load_fraction, w.source,
                                                {s: 0.5 / 3.0 for s in SENSORS})
                              for w in _window_set(np.random.default_rng(7))))
    understated = _objective(windows)
    kappa = likelihood_tempering(understated, TRUTH)
    assert kappa == pytest.approx(1.0 / 9.0, rel=0.35)
    # a tempered objective gives the same interval (κ is taken out and put back as 1/(τ S²))
    tempered = replace(understated, tempering=kappa)
    plain = laplace_posterior(understated, TRUTH).table()
    again = laplace_posterior(tempered, TRUTH).table()
    np.testing.assert_allclose(again["std"], plain["std"], rtol=1e-6)


def test_calibrator_tempering_setting(tmp_path):
    windows = _window_set(np.random.default_rng(8))
    fitted = Calibrator(LagSimulator(), objective=MAP, search=TWO, workers=1).fit(windows)
    assert 0.0 < fitted.tempering_ <= 1.0
    assert Calibrator(LagSimulator(), objective=replace(MAP, priors=None), search=ONE,
                      workers=1).fit(windows).tempering_ == 1.0
    fixed = Calibrator(LagSimulator(), objective=replace(MAP, tempering=0.25), search=ONE,
                       workers=1).fit(windows)
    assert fixed.tempering_ == 0.25
    with pytest.raises(ValueError, match="tempering must be"):
        replace(MAP, tempering=2.0)


def test_a_biased_input_moves_the_map_as_the_propagated_uncertainty_says():
    """Implicit-function theorem: refitting on inputs moved by an input's standard uncertainty
    u shifts the MAP by g = H⁻¹Jᵀ(∂r/∂u)u, whose outer product the posterior adds; the shift
    of a real refit on biased data matches √diag of that term in size and the intervals
    widen by it."""
    windows = _window_set(np.random.default_rng(3), ramp=True)
    objective = _objective(windows)
    estimate = fit_map(objective)
    flow = {"main_steam_flow": InputUncertainty("relative", 0.01, "test: 1 % of reading")}
    plain = laplace_posterior(objective, estimate, inflate=False)
    carried = laplace_posterior(objective, estimate, inflate=False, inputs=flow)
    np.testing.assert_array_equal(carried.covariance, plain.covariance)
    biased = WindowSet(tuple(replace(w, data=w.data.assign(
        main_steam_flow=w.data["main_steam_flow"] * 1.01)) for w in windows))
    refit = fit_map(_objective(biased), start=estimate)
    table, spread = carried.table(), np.sqrt(np.diag(carried.input_covariance))
    for i, name in enumerate(PARAMETER_NAMES):
        prior = DEFAULT_PRIORS[name]
        shift = prior.to_internal(getattr(refit, name)) - prior.to_internal(getattr(estimate,
                                                                                      name))
        assert abs(shift) == pytest.approx(spread[i], rel=0.05, abs=1e-4 * prior.spread), name
        assert table.loc[name, "input_std"] == pytest.approx(spread[i])
    assert spread[0] > 0.005  # the toy's φ·f term: a 1 % flow error is ≈ 1 % of φ
    assert table.loc["flow_coefficient", "std"] > plain.table().loc["flow_coefficient", "std"]
    document = carried.to_dict()
    assert document["input_uncertainties"] == {"main_steam_flow": "test: 1 % of reading"}
    assert document["intervals"]["flow_coefficient"]["input_std"] == pytest.approx(spread[0])


def test_inputs_the_model_does_not_take_are_not_propagated():
    objective = _objective(_window_set(np.random.default_rng(4), ramp=False))
    estimate = fit_map(objective)
    other = {"reheat_pressure": InputUncertainty("relative", 0.01, "not an input")}
    posterior = laplace_posterior(objective, estimate, inputs=other)
    assert posterior.input_sources == ()
    np.testing.assert_array_equal(posterior.total_covariance, posterior.covariance)


class PickySimulator(LagSimulator):
    """LagSimulator that refuses a flow outside (0, 1.5 × rated)."""

    def check_inputs(self, inputs: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, float]:
        flow = inputs["main_steam_flow"].to_numpy(dtype=float)
        if not ((flow > 0.0) & (flow < 1.5 * RATED_FLOW)).all():
            raise ValueError("main_steam_flow outside what the valves pass")
        return super().check_inputs(inputs)


def test_an_input_the_model_rejects_moved_either_way_is_said_not_propagated():
    windows = _window_set(np.random.default_rng(5), ramp=False)
    objective = CalibrationProblem(PickySimulator(), windows, MAP).objective
    estimate = fit_map(objective)
    huge = {"main_steam_flow": InputUncertainty("relative", 2.0, "test: 200 %")}
    posterior = laplace_posterior(objective, estimate, inputs=huge)
    assert posterior.input_sources[0][1].startswith("not propagated")
    np.testing.assert_array_equal(posterior.total_covariance, posterior.covariance)
    with pytest.raises(ValueError, match="kind must be"):
        InputUncertainty("absolute", 1.0, "no such kind")


def test_sensor_offsets_recover_the_sensors_biases_and_reach_the_parameter_file(tmp_path):
    """Windows whose thermocouples read +0.8 / −1.1 / +0.3 K off: the pooled offsets at the
    true parameters are those biases (within the noise's 0.5 K/√n and the prior's pull), the
    calibrators write them into params.json and sensor_offsets_from_json reads them back."""
    bias = {"control_stage_temperature": 0.8, "hp_exhaust_temperature": -1.1,
            "hp_inner_casing_temperature": 0.3}
    windows = WindowSet(tuple(replace(w, data=w.data.assign(**{
        name: w.data[name] + value for name, value in bias.items()}))
        for w in _window_set(np.random.default_rng(6), ramp=True)))
    problem = CalibrationProblem(LagSimulator(), windows, BIASED)
    offsets = problem.objective.sensor_offsets(TRUTH)
    assert offsets.keys() == bias.keys()
    for name, value in bias.items():
        assert offsets[name] == pytest.approx(value, abs=0.1)
    unbiased = CalibrationProblem(LagSimulator(), windows, replace(MAP, priors=None))
    assert unbiased.objective.sensor_offsets(TRUTH) == {}
    calibrator = Calibrator(LagSimulator(), objective=BIASED, search=TWO, workers=1).fit(windows)
    path, _ = calibrator.save(tmp_path / "params.json")
    assert sensor_offsets_from_json(path) == pytest.approx(calibrator.sensor_offsets_)
    assert set(calibrator.sensor_offsets_) == set(bias)
    document = json.loads(path.read_text())
    document["sensor_offsets"]["hp_exhaust_temperature"] = 40.0
    (tmp_path / "bad.json").write_text(json.dumps(document))
    with pytest.raises(ParameterError, match=r"sensor_offsets\.hp_exhaust_temperature = 40"):
        sensor_offsets_from_json(tmp_path / "bad.json")
    # a pressure witness's offset is in Pa (a transmitter's, within 375 kPa), not K: what a
    # calibration with the control-stage pressure and sensor biases writes reads back
    document["sensor_offsets"] = {"control_stage_pressure": 2149.0}
    (tmp_path / "pressure.json").write_text(json.dumps(document))
    assert sensor_offsets_from_json(tmp_path / "pressure.json") == {
        "control_stage_pressure": 2149.0}
    document["sensor_offsets"] = {"control_stage_pressure": 4.0e5}
    (tmp_path / "pressure.json").write_text(json.dumps(document))
    with pytest.raises(ParameterError, match=r"expected a number of Pa within ±375000"):
        sensor_offsets_from_json(tmp_path / "pressure.json")


def _full_load_discrepancy(seed: int, kelvin: float) -> WindowSet:
    """The window set with the exhaust and casing readings of the 100 % hold ``kelvin`` off:
    a model error local to one load, as the plant's casing thermocouple shows at full load
    (docs/benchmarks.md, "A day the twin has not seen")."""
    def shifted(window: CalibrationWindow) -> CalibrationWindow:
        if window.kind != "steady" or window.load_fraction != 1.0:
            return window
        return replace(window, data=window.data.assign(**{
            name: window.data[name] + kelvin
            for name in ("hp_exhaust_temperature", "hp_inner_casing_temperature")}))
    return WindowSet(tuple(shifted(w) for w in _window_set(np.random.default_rng(seed))))


def _robust_posterior(windows: WindowSet):
    objective = CalibrationProblem(LagSimulator(), windows, BIASED).objective
    estimate = fit_map(objective)
    return estimate, laplace_posterior(objective, estimate, clusters=windows.bands())


def test_the_band_robust_interval_holds_the_truth_where_one_load_misleads_the_fit():
    """A +1.5 K model error at full load pulls the friction coefficient ~0.15 above its
    truth; the Laplace interval (residual size and correlation) misses it, the
    leave-one-band-out interval (the bands disagree) holds it and is the one reported, and
    the band whose removal moves the estimate most is the full-load one."""
    truth = TRUTH.friction_coefficient
    for seed in range(4):
        estimate, posterior = _robust_posterior(_full_load_discrepancy(seed, 1.5))
        row = posterior.table().loc["friction_coefficient"]
        assert estimate.friction_coefficient > truth + 0.1
        assert not row["laplace_low"] <= truth <= row["laplace_high"]
        assert row["robust_low"] <= truth <= row["robust_high"]
        assert row["method"] == "cluster-robust"
        assert (row["low"], row["high"]) == pytest.approx((row["robust_low"], row["robust_high"]))
        without = posterior.without_cluster()
        assert list(without) == list(dict.fromkeys(_window_set(
            np.random.default_rng(seed)).bands()))
        assert min(without, key=lambda band: without[band]["friction_coefficient"]) \
            == "100–110 %"


def test_the_band_robust_covariance_agrees_with_laplace_for_a_correct_model():
    """No model error: the leave-one-band-out variance scatters about the Laplace one by its
    sampling error (G = 5 bands: ≈ √(2/4)), and the reported interval still holds the
    truth."""
    ratios, covered = [], 0
    draws = 8
    for seed in range(draws):
        _, posterior = _robust_posterior(_full_load_discrepancy(300 + seed, 0.0))
        ratios.append(np.sqrt(np.diag(posterior.robust_covariance)[:2]
                              / np.diag(posterior.covariance)[:2]))
        table = posterior.table()
        covered += all(table.loc[n, "low"] <= getattr(TRUTH, n) <= table.loc[n, "high"]
                       for n in ("flow_coefficient", "friction_coefficient"))
    median = np.median(ratios, axis=0)
    assert ((median > 0.5) & (median < 1.6)).all(), ratios
    assert covered >= draws - 1


def test_a_joint_calibration_writes_both_intervals_and_says_which_it_reports(tmp_path):
    windows = _full_load_discrepancy(9, 1.5)
    calibrator = Calibrator(LagSimulator(), objective=BIASED, search=TWO, workers=1).fit(windows)
    assert calibrator.posterior_.clusters == tuple(dict.fromkeys(windows.bands()))
    path, _ = calibrator.save(tmp_path / "params.json")
    section = json.loads(path.read_text())["posterior"]
    assert section["method"] == "wider of laplace and cluster-robust"
    assert section["robust"]["clusters"] == list(dict.fromkeys(windows.bands()))
    assert section["robust"]["t_over_z"] == pytest.approx(2.776 / 1.960, rel=1e-3)  # t_4
    for interval in section["intervals"].values():
        assert interval["method"] in ("laplace", "cluster-robust")
        kind = "robust" if interval["method"] == "cluster-robust" else "laplace"
        assert (interval["low"], interval["high"]) == pytest.approx(
            (interval[f"{kind}_low"], interval[f"{kind}_high"]))
        assert interval["low"] <= min(interval["laplace_low"], interval["robust_low"]) + 1e-12
        assert interval["high"] >= max(interval["laplace_high"], interval["robust_high"]) - 1e-12
    assert set(section["robust"]["map_without_band"]["ramps"]) == set(PARAMETER_NAMES)
    # plain frames carry no bands: the Laplace interval alone, as before
    plain = Calibrator(LagSimulator(), objective=MAP, search=ONE, workers=1).fit(
        [w.data for w in windows])
    assert plain.posterior_.robust_covariance is None
    assert set(plain.posterior_.table()["method"]) == {"laplace"}
