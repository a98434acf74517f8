"""The three unmeasurable model parameters, their physical bounds and their empirical defaults.

All three are dimensionless multipliers on a design correlation:

* ``flow_coefficient`` scales every flow capacity of the steam path — the Stodola constants of the
  pressure stages and the nozzle area of the control stage. Deposits shrink and erosion widens
  throat areas; ±10 % brackets what is reported for HP blading in service (Cotton 1998, ch. 9 on
  deposits; Cooke 1985 on the cone-law constants).
* ``friction_coefficient`` scales the fluid-friction losses: blade-profile friction, disc friction
  and idle-arc windage (Kang et al., *Principles of Steam Turbines*, China Electric Power Press —
  the K1 and B_e loss set; Traupel 2001). 0.5–2.0 spans new, polished blading to rough, deposited
  blading.
* ``heat_transfer_coefficient`` scales the Dittus–Boelter steam-to-metal Nusselt correlation.
  Turbulent-pipe correlations scatter by ±25 % in their own range (Incropera & DeWitt) and by far
  more for rotor/casing surfaces (manufacturers' formulas "vary greatly", ASME POWER2014-32004
  abstract), hence 0.5–2.0.

The defaults (1, 1, 1) are the "empirical constants": the correlations as published, the values a
designer uses before any calibration.

Priors (:data:`DEFAULT_PRIORS`, what a calibration assumes before it sees data): each
coefficient's design value 1 with a spread read from the same sources, so that the physical
bounds above are about the prior's 95 % range (± 2 σ):

* flow coefficient — normal, σ = 0.05: ± 10 % (the bounds) is 2 σ, the range reported for
  deposits and erosion of HP blading (Cotton 1998, ch. 9);
* friction coefficient — log-normal, σ_ln = ln 2 / 2 ≈ 0.35: a factor 2 either way (0.5–2.0)
  is 2 σ; a multiplier on a loss is positive and its uncertainty a factor, hence log-normal
  (Traupel 2001 quotes loss correlations to within a factor, not a difference);
* heat-transfer coefficient — log-normal, σ_ln ≈ 0.35 likewise: ± 25 % scatter of turbulent
  pipe correlations in their own range (Incropera & DeWitt) and "greatly varying" rotor/casing
  formulas (ASME POWER2014-32004) make a factor 2 the 95 % range.

A parameter file may override them (key ``priors``, see :func:`priors_from_dict`) and carries
the calibration's posterior (key ``posterior``); :data:`PARAMETERS_SCHEMA_VERSION` versions the
file (files without ``schema_version`` are version 1 and still load).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from statistics import NormalDist
from typing import Any

from steamtwin.dcs.signals import SIGNALS
from steamtwin.errors import ModelError
from steamtwin.keys import unknown_key_message
from steamtwin.textfile import read_utf8_text

PARAMETER_BOUNDS: dict[str, tuple[float, float]] = {
    "flow_coefficient": (0.90, 1.10),
    "friction_coefficient": (0.5, 2.0),
    "heat_transfer_coefficient": (0.5, 2.0),
}
#: Informational keys a parameter file may carry next to the coefficients (what the package's
#: writers add); their content is not read here — the bounds applied are always
#: PARAMETER_BOUNDS; ``priors`` is read by :func:`priors_from_dict` when a calibration asks,
#: ``sensor_offsets`` by :func:`sensor_offsets_from_json` when validate or predict asks.
METADATA_KEYS = frozenset({"bounds", "calibration", "priors", "posterior", "sensor_offsets"})

#: Largest sensor offset a parameter file may state, K: three times the IEC 60584-1 class-2
#: thermocouple tolerance at 600 °C (±4.5 K); beyond it the sensor is faulty, not offset.
MAX_SENSOR_OFFSET_K = 13.5
#: Largest pressure-sensor offset, Pa: three times a 0.5 %-of-span transmitter error (the
#: accuracy class of IEC 60770-1 process transmitters) on a 0–25 MPa span, the main-steam
#: range; a control-stage pressure witness calibrated with sensor biases has one.
MAX_SENSOR_OFFSET_PA = 3.0 * 0.005 * 25.0e6

PARAMETERS_SCHEMA_VERSION = 2
"""Version of the parameter-file format: 1 = coefficients (+ bounds, calibration); 2 adds
``schema_version``, ``priors`` and ``posterior`` (intervals)."""

PRIOR_DISTRIBUTIONS = ("normal", "lognormal")
"""Prior families: ``normal`` (``center`` ± ``spread``, both in the parameter's unit) and
``lognormal`` (median ``center``, ``spread`` = σ of ln x)."""


class ParameterError(ModelError):
    """A parameter value is missing, not a number or outside its physical bounds."""


@dataclass(frozen=True)
class ParameterPrior:
    """Prior of one coefficient: ``distribution`` (one of :data:`PRIOR_DISTRIBUTIONS`),
    ``center`` (design value; the median for log-normal) and ``spread`` (σ; of ln x for
    log-normal). Dimensionless, as the coefficients are. ``source`` says where it comes from."""

    distribution: str
    center: float
    spread: float
    source: str = ""

    def __post_init__(self) -> None:
        if self.distribution not in PRIOR_DISTRIBUTIONS:
            raise ParameterError(f"prior distribution {self.distribution!r}: expected one of "
                                 f"{', '.join(PRIOR_DISTRIBUTIONS)}")
        for name in ("center", "spread"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not (
                    0.0 < value < float("inf")):
                raise ParameterError(f"prior {name} = {value!r}: expected a finite number > 0")

    def to_internal(self, value: float) -> float:
        """The coordinate in which this prior is normal: x, or ln x for log-normal."""
        return value if self.distribution == "normal" else math.log(value)

    def from_internal(self, theta: float) -> float:
        """Inverse of :meth:`to_internal`."""
        return theta if self.distribution == "normal" else math.exp(theta)

    @property
    def mean_internal(self) -> float:
        """The prior's mean in the internal (normal) coordinate."""
        return self.to_internal(self.center)

    def interval(self, probability: float = 0.95) -> tuple[float, float]:
        """Central prior interval holding ``probability`` (in the parameter's unit)."""
        z = _normal_quantile(0.5 + probability / 2.0)
        return (self.from_internal(self.mean_internal - z * self.spread),
                self.from_internal(self.mean_internal + z * self.spread))


def _normal_quantile(p: float) -> float:
    """Standard-normal quantile (inverse CDF)."""
    return NormalDist().inv_cdf(p)


DEFAULT_PRIORS: dict[str, ParameterPrior] = {
    "flow_coefficient": ParameterPrior(
        "normal", 1.0, 0.05, "±10 % (bounds) = 2σ: deposits/erosion of HP blading, Cotton 1998"),
    "friction_coefficient": ParameterPrior(
        "lognormal", 1.0, math.log(2.0) / 2.0,
        "factor 2 = 2σ: loss correlations to within a factor, Traupel 2001"),
    "heat_transfer_coefficient": ParameterPrior(
        "lognormal", 1.0, math.log(2.0) / 2.0,
        "factor 2 = 2σ: Incropera & DeWitt ±25 % in range, ASME POWER2014-32004 beyond"),
}
"""Default prior per coefficient (see the module docstring for the reasoning)."""


def parse_prior(text: str, option: str = "--prior") -> tuple[str, ParameterPrior]:
    """``NAME=DISTRIBUTION:CENTER:SPREAD`` (e.g. ``flow_coefficient=normal:1.0:0.03``) →
    (name, prior); ParameterError naming ``option`` and the expected form."""
    name, sep, rest = text.partition("=")
    parts = rest.split(":")
    form = "NAME=normal|lognormal:CENTER:SPREAD, e.g. flow_coefficient=normal:1.0:0.03"
    if not sep or len(parts) != 3:
        raise ParameterError(f"{option} {text!r}: expected {form}")
    if name not in PARAMETER_BOUNDS:
        raise ParameterError(f"{option} {text!r}: unknown parameter {name!r}; known: "
                             f"{', '.join(PARAMETER_BOUNDS)}")
    try:
        center, spread = float(parts[1]), float(parts[2])
    except ValueError:
        raise ParameterError(f"{option} {text!r}: CENTER and SPREAD must be numbers ({form})"
                             ) from None
    try:
        return name, ParameterPrior(parts[0], center, spread, f"{option} {text}")
    except ParameterError as error:
        raise ParameterError(f"{option} {text!r}: {error}") from None


def priors_from_dict(document: Any, source: str = "<priors>",
                     base: Mapping[str, ParameterPrior] | None = None
                     ) -> dict[str, ParameterPrior]:
    """Priors from ``{name: {"distribution": ..., "center": ..., "spread": ...}}`` (a parameter
    file's ``priors``), each over ``base`` (default :data:`DEFAULT_PRIORS`); a coefficient not
    given keeps its base prior. Errors name ``source`` and the key."""
    result = dict(DEFAULT_PRIORS if base is None else base)
    if not isinstance(document, Mapping):
        raise ParameterError(f"{source}: priors must be a JSON object, got "
                             f"{type(document).__name__}")
    message = unknown_key_message(document, PARAMETER_BOUNDS, "priors", source, "parameter file")
    if message is not None:
        raise ParameterError(message)
    for name, entry in document.items():
        where = f"{source}: priors.{name}"
        if not isinstance(entry, Mapping):
            raise ParameterError(f"{where}: expected an object with distribution, center, "
                                 "spread")
        message = unknown_key_message(entry, {"distribution", "center", "spread", "source"},
                                      f"priors.{name}", source, "parameter file")
        if message is not None:
            raise ParameterError(message)
        merged = {**asdict(result[name]), "source": "", **entry}
        try:
            result[name] = ParameterPrior(**merged)
        except ParameterError as error:
            raise ParameterError(f"{where}: {error}") from None
    return result


def _reject_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """JSON object hook: a key given twice is an error, not "the last one wins"."""
    document: dict[str, Any] = {}
    for key, value in pairs:
        if key in document:
            raise ValueError(f"key {key!r} appears twice in one object")
        document[key] = value
    return document


@dataclass(frozen=True)
class ModelParameters:
    """Unmeasurable parameters of the full-order model (dimensionless multipliers, default 1)."""

    flow_coefficient: float = 1.0
    friction_coefficient: float = 1.0
    heat_transfer_coefficient: float = 1.0

    def __post_init__(self) -> None:
        for field in fields(self):
            value = getattr(self, field.name)
            low, high = PARAMETER_BOUNDS[field.name]
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ParameterError(f"{field.name} = {value!r}: expected a number")
            if not low <= value <= high:  # also false for NaN and ±inf
                raise ParameterError(
                    f"{field.name} = {value!r} is outside its physical bounds [{low}, {high}]"
                )

    @classmethod
    def from_json(cls, path: str | Path) -> ModelParameters:
        """Read a parameter file (UTF-8 JSON) strictly: nothing missing, unknown or defaulted.

        The file is one JSON object in either form:

        * ``{"parameters": {...}, "bounds": {...}, "calibration": {...}}`` — what
          :meth:`to_json`, calibration (``Calibrator.save``, whatever its search) and the
          online :class:`~steamtwin.calibration.online.ParameterStore` write;
        * ``{"flow_coefficient": ..., "friction_coefficient": ...,
          "heat_transfer_coefficient": ...}`` — the coefficients at the top level, by hand.

        All three coefficients are required (the defaults 1, 1, 1 apply only when no file is
        given), each a finite number within :data:`PARAMETER_BOUNDS`. The optional metadata
        keys :data:`METADATA_KEYS` must be JSON objects and are informational only: ``bounds``
        (the bounds at writing time) and ``calibration`` (``rmse_K``, ``sensors``,
        ``evaluations`` and the optimiser's settings). Any other key, a key given twice, or
        coefficients both at the top level and under ``parameters`` raise
        :class:`ParameterError` naming the file and the key (with a "did you mean" hint).
        """
        path = Path(path)
        text = read_utf8_text(path, "parameter file", "JSON", ParameterError)
        try:
            document = json.loads(text, object_pairs_hook=_reject_duplicate_keys)
        except (ValueError, RecursionError) as error:  # JSONDecodeError, duplicates, nesting
            raise ParameterError(f"{path}: not valid JSON: {error}") from None
        return cls.from_dict(document, str(path))

    @classmethod
    def from_dict(cls, document: Any, source: str = "<parameters>") -> ModelParameters:
        """Validate a parsed parameter document (the schema of :meth:`from_json`).

        ``source`` names the document (file name) in errors.
        """
        if not isinstance(document, Mapping):
            raise ParameterError(f"{source}: expected a JSON object with "
                                 f"{', '.join(PARAMETER_BOUNDS)}, got {type(document).__name__}")
        message = unknown_key_message(document, {"parameters", "schema_version",
                                                 *METADATA_KEYS, *PARAMETER_BOUNDS}, "", source,
                                      "parameter file")
        if message is not None:
            raise ParameterError(message)
        version = document.get("schema_version", 1)
        if isinstance(version, bool) or version not in range(1, PARAMETERS_SCHEMA_VERSION + 1):
            raise ParameterError(f"{source}: schema_version = {version!r}: expected an integer "
                                 f"1…{PARAMETERS_SCHEMA_VERSION} (this steamtwin reads those)")
        for key in METADATA_KEYS & set(document):
            if not isinstance(document[key], Mapping):
                raise ParameterError(f"{source}: {key} must be a JSON object (informational "
                                     f"metadata), got {type(document[key]).__name__}")
        values, prefix = document, ""
        if "parameters" in document:
            values, prefix = document["parameters"], "parameters."
            inline = sorted(set(PARAMETER_BOUNDS) & set(document))
            if inline:
                raise ParameterError(f"{source}: {', '.join(inline)} given both at the top "
                                     "level and under 'parameters'; give each once")
            if not isinstance(values, Mapping):
                raise ParameterError(f"{source}: parameters must be a JSON object, got "
                                     f"{type(values).__name__}")
            message = unknown_key_message(values, PARAMETER_BOUNDS, "parameters", source,
                                          "parameter file")
            if message is not None:
                raise ParameterError(message)
        missing = [name for name in PARAMETER_BOUNDS if name not in values]
        if missing:
            raise ParameterError(
                f"{source}: missing coefficient(s) {', '.join(prefix + name for name in missing)};"
                " a parameter file must give all three, none is defaulted"
            )
        checked = {}
        for name, (low, high) in PARAMETER_BOUNDS.items():
            value = values[name]
            if (isinstance(value, bool) or not isinstance(value, int | float)
                    or not low <= value <= high):  # the comparison is false for NaN and ±inf
                raise ParameterError(f"{source}: {prefix}{name} = {value!r}: expected a number "
                                     f"within its physical bounds [{low}, {high}]")
            checked[name] = float(value)
        return cls(**checked)

    def to_json(self, path: str | Path) -> None:
        """Write the parameters (with their bounds, for the reader's benefit) as JSON."""
        document = {
            "parameters": asdict(self),
            "bounds": {name: list(bounds) for name, bounds in PARAMETER_BOUNDS.items()},
        }
        Path(path).write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")


def sensor_offset_unit(signal: str) -> str:
    """The SI unit of ``signal``'s offset: "Pa" for a pressure of the data contract, else "K"
    (a thermocouple's)."""
    known = SIGNALS.get(signal)
    return "Pa" if known is not None and known.si_unit == "Pa" else "K"


def sensor_offsets_from_json(path: str | Path) -> dict[str, float]:
    """The ``sensor_offsets`` section of a parameter file (signal → measured − model in the
    signal's SI unit — K, or Pa for a pressure — as a joint calibration with sensor biases
    estimated them; empty when the file has none). ParameterError naming the file and key for
    a value that is not a finite number within ±:data:`MAX_SENSOR_OFFSET_K` (K) or
    ±:data:`MAX_SENSOR_OFFSET_PA` (Pa)."""
    text = read_utf8_text(path, "parameter file", "JSON", ParameterError)
    try:
        document = json.loads(text, object_pairs_hook=_reject_duplicate_keys)
    except (ValueError, RecursionError) as error:
        raise ParameterError(f"{path}: not valid JSON: {error}") from None
    ModelParameters.from_dict(document, str(path))
    offsets = document.get("sensor_offsets", {})
    result = {}
    for name, value in offsets.items():
        unit = sensor_offset_unit(str(name))
        limit = MAX_SENSOR_OFFSET_PA if unit == "Pa" else MAX_SENSOR_OFFSET_K
        if (isinstance(value, bool) or not isinstance(value, int | float)
                or not abs(value) <= limit):
            raise ParameterError(f"{path}: sensor_offsets.{name} = {value!r}: expected a "
                                 f"number of {unit} within ±{limit:g}")
        result[str(name)] = float(value)
    return result
