"""IAPWS-IF97 water and steam properties: a vectorised, validated layer over CoolProp.

All quantities are SI: pressure ``p`` in Pa, temperature ``T`` in K, specific enthalpy ``h``
in J/kg, specific entropy ``s`` in J/(kg·K), specific volume ``v`` in m³/kg, isobaric heat
capacity ``cp`` in J/(kg·K), dynamic viscosity in Pa·s and thermal conductivity in W/(m·K).

Every function accepts floats or numpy arrays, broadcasts its arguments against each other and
returns a float64 :class:`numpy.ndarray` of the broadcast shape (0-d for scalar inputs).

Forward functions of ``(p, T)`` evaluate the IF97 basic equations (CoolProp's ``IF97::Water``
backend).  Functions of ``(p, h)`` and ``(p, s)`` by default return the state that is *exactly*
consistent with those basic equations: starting from CoolProp's IF97 backward-equation value,
a bracketed Newton iteration solves ``h(p, T) = h`` resp. ``s(p, T) = s`` to about 1e-11
relative in T; wet states (region 4) use the lever rule between the saturated states.  The raw
IF97 backward equations are consistent with the basic equations only within IF97's tolerated
inconsistencies (tens of mK); for CoolProp's evaluation we measured up to 23 mK in T(p, h) and
19 mK in T(p, s) near 25 MPa, i.e. up to 180 J/kg in h(p, s).  Pass ``backward=True`` to get
the raw backward-equation values (faster; these are what the IF97 verification tables list).

Reference: IAPWS R7-97(2012), Revised Release on the IAPWS Industrial Formulation 1997 for the
Thermodynamic Properties of Water and Steam.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from steamtwin.errors import ModelError

__all__ = [
    "P_CRIT",
    "P_MAX",
    "P_MIN_SAT",
    "P_TRIPLE",
    "T_CRIT",
    "T_MAX",
    "T_MAX_R2",
    "T_MIN",
    "SteamPropertyError",
    "enthalpy_ps",
    "enthalpy_pt",
    "entropy_ph",
    "entropy_pt",
    "isobaric_heat_capacity_pt",
    "saturated_vapour_enthalpy",
    "saturated_vapour_entropy",
    "saturation_pressure",
    "saturation_temperature",
    "specific_volume_ph",
    "specific_volume_pt",
    "temperature_ph",
    "temperature_ps",
    "thermal_conductivity_pt",
    "viscosity_pt",
]

FLUID = "IF97::Water"

T_MIN = 273.15  #: lower temperature limit of IF97, K
T_MAX_R2 = 1073.15  #: upper temperature limit of regions 1–3, K (p ≤ 100 MPa)
T_MAX = 2273.15  #: upper temperature limit of region 5, K (p ≤ 50 MPa)
P_MAX = 100.0e6  #: upper pressure limit of IF97, Pa
P_MAX_R5 = 50.0e6  #: upper pressure limit of region 5, Pa
T_CRIT = 647.096  #: critical temperature, K
P_CRIT = 22.064e6  #: critical pressure, Pa
P_TRIPLE = 611.657  #: triple-point pressure, Pa
P_MIN_SAT = 611.212677  #: saturation pressure at 273.15 K (IF97 eq. 30), Pa

FloatArray = NDArray[np.float64]

_RANGE_PT = (
    "273.15 K ≤ T ≤ 1073.15 K for 0 < p ≤ 100 MPa, or 1073.15 K < T ≤ 2273.15 K for "
    "0 < p ≤ 50 MPa (IAPWS-IF97 range of validity)"
)


class SteamPropertyError(ModelError):
    """Invalid input to, or failure of, an IF97 property evaluation.

    ``argument`` names the offending argument (or ``None`` if CoolProp rejected a combination of
    inputs) and ``index`` is the index of the first offending element (``None`` for scalars).
    """

    def __init__(self, message: str, argument: str | None = None, index: tuple | None = None):
        super().__init__(message)
        self.argument = argument
        self.index = index


# --------------------------------------------------------------------------------------------
# Input validation
# --------------------------------------------------------------------------------------------


def _index_text(arr: np.ndarray, flat: int) -> tuple[tuple | None, str]:
    if arr.ndim == 0:
        return None, ""
    idx = tuple(int(i) for i in np.unravel_index(flat, arr.shape))
    text = str(idx[0]) if len(idx) == 1 else str(idx)
    return idx, f" at index {text}"


def _as_float_array(name: str, x: ArrayLike) -> FloatArray:
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise SteamPropertyError(
            f"argument {name!r} must be a real number or array of real numbers", name
        ) from exc
    return arr


def _check(
    name: str,
    x: ArrayLike,
    unit: str,
    expected: str,
    lower: float | None = None,
    upper: float | None = None,
    positive: bool = True,
) -> FloatArray:
    """Return ``x`` as a float64 array, raising SteamPropertyError on the first bad element."""
    arr = _as_float_array(name, x)
    bad = ~np.isfinite(arr)
    problem = "a non-finite value"
    if not bad.any():
        if positive:
            bad = arr <= 0.0
            problem = "a non-positive value"
        if not bad.any() and (lower is not None or upper is not None):
            lo = -np.inf if lower is None else lower
            hi = np.inf if upper is None else upper
            bad = (arr < lo) | (arr > hi)
            problem = "a value outside the valid range"
    if bad.any():
        flat = int(np.flatnonzero(bad.ravel())[0])
        idx, where = _index_text(arr, flat)
        value = float(arr.ravel()[flat])
        raise SteamPropertyError(
            f"argument {name!r} has {problem} ({value!r} {unit}){where}; expected {expected}",
            name,
            idx,
        )
    return arr


def _check_p(p: ArrayLike) -> FloatArray:
    return _check("p", p, "Pa", "pressure in Pa with 0 < p ≤ 100 MPa", upper=P_MAX)


def _check_pt(p: ArrayLike, T: ArrayLike) -> tuple[FloatArray, FloatArray]:
    pa = _check_p(p)
    Ta = _check("T", T, "K", f"temperature in K with {_RANGE_PT}", lower=T_MIN, upper=T_MAX)
    pb, Tb = np.broadcast_arrays(pa, Ta)
    bad = (Tb > T_MAX_R2) & (pb > P_MAX_R5)
    if bad.any():
        flat = int(np.flatnonzero(bad.ravel())[0])
        idx, where = _index_text(pb, flat)
        raise SteamPropertyError(
            f"state (p={float(pb.ravel()[flat])!r} Pa, T={float(Tb.ravel()[flat])!r} K){where} "
            f"is outside the IF97 range of validity: {_RANGE_PT}",
            "T",
            idx,
        )
    return pa, Ta


# --------------------------------------------------------------------------------------------
# CoolProp calls
# --------------------------------------------------------------------------------------------


def _props_si(*arguments: object) -> object:
    """CoolProp's ``PropsSI``, imported on the first call: CoolProp's import takes ~2 s of
    CPU (it loads every fluid), which every process importing the model paid, each GA
    worker included, though a calibration's model runs never call it."""
    from CoolProp.CoolProp import PropsSI as props_si

    return props_si(*arguments)


def _props_raw(out: str, n1: str, v1: FloatArray, n2: str, v2: FloatArray) -> FloatArray:
    """Vectorised PropsSI on broadcast inputs; failed elements are NaN (never raises)."""
    a, b = np.broadcast_arrays(v1, v2)
    shape = a.shape
    fa = np.ascontiguousarray(a, dtype=np.float64).ravel()
    fb = np.ascontiguousarray(b, dtype=np.float64).ravel()
    if fa.size == 0:
        return np.empty(shape)
    try:
        res = np.asarray(_props_si(out, n1, fa, n2, fb, FLUID), dtype=np.float64)
    except ValueError:
        # CoolProp raises (instead of returning inf) when a one-element vector fails.
        res = np.empty(fa.size)
        for i in range(fa.size):
            try:
                res[i] = _props_si(out, n1, float(fa[i]), n2, float(fb[i]), FLUID)
            except ValueError:
                res[i] = np.nan
    res = res.reshape(shape)
    res[~np.isfinite(res)] = np.nan
    return res


def _props(out: str, n1: str, v1: FloatArray, n2: str, v2: FloatArray) -> FloatArray:
    """Vectorised PropsSI on broadcast inputs; CoolProp failures become SteamPropertyError."""
    res = _props_raw(out, n1, v1, n2, v2)
    bad = np.isnan(res)
    if bad.any():
        a, b = np.broadcast_arrays(v1, v2)
        flat = int(np.flatnonzero(bad.ravel())[0])
        x1, x2 = float(a.ravel()[flat]), float(b.ravel()[flat])
        raise _coolprop_error(out, n1, x1, n2, x2, a, flat)
    return res


def _coolprop_error(
    out: str,
    n1: str,
    x1: float,
    n2: str,
    x2: float,
    arr: np.ndarray,
    flat: int,
    why: str = "",
    argument: str | None = None,
) -> SteamPropertyError:
    """SteamPropertyError carrying CoolProp's own message for one failed point."""
    if not why:
        try:
            val = _props_si(out, n1, x1, n2, x2, FLUID)
            why = f"CoolProp returned {val!r}"
        except ValueError as exc:
            why = f"CoolProp: {exc}"
    idx, where = _index_text(arr, flat)
    return SteamPropertyError(
        f"IF97 property {out!r} could not be evaluated for {n1}={x1!r} {_units(n1)}, "
        f"{n2}={x2!r} {_units(n2)}{where}; {why}",
        argument,
        idx,
    )


def _units(name: str) -> str:
    return {"P": "Pa", "T": "K", "H": "J/kg", "S": "J/(kg K)", "Q": "(quality)"}[name]


# --------------------------------------------------------------------------------------------
# Forward functions of (p, T)
# --------------------------------------------------------------------------------------------


def _pt(out: str, p: ArrayLike, T: ArrayLike) -> FloatArray:
    pa, Ta = _check_pt(p, T)
    return _props(out, "P", pa, "T", Ta)


def enthalpy_pt(p: ArrayLike, T: ArrayLike) -> FloatArray:
    """Specific enthalpy h(p, T) in J/kg; p in Pa, T in K."""
    return _pt("H", p, T)


def entropy_pt(p: ArrayLike, T: ArrayLike) -> FloatArray:
    """Specific entropy s(p, T) in J/(kg·K); p in Pa, T in K."""
    return _pt("S", p, T)


def specific_volume_pt(p: ArrayLike, T: ArrayLike) -> FloatArray:
    """Specific volume v(p, T) in m³/kg; p in Pa, T in K."""
    return 1.0 / _pt("D", p, T)


def isobaric_heat_capacity_pt(p: ArrayLike, T: ArrayLike) -> FloatArray:
    """Specific isobaric heat capacity cp(p, T) in J/(kg·K); p in Pa, T in K."""
    return _pt("C", p, T)


def viscosity_pt(p: ArrayLike, T: ArrayLike) -> FloatArray:
    """Dynamic viscosity (IAPWS 2008, industrial use) in Pa·s; p in Pa, T in K."""
    return _pt("V", p, T)


def thermal_conductivity_pt(p: ArrayLike, T: ArrayLike) -> FloatArray:
    """Thermal conductivity (IAPWS 2011, industrial use) in W/(m·K); p in Pa, T in K."""
    return _pt("L", p, T)


# --------------------------------------------------------------------------------------------
# Backward functions of (p, h) and (p, s)
# --------------------------------------------------------------------------------------------

_REL_OFFSET = 1e-9  # keeps Newton iterates strictly on their side of the saturation line
_NEWTON_MAX_ITER = 100
_NEWTON_RTOL = 1e-11


def _saturation_bounds(p: FloatArray, key: str) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Tsat, liquid and vapour values of ``key`` at p (NaN where p ≥ p_crit or p < p_min)."""
    sub = (p < P_CRIT) & (p >= P_MIN_SAT)
    Ts = np.full(p.shape, np.nan)
    f = np.full(p.shape, np.nan)
    g = np.full(p.shape, np.nan)
    if sub.any():
        ps = p[sub]
        q0 = np.zeros_like(ps)
        Ts[sub] = _props("T", "P", ps, "Q", q0)
        f[sub] = _props(key, "P", ps, "Q", q0)
        g[sub] = _props(key, "P", ps, "Q", q0 + 1.0)
    return Ts, f, g


def _invert_forward(
    p: FloatArray, target: FloatArray, key: str, shape: tuple[int, ...] | None = None
) -> tuple[FloatArray, np.ndarray]:
    """Solve key(p, T) = target for T (key 'H' or 'S') on the IF97 basic equations.

    ``p`` and ``target`` are 1-D arrays of equal length (the raveled inputs of broadcast
    ``shape``, used for error messages).  Safeguarded Newton iteration (the root is kept
    bracketed, h and s increase with T at constant p), started from CoolProp's backward-equation
    value where that exists.  Returns (T, two_phase) where ``two_phase`` marks wet states
    (T = Tsat there).
    """
    T0 = _props_raw("T", "P", p, key, target)  # backward-equation estimate (NaN if it fails)
    Ts, f, g = _saturation_bounds(p, key)
    two_phase = (target >= f) & (target <= g)  # NaN comparisons are False
    t_max = np.where(p > P_MAX_R5, T_MAX_R2, T_MAX)
    lo = np.where(target > g, Ts * (1.0 + _REL_OFFSET), T_MIN)
    hi = np.where(target < f, Ts * (1.0 - _REL_OFFSET), t_max)
    T = np.where(np.isnan(T0), 0.5 * (lo + hi), np.clip(T0, lo, hi))
    T[two_phase] = Ts[two_phase]
    step_old = hi - lo
    active = np.flatnonzero(~two_phase)
    for _ in range(_NEWTON_MAX_ITER):
        if active.size == 0:
            break
        pa, Ta, la, ha = p[active], T[active], lo[active], hi[active]
        val = _props(key, "P", pa, "T", Ta)
        cp = _props("C", "P", pa, "T", Ta)
        r = val - target[active]
        la = np.where(r < 0.0, Ta, la)
        ha = np.where(r > 0.0, Ta, ha)
        step = r / (cp if key == "H" else cp / Ta)
        T_new = Ta - step
        # Bisect when Newton leaves the bracket or does not halve the step (cf. rtsafe).
        bisect = ~((T_new > la) & (T_new < ha)) | (np.abs(step) > 0.5 * step_old[active])
        bisect &= r != 0.0
        T_new = np.where(bisect, 0.5 * (la + ha), T_new)
        step_old[active] = np.abs(T_new - Ta)
        T[active], lo[active], hi[active] = T_new, la, ha
        moved = np.abs(T_new - Ta) > _NEWTON_RTOL * Ta
        active = active[moved]
    # States outside the IF97 range end pinned at a temperature limit: check the residual there.
    at_limit = np.less_equal(T, T_MIN * (1 + 1e-9)) | np.greater_equal(T, t_max * (1 - 1e-9))
    pinned = np.flatnonzero(~two_phase & at_limit)
    if pinned.size:
        r = _props(key, "P", p[pinned], "T", T[pinned]) - target[pinned]
        tol = 1e-6 * np.maximum(np.abs(target[pinned]), 1e3)
        bad = np.flatnonzero(~(np.abs(r) <= tol))
        if bad.size:
            k = int(pinned[bad[0]])
            raise _coolprop_error(
                "T",
                "P",
                float(p[k]),
                key,
                float(target[k]),
                np.broadcast_to(0.0, p.shape if shape is None else shape),
                k,
                "the state lies outside the IF97 range of validity (" + _RANGE_PT + ")",
                argument=key.lower(),
            )
    return T, two_phase


def _backward(
    out: str, key: str, p: ArrayLike, x: ArrayLike, x_name: str, backward: bool
) -> FloatArray:
    pa = _check_p(p)
    xa = _check(
        x_name,
        x,
        _units(key),
        f"a finite specific {'enthalpy' if key == 'H' else 'entropy'} in {_units(key)}",
        positive=False,
    )
    if backward:
        return _props(out, "P", pa, key, xa)
    pb, xb = np.broadcast_arrays(pa, xa)
    shape = pb.shape
    pf, xf = pb.ravel().copy(), xb.ravel().copy()
    T, wet = _invert_forward(pf, xf, key, shape)
    if out == "T":
        return T.reshape(shape)
    res = np.empty_like(T)
    dry = ~wet
    if dry.any():
        res[dry] = _props(out, "P", pf[dry], "T", T[dry])
    if wet.any():
        # Region 4: lever rule between the saturated states (CoolProp's own two-phase
        # S(p, h) / H(p, s) were found inconsistent with it by ~0.1 J/(kg K) / ~3 J/kg).
        pw = pf[wet]
        q0, q1 = np.zeros_like(pw), np.ones_like(pw)
        kf, kg = _props(key, "P", pw, "Q", q0), _props(key, "P", pw, "Q", q1)
        quality = (xf[wet] - kf) / (kg - kf)
        if out == "D":  # lever rule on specific volume
            vf = 1.0 / _props("D", "P", pw, "Q", q0)
            vg = 1.0 / _props("D", "P", pw, "Q", q1)
            res[wet] = 1.0 / (vf + quality * (vg - vf))
        else:
            of, og = _props(out, "P", pw, "Q", q0), _props(out, "P", pw, "Q", q1)
            res[wet] = of + quality * (og - of)
    return res.reshape(shape)


def temperature_ph(p: ArrayLike, h: ArrayLike, *, backward: bool = False) -> FloatArray:
    """Temperature T(p, h) in K; p in Pa, h in J/kg.

    ``backward=True`` returns the raw IF97 backward-equation value (see module docstring).
    """
    return _backward("T", "H", p, h, "h", backward)


def entropy_ph(p: ArrayLike, h: ArrayLike, *, backward: bool = False) -> FloatArray:
    """Specific entropy s(p, h) in J/(kg·K); p in Pa, h in J/kg (wet states included)."""
    return _backward("S", "H", p, h, "h", backward)


def specific_volume_ph(p: ArrayLike, h: ArrayLike, *, backward: bool = False) -> FloatArray:
    """Specific volume v(p, h) in m³/kg; p in Pa, h in J/kg (wet states included)."""
    return 1.0 / _backward("D", "H", p, h, "h", backward)


def temperature_ps(p: ArrayLike, s: ArrayLike, *, backward: bool = False) -> FloatArray:
    """Temperature T(p, s) in K; p in Pa, s in J/(kg·K)."""
    return _backward("T", "S", p, s, "s", backward)


def enthalpy_ps(p: ArrayLike, s: ArrayLike, *, backward: bool = False) -> FloatArray:
    """Specific enthalpy h(p, s) in J/kg; p in Pa, s in J/(kg·K) (wet states included)."""
    return _backward("H", "S", p, s, "s", backward)


# --------------------------------------------------------------------------------------------
# Saturation line (IF97 region 4)
# --------------------------------------------------------------------------------------------

_SAT_P_EXPECTED = "saturation pressure in Pa with 611.213 Pa ≤ p ≤ 22.064 MPa"


def _sat_p(p: ArrayLike) -> FloatArray:
    return _check("p", p, "Pa", _SAT_P_EXPECTED, lower=P_MIN_SAT, upper=P_CRIT)


def saturation_temperature(p: ArrayLike) -> FloatArray:
    """Saturation temperature Tsat(p) in K (IF97 eq. 31); p in Pa."""
    pa = _sat_p(p)
    return _props("T", "P", pa, "Q", np.zeros_like(pa))


def saturation_pressure(T: ArrayLike) -> FloatArray:
    """Saturation pressure psat(T) in Pa (IF97 eq. 30); T in K, 273.15 K ≤ T ≤ 647.096 K."""
    Ta = _check(
        "T", T, "K", "temperature in K with 273.15 K ≤ T ≤ 647.096 K", lower=T_MIN, upper=T_CRIT
    )
    return _props("P", "T", Ta, "Q", np.zeros_like(Ta))


def _sat_vapour(out: str, p: ArrayLike) -> FloatArray:
    pa = _sat_p(p)
    return _props(out, "P", pa, "Q", np.ones_like(pa))


def saturated_vapour_enthalpy(p: ArrayLike) -> FloatArray:
    """Specific enthalpy of saturated vapour h''(p) in J/kg; p in Pa."""
    return _sat_vapour("H", p)


def saturated_vapour_entropy(p: ArrayLike) -> FloatArray:
    """Specific entropy of saturated vapour s''(p) in J/(kg·K); p in Pa."""
    return _sat_vapour("S", p)
