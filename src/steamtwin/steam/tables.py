"""Fast spline-based table look-up of superheated-steam properties for numba kernels.

Kept as one module because the table build and the jitted look-ups share one grid layout (the
transformed coordinates, cell polynomials and their packing), which must change together, and
numba's cache does not notice changes to jitted callees in other files (numba docs, "Notes on
Caching").

The method follows the idea of the IAPWS Guideline on the Fast Calculation of Steam and Water
Properties with the Spline-Based Table Look-up Method (SBTL), IAPWS G13-15 (2015): properties
are sampled from the IAPWS-IF97 basic equation on a grid in transformed coordinates, each grid
cell carries a local polynomial, and a look-up is "locate the cell, evaluate one polynomial".

Domain: superheated steam (IF97 region 2) for 0.05 MPa ≤ p ≤ 25 MPa and
``T_low(p) ≤ T ≤ T_MAX = 923.15 K`` with ``T_low(p) = T_boundary(p) + T_MARGIN`` and
``T_MARGIN = 0.05 K``.  The region-2 lower boundary ``T_boundary`` is the saturation line
Tsat(p) for p ≤ 16.5291643 MPa and the B23 line (IF97 eqs. 5–6) above.  The margin keeps every
sampled state strictly inside region 2; states between ``T_boundary`` and ``T_low`` are served by
extrapolation of the edge cells, which was measured to stay within the same error bounds as
the interior (see ``tests/steam/test_tables.py``).

Coordinates: ``X = ln p``, uniform in two segments split at the kink of the lower boundary
(p = 16.5291643 MPa) so that every table cell is smooth.  The second coordinate is normalised
so that each table is a rectangle: for the (p, h) table ``Y = (h − h_low(p)) / (h_high(p) −
h_low(p))`` with ``h_low = h(p, T_low)`` and ``h_high = h(p, T_MAX)``; likewise for (p, s) with
s_low/s_high and for (p, T) with T_low/T_MAX.  The (p, T) table places its Y nodes closer
together near Y = 0 (``Y = c·η + (1 − c)·η²`` with η uniform) because h(T) is strongly curved
next to the boundary at high pressure.  Properties are interpolated by bicubic splines
(``scipy`` ``RectBivariateSpline``, s = 0), stored per cell as 16 coefficients of a bicubic
polynomial in the local cell coordinates ``(t, u) ∈ [0, 1]²``; the boundary functions of X are
cubic splines stored as 4 coefficients per interval.  Specific volume is tabulated as ``p·v``
(J/kg) and divided by p on look-up.

All grid values come from the IF97 *basic* equation (CoolProp ``IF97::Water``): states on the
(p, h) and (p, s) grids are found by Newton iteration on ``h(p, T)`` resp. ``s(p, T)``, not
from the IF97 backward equations, so the tables are consistent with ``if97.*_pt``.

The scalar kernels are numba ``@njit(cache=True, nogil=True)`` functions taking the
:class:`SteamTables` namedtuple as first argument.  Outside the domain they extrapolate the
polynomial of the nearest cell (no exceptions, NaN in → NaN out); use
:func:`ph_domain_position` (and :func:`ps_domain_position`, :func:`pt_domain_position`) and
:func:`pressure_in_range` to check the domain.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.metadata
import math
import os
import tempfile
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline, RectBivariateSpline

from steamtwin.cache import cache_root, njit

# steamtwin.steam.if97 (and with it CoolProp, whose import takes seconds) is imported lazily:
# loading the tables from a valid cache file does not need it.

__all__ = [
    "PH_CP",
    "PH_K",
    "PH_MU",
    "PH_NAMES",
    "PH_S",
    "PH_T",
    "PH_V",
    "P_MAX",
    "P_MIN",
    "P_SPLIT",
    "TABLE_FORMAT_VERSION",
    "T_MARGIN",
    "T_MAX",
    "SteamTables",
    "build_steam_tables",
    "enthalpy_ps",
    "enthalpy_pt",
    "load_or_build_steam_tables",
    "lower_boundary_temperature",
    "ph_domain_position",
    "ph_properties",
    "ph_property",
    "pressure_in_range",
    "ps_domain_position",
    "pt_domain_position",
    "steam_tables",
    "steam_tables_cache_path",
    "tables_enthalpy_ps",
    "tables_enthalpy_pt",
    "tables_ph_domain_position",
    "tables_ph_property",
    "tables_temperature_ph",
]

FloatArray = NDArray[np.float64]

# --------------------------------------------------------------------------------------------
# Domain and grid
# --------------------------------------------------------------------------------------------

P_MIN = 0.05e6  #: lowest table pressure, Pa
P_MAX = 25.0e6  #: highest table pressure, Pa
T_MAX = 923.15  #: highest table temperature, K (650 °C)
T_MARGIN = 0.05  #: distance of the table's lower edge from the region-2 boundary, K

# IF97 B23 boundary (IAPWS R7-97(2012), eqs. 5 and 6, Table 1), pressures in MPa.
_B23_N = (
    0.34805185628969e3,
    -0.11671859879975e1,
    0.10192970039326e-2,
    0.57254459862746e3,
    0.13918839778870e2,
)
_T_B23_MIN = 623.15  # K, where the B23 line meets the saturation line
#: Pressure of the kink of the region-2 lower boundary: p_B23(623.15 K) = 16.5291643 MPa.
P_SPLIT = (_B23_N[0] + _B23_N[1] * _T_B23_MIN + _B23_N[2] * _T_B23_MIN**2) * 1e6

#: Version of the table layout and sampling; bump whenever either changes (invalidates caches).
TABLE_FORMAT_VERSION = 1


# Number of cells: along ln p below / above P_SPLIT, and along Y for the (p,h), (p,s), (p,T)
# tables.  Chosen from measured accuracy (see tests/steam/test_tables.py).
class _Grid(NamedTuple):
    nx_a: int  # ln-p cells below P_SPLIT
    nx_b: int  # ln-p cells above P_SPLIT
    ny_ph: int  # Y cells of the (p, h) table
    ny_ps: int
    ny_pt: int
    c_ph: float  # Y-node clustering: Y = c·eta + (1 − c)·eta² with eta uniform
    c_ps: float
    c_pt: float


_GRID = _Grid(nx_a=180, nx_b=48, ny_ph=128, ny_ps=128, ny_pt=160, c_ph=1.0, c_ps=1.0, c_pt=0.3)

# Property indices of the (p, h) table.
PH_T = 0  #: temperature, K
PH_S = 1  #: specific entropy, J/(kg·K)
PH_V = 2  #: specific volume, m³/kg
PH_CP = 3  #: specific isobaric heat capacity, J/(kg·K)
PH_MU = 4  #: dynamic viscosity, Pa·s
PH_K = 5  #: thermal conductivity, W/(m·K)
PH_NAMES = ("T", "s", "v", "cp", "mu", "k")
_N_PH = len(PH_NAMES)

# Rows of SteamTables.bounds.
_B_TLOW, _B_HLOW, _B_HHIGH, _B_SLOW, _B_SHIGH = range(5)

# Entries of SteamTables.meta.
_M_X_MIN, _M_X_SPLIT, _M_X_MAX, _M_DX_A, _M_DX_B, _M_N_A, _M_N_B = range(7)
_M_P_MIN, _M_P_MAX, _M_T_MAX = 7, 8, 9
_M_C_PH, _M_C_PS, _M_C_PT = 10, 11, 12
_M_INV_DX_A, _M_INV_DX_B = 13, 14


# numba flags: no exceptions on division by zero; allow FMA contraction only (keeps NaN/inf).
_FASTMATH = {"contract"}


class SteamTables(NamedTuple):
    """Spline tables for superheated steam; float64 arrays only (one numba argument).

    ``meta``: [ln p_min, ln p_split, ln p_max, Δx below split, Δx above split, cells below,
    cells above, p_min (Pa), p_max (Pa), T_max (K), Y-clustering c of the (p,h), (p,s), (p,T)
    tables, 1/Δx below split, 1/Δx above split] (p in Pa).
    ``bounds[k, i, :]``: cubic coefficients in the local coordinate t ∈ [0, 1] of ln-p cell i
    for k = T_low (K), h_low, h_high (J/kg), s_low, s_high (J/(kg·K)).
    ``ph[prop, i, j, :]``: bicubic coefficients ``a[m*4 + n]`` of ``Σ a t^m u^n`` for the
    (p, h) properties ``PH_*`` (volume stored as p·v in J/kg).
    ``ps[0, i, j, :]``: h(p, s) in J/kg.  ``pt[0, i, j, :]``: h(p, T) in J/kg (a leading axis of
    one, so every table is indexed alike).
    """

    meta: FloatArray
    bounds: FloatArray
    ph: FloatArray
    ps: FloatArray
    pt: FloatArray


# --------------------------------------------------------------------------------------------
# Region-2 lower boundary
# --------------------------------------------------------------------------------------------


def _t_b23(p: FloatArray) -> FloatArray:
    """IF97 B23 boundary temperature T_B23(p) in K (eq. 6); p in Pa, p ≥ 16.5291643 MPa."""
    n3, n4, n5 = _B23_N[2], _B23_N[3], _B23_N[4]
    return n4 + np.sqrt((np.asarray(p) / 1e6 - n5) / n3)


def lower_boundary_temperature(p: ArrayLike) -> FloatArray:
    """Region-2 lower boundary T_boundary(p) in K (Tsat or B23 line); p in Pa, ≤ 100 MPa.

    The tables start at ``T_boundary(p) + T_MARGIN``.
    """
    from steamtwin.steam import if97

    pa = np.asarray(p, dtype=np.float64)
    below = pa <= P_SPLIT
    out = np.empty(pa.shape)
    if below.any():
        out[below] = if97.saturation_temperature(pa[below])
    if (~below).any():
        out[~below] = _t_b23(if97._check_p(pa[~below]))
    return out


# --------------------------------------------------------------------------------------------
# Sampling (the expensive, cached part)
# --------------------------------------------------------------------------------------------


def _x_nodes(grid: _Grid) -> FloatArray:
    xa = np.linspace(math.log(P_MIN), math.log(P_SPLIT), grid.nx_a + 1)
    xb = np.linspace(math.log(P_SPLIT), math.log(P_MAX), grid.nx_b + 1)
    return np.concatenate([xa, xb[1:]])


def _p_nodes(grid: _Grid) -> FloatArray:
    """Pressures (Pa) of the ln-p nodes, with the end and kink nodes exact."""
    p = np.exp(_x_nodes(grid))
    p[0], p[grid.nx_a], p[-1] = P_MIN, P_SPLIT, P_MAX
    return p


def _y_nodes(n: int, c: float) -> FloatArray:
    """Y at the uniform nodes of eta: Y = c·eta + (1 − c)·eta² (clusters nodes near Y = 0)."""
    eta = np.linspace(0.0, 1.0, n + 1)
    return c * eta + (1.0 - c) * eta**2


def _newton_t(p: FloatArray, target: FloatArray, key: str, T0: FloatArray) -> FloatArray:
    """Solve h(p, T) = target (key 'h') or s(p, T) = target (key 's') in region 2."""
    from steamtwin.steam import if97

    T = T0.copy()
    for _ in range(30):
        cp = if97.isobaric_heat_capacity_pt(p, T)
        if key == "h":
            step = (if97.enthalpy_pt(p, T) - target) / cp
        else:
            step = (if97.entropy_pt(p, T) - target) * T / cp
        T -= step
        if np.max(np.abs(step) / T) < 1e-12:
            return T
    raise RuntimeError("steam table sampling: Newton iteration did not converge")


def _initial_t(values: FloatArray, T_rows: FloatArray, targets: FloatArray) -> FloatArray:
    """Per-row interpolation of T from monotone samples ``values`` (initial Newton guess)."""
    out = np.empty_like(targets)
    for i in range(values.shape[0]):
        out[i] = CubicSpline(values[i], T_rows[i])(targets[i])
    return out


def _sample(grid: _Grid) -> dict[str, FloatArray]:
    """Evaluate IF97 at all grid nodes; returns node arrays keyed by name."""
    from steamtwin.steam import if97

    x = _x_nodes(grid)
    p = _p_nodes(grid)
    t_low = lower_boundary_temperature(p) + T_MARGIN
    h_low = if97.enthalpy_pt(p, t_low)
    h_high = if97.enthalpy_pt(p, T_MAX)
    s_low = if97.entropy_pt(p, t_low)
    s_high = if97.entropy_pt(p, T_MAX)
    P2 = p[:, None]

    y_pt = _y_nodes(grid.ny_pt, grid.c_pt)
    T_pt = t_low[:, None] + y_pt[None, :] * (T_MAX - t_low)[:, None]
    h_pt = if97.enthalpy_pt(P2, T_pt)
    s_pt = if97.entropy_pt(P2, T_pt)

    y_ph = _y_nodes(grid.ny_ph, grid.c_ph)
    h_ph = h_low[:, None] + y_ph[None, :] * (h_high - h_low)[:, None]
    T_ph = _newton_t(np.broadcast_to(P2, h_ph.shape), h_ph, "h", _initial_t(h_pt, T_pt, h_ph))
    T_ph[:, 0], T_ph[:, -1] = t_low, T_MAX  # exact at the edges
    ph = np.empty((_N_PH, *h_ph.shape))
    ph[PH_T] = T_ph
    ph[PH_S] = if97.entropy_pt(P2, T_ph)
    ph[PH_V] = P2 * if97.specific_volume_pt(P2, T_ph)  # tabulate p·v
    ph[PH_CP] = if97.isobaric_heat_capacity_pt(P2, T_ph)
    ph[PH_MU] = if97.viscosity_pt(P2, T_ph)
    ph[PH_K] = if97.thermal_conductivity_pt(P2, T_ph)

    y_ps = _y_nodes(grid.ny_ps, grid.c_ps)
    s_ps = s_low[:, None] + y_ps[None, :] * (s_high - s_low)[:, None]
    T_ps = _newton_t(np.broadcast_to(P2, s_ps.shape), s_ps, "s", _initial_t(s_pt, T_pt, s_ps))
    T_ps[:, 0], T_ps[:, -1] = t_low, T_MAX
    h_ps = if97.enthalpy_pt(P2, T_ps)

    return {
        "x": x,
        "bounds": np.stack([t_low, h_low, h_high, s_low, s_high]),
        "ph": ph,
        "ps": h_ps,
        "pt": h_pt,
    }


# --------------------------------------------------------------------------------------------
# Spline assembly
# --------------------------------------------------------------------------------------------

# Hermite basis: p(t) = [1, t, t², t³] · M · [f(0), f(1), f'(0), f'(1)]ᵀ.
_HERMITE = np.array(
    [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [-3.0, 3.0, -2.0, -1.0], [2.0, -2.0, 1.0, 1.0]]
)


def _segments(grid: _Grid) -> tuple[slice, slice]:
    na = grid.nx_a
    return slice(0, na + 1), slice(na, na + grid.nx_b + 1)


def _cubic_coefficients(x: FloatArray, values: FloatArray, grid: _Grid) -> FloatArray:
    """Local cubic coefficients (ascending powers of t) of per-segment cubic splines."""
    out = []
    for seg in _segments(grid):
        xs = x[seg]
        c = CubicSpline(xs, values[seg]).c  # c[k] multiplies (x - x_i)^(3 - k)
        dx = np.diff(xs)
        out.append(np.stack([c[3], c[2] * dx, c[1] * dx**2, c[0] * dx**3], axis=-1))
    return np.concatenate(out, axis=0)


def _bicubic_coefficients(x: FloatArray, values: FloatArray, grid: _Grid) -> FloatArray:
    """Per-cell bicubic coefficients (ncx, ncy, 16) of per-segment bicubic splines."""
    ny = values.shape[1] - 1
    y = np.linspace(0.0, 1.0, ny + 1)
    dy = 1.0 / ny
    out = []
    for seg in _segments(grid):
        xs = x[seg]
        dx = xs[1] - xs[0]
        spl = RectBivariateSpline(xs, y, values[seg], kx=3, ky=3, s=0)
        f = values[seg]
        ft = spl(xs, y, dx=1) * dx
        fu = spl(xs, y, dy=1) * dy
        ftu = spl(xs, y, dx=1, dy=1) * (dx * dy)
        K = np.empty((len(xs) - 1, ny, 4, 4))
        for a, (g0, g1) in enumerate(((f, fu), (ft, ftu))):
            K[:, :, 2 * a, 0] = g0[:-1, :-1]
            K[:, :, 2 * a + 1, 0] = g0[1:, :-1]
            K[:, :, 2 * a, 1] = g0[:-1, 1:]
            K[:, :, 2 * a + 1, 1] = g0[1:, 1:]
            K[:, :, 2 * a, 2] = g1[:-1, :-1]
            K[:, :, 2 * a + 1, 2] = g1[1:, :-1]
            K[:, :, 2 * a, 3] = g1[:-1, 1:]
            K[:, :, 2 * a + 1, 3] = g1[1:, 1:]
        A = np.einsum("mk,ijkl,nl->ijmn", _HERMITE, K, _HERMITE)
        out.append(A.reshape(len(xs) - 1, ny, 16))
    return np.ascontiguousarray(np.concatenate(out, axis=0))


def _assemble(nodes: dict[str, FloatArray], grid: _Grid) -> SteamTables:
    x = nodes["x"]
    na, nb = grid.nx_a, grid.nx_b
    meta = np.array(
        [
            x[0],
            x[na],
            x[-1],
            x[1] - x[0],
            x[na + 1] - x[na],
            float(na),
            float(nb),
            P_MIN,
            P_MAX,
            T_MAX,
            grid.c_ph,
            grid.c_ps,
            grid.c_pt,
            1.0 / (x[1] - x[0]),
            1.0 / (x[na + 1] - x[na]),
        ]
    )
    bounds = np.ascontiguousarray(
        np.stack([_cubic_coefficients(x, b, grid) for b in nodes["bounds"]])
    )
    ph = np.ascontiguousarray(np.stack([_bicubic_coefficients(x, v, grid) for v in nodes["ph"]]))
    return SteamTables(
        meta=meta,
        bounds=bounds,
        ph=ph,
        ps=_bicubic_coefficients(x, nodes["ps"], grid)[np.newaxis],
        pt=_bicubic_coefficients(x, nodes["pt"], grid)[np.newaxis],
    )


def build_steam_tables() -> SteamTables:
    """Build the tables from IF97 (no caching); takes a few seconds."""
    return _assemble(_sample(_GRID), _GRID)


# --------------------------------------------------------------------------------------------
# Cache
# --------------------------------------------------------------------------------------------


def _coolprop_version() -> str:
    try:
        return importlib.metadata.version("CoolProp")
    except importlib.metadata.PackageNotFoundError:  # e.g. a source build without metadata
        import CoolProp

        return str(CoolProp.__version__)


def steam_tables_cache_path() -> Path:
    """Path of the .npz cache of the sampled grid values for this format and CoolProp version.

    The directory is :func:`steamtwin.cache.cache_root`.
    """
    name = f"steam_tables_v{TABLE_FORMAT_VERSION}_coolprop-{_coolprop_version()}.npz"
    return cache_root() / name


def _grid_signature(grid: _Grid) -> FloatArray:
    return np.array(
        [TABLE_FORMAT_VERSION, P_MIN, P_MAX, T_MAX, T_MARGIN, *grid],
        dtype=np.float64,
    )


def _expected_shapes(grid: _Grid) -> dict[str, tuple[int, ...]]:
    nx = grid.nx_a + grid.nx_b + 1
    return {
        "x": (nx,),
        "bounds": (5, nx),
        "ph": (_N_PH, nx, grid.ny_ph + 1),
        "ps": (nx, grid.ny_ps + 1),
        "pt": (nx, grid.ny_pt + 1),
    }


def _load_nodes(path: Path, grid: _Grid) -> dict[str, FloatArray] | None:
    """Return cached node arrays, or None if the file is missing, corrupt or mismatched."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if str(data["coolprop_version"]) != _coolprop_version():
                return None
            if not np.array_equal(data["signature"], _grid_signature(grid)):
                return None
            nodes = {}
            for key, shape in _expected_shapes(grid).items():
                arr = np.array(data[key], dtype=np.float64)
                if arr.shape != shape or not np.all(np.isfinite(arr)):
                    return None
                nodes[key] = arr
    except Exception:  # any unreadable/corrupt file is simply rebuilt
        return None
    return nodes


def _save_nodes(path: Path, nodes: dict[str, FloatArray], grid: _Grid) -> None:
    """Write the cache atomically; failures (e.g. read-only directory) are ignored."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=path.stem, suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(
                    fh,
                    coolprop_version=np.array(_coolprop_version()),
                    signature=_grid_signature(grid),
                    **nodes,
                )
            os.replace(tmp, path)
        finally:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
    except OSError:
        pass


def load_or_build_steam_tables(path: Path | None = None) -> SteamTables:
    """Load the sampled grid from the cache file (default :func:`steam_tables_cache_path`) or
    sample IF97 and write the cache; a corrupt or mismatched cache file is rebuilt."""
    path = steam_tables_cache_path() if path is None else Path(path)
    nodes = _load_nodes(path, _GRID)
    if nodes is None:
        nodes = _sample(_GRID)
        _save_nodes(path, nodes, _GRID)
    return _assemble(nodes, _GRID)


@functools.lru_cache(maxsize=1)
def steam_tables() -> SteamTables:
    """The process-wide steam tables (built once; grid values cached on disk)."""
    return load_or_build_steam_tables()


# --------------------------------------------------------------------------------------------
# numba kernels
# --------------------------------------------------------------------------------------------


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _locate_x(meta: FloatArray, p: float) -> tuple[int, float]:
    """Cell index along ln p and local coordinate t (unclamped, for extrapolation)."""
    return _locate_ln_p(meta, math.log(p) if p > 0.0 else math.nan)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _locate_ln_p(meta: FloatArray, x: float) -> tuple[int, float]:
    """As :func:`_locate_x` for x = ln(p / Pa) given.

    The ln p axis is uniform in each of its two segments, so the cell follows from x by index
    arithmetic (no search, so no warm start either: Press et al., *Numerical Recipes*, 3rd ed.,
    §3.1.1, "hunt", helps only on non-uniform tables).
    """
    if x < meta[_M_X_SPLIT]:
        r = (x - meta[_M_X_MIN]) * meta[_M_INV_DX_A]
        n = meta[_M_N_A]
        off = 0.0
    else:
        r = (x - meta[_M_X_SPLIT]) * meta[_M_INV_DX_B]
        n = meta[_M_N_B]
        off = meta[_M_N_A]
    fi = math.floor(r)
    if not fi >= 0.0:  # also catches NaN
        fi = 0.0
    elif fi > n - 1.0:
        fi = n - 1.0
    return int(fi + off), r - fi


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _locate_y(y: float, c: float, n: int) -> tuple[int, float]:
    """Cell index and local coordinate u along eta, where Y = c·eta + (1 − c)·eta²."""
    if c == 1.0:  # uniform grid
        eta = y
    elif y > 0.0:
        eta = 2.0 * y / (c + math.sqrt(c * c + 4.0 * (1.0 - c) * y))
    else:  # linear continuation below Y = 0 (value and slope continuous)
        eta = y / c
    r = eta * n
    fj = math.floor(r)
    if not fj >= 0.0:
        fj = 0.0
    elif fj > n - 1.0:
        fj = n - 1.0
    return int(fj), r - fj


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _cubic(c: FloatArray, k: int, i: int, t: float) -> float:
    return c[k, i, 0] + t * (c[k, i, 1] + t * (c[k, i, 2] + t * c[k, i, 3]))


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _bicubic(a: FloatArray, k: int, i: int, j: int, t: float, u: float) -> float:
    """Evaluate Σ a[k, i, j, m*4+n] t^m u^n by scalar indexing.

    Indexing element by element rather than slicing ``a[k, i, j]`` matters for speed: a slice is
    a new array view, and its reference counting costs more than the polynomial.
    """
    r3 = a[k, i, j, 12] + u * (a[k, i, j, 13] + u * (a[k, i, j, 14] + u * a[k, i, j, 15]))
    r2 = a[k, i, j, 8] + u * (a[k, i, j, 9] + u * (a[k, i, j, 10] + u * a[k, i, j, 11]))
    r1 = a[k, i, j, 4] + u * (a[k, i, j, 5] + u * (a[k, i, j, 6] + u * a[k, i, j, 7]))
    r0 = a[k, i, j, 0] + u * (a[k, i, j, 1] + u * (a[k, i, j, 2] + u * a[k, i, j, 3]))
    return r0 + t * (r1 + t * (r2 + t * r3))


# Located-pressure kernels: a model that evaluates several properties at one pressure locates
# it on the ln p axis once (one logarithm) and reuses the cell for every look-up there.


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def locate_pressure(tables: SteamTables, p: float) -> tuple[int, float]:
    """Cell index and local coordinate of pressure p (Pa) on the ln p axis (for ``*_at``)."""
    return _locate_x(tables.meta, p)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _ph_cell(tables: SteamTables, i: int, t: float, h: float) -> tuple[int, float]:
    return _locate_y(_ph_position(tables, i, t, h), tables.meta[_M_C_PH], tables.ph.shape[2])


# inlined into its callers (the kernel's throttle, control stage and acceptance, ~7 calls a
# sample): 2–4 % of a GA evaluation, the same bits, ~+10 s of CPU for a cold compile
# (docs/benchmarks.md, session 19)
@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def ph_property_at(tables: SteamTables, prop: int, i: int, t: float, p: float, h: float) -> float:
    """As :func:`ph_property` at pressure p (Pa) already located as cell ``i``, coordinate ``t``."""
    if prop < 0 or prop >= tables.ph.shape[0]:
        return math.nan
    j, u = _ph_cell(tables, i, t, h)
    val = _bicubic(tables.ph, prop, i, j, t, u)
    if prop == PH_V:
        val /= p
    return val


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def locate_log_pressure(tables: SteamTables, x: float) -> tuple[int, float]:
    """As :func:`locate_pressure` for x = ln(p / Pa): a caller that keeps ln p of its pressures
    locates a geometric mean sqrt(p_a·p_b) at (x_a + x_b)/2 without a logarithm."""
    return _locate_ln_p(tables.meta, x)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _ph_position(tables: SteamTables, i: int, t: float, h: float) -> float:
    h_lo = _cubic(tables.bounds, _B_HLOW, i, t)
    h_hi = _cubic(tables.bounds, _B_HHIGH, i, t)
    return (h - h_lo) / (h_hi - h_lo)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def ph_domain_position_at(tables: SteamTables, i: int, t: float, h: float) -> float:
    """As :func:`ph_domain_position` at a pressure located as cell ``i``, coordinate ``t``
    (no range check: the caller located a pressure it checked); h in J/kg."""
    return _ph_position(tables, i, t, h)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def ph_property_and_position_at(
    tables: SteamTables, prop: int, i: int, t: float, p: float, h: float
) -> tuple[float, float]:
    """:func:`ph_property_at` and :func:`ph_domain_position_at` of one state from one cell
    location: property ``prop`` (PH_*, SI) and Y at the located pressure p (Pa), h (J/kg)."""
    y = _ph_position(tables, i, t, h)
    j, u = _locate_y(y, tables.meta[_M_C_PH], tables.ph.shape[2])
    val = _bicubic(tables.ph, prop, i, j, t, u)
    if prop == PH_V:
        val /= p
    return val, y


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def heat_transfer_properties_at(
    tables: SteamTables, i: int, t: float, p: float, h: float, out: FloatArray
) -> float:
    """T (K), v (m³/kg), cp (J/(kg·K)), μ (Pa·s), k (W/(m·K)) into ``out[PH_*]`` at the located
    pressure p (Pa) and h (J/kg); returns the state's domain position Y.

    As :func:`ph_properties` without the entropy (``out[PH_S]`` is left as it was), which a
    convective heat-transfer coefficient does not use.
    """
    y = _ph_position(tables, i, t, h)
    j, u = _locate_y(y, tables.meta[_M_C_PH], tables.ph.shape[2])
    out[PH_T] = _bicubic(tables.ph, PH_T, i, j, t, u)
    out[PH_V] = _bicubic(tables.ph, PH_V, i, j, t, u) / p
    out[PH_CP] = _bicubic(tables.ph, PH_CP, i, j, t, u)
    out[PH_MU] = _bicubic(tables.ph, PH_MU, i, j, t, u)
    out[PH_K] = _bicubic(tables.ph, PH_K, i, j, t, u)
    return y


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _entropy_and_pv(tables: SteamTables, i: int, t: float, h: float) -> tuple[float, float]:
    j, u = _ph_cell(tables, i, t, h)
    return _bicubic(tables.ph, PH_S, i, j, t, u), _bicubic(tables.ph, PH_V, i, j, t, u)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def _enthalpy_ps(tables: SteamTables, i: int, t: float, s: float) -> float:
    s_lo = _cubic(tables.bounds, _B_SLOW, i, t)
    s_hi = _cubic(tables.bounds, _B_SHIGH, i, t)
    j, u = _locate_y((s - s_lo) / (s_hi - s_lo), tables.meta[_M_C_PS], tables.ps.shape[2])
    return _bicubic(tables.ps, 0, i, j, t, u)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def entropy_and_pv_at(tables: SteamTables, i: int, t: float, h: float) -> tuple[float, float]:
    """Entropy J/(kg·K) and the product p·v (J/kg) at a located pressure and enthalpy h (J/kg)."""
    return _entropy_and_pv(tables, i, t, h)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def enthalpy_ps_at(tables: SteamTables, i: int, t: float, s: float) -> float:
    """Specific enthalpy h (J/kg) at a located pressure and entropy s (J/(kg·K))."""
    return _enthalpy_ps(tables, i, t, s)


# inlined into its caller (the kernel's forward sweep, 12 calls a sample): handing the tables'
# five arrays to a compiled call costs about a look-up; 6–8 % of a GA evaluation, the same bits
# (docs/benchmarks.md, session 19)
@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def isentropic_step_at(
    tables: SteamTables, i: int, t: float, h: float, x_out: float
) -> tuple[float, int, float, float]:
    """The look-ups of one expansion step in one call: p·v (J/kg) at the inlet, located as cell
    ``i`` and coordinate ``t``, with enthalpy h (J/kg); the outlet pressure, given as
    x_out = ln(p_out / Pa), located (cell, coordinate); and the isentropic outlet enthalpy
    h(p_out, s_in) (J/kg).

    The same values as :func:`entropy_and_pv_at`, :func:`locate_log_pressure` and
    :func:`enthalpy_ps_at` in turn, for a third of the calls: each call hands over the tables'
    five arrays field by field (~57 machine words), which costs about as much as a look-up.
    """
    s, pv = _entropy_and_pv(tables, i, t, h)
    i_out, t_out = _locate_ln_p(tables.meta, x_out)
    return pv, i_out, t_out, _enthalpy_ps(tables, i_out, t_out, s)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def pressure_in_range(tables: SteamTables, p: float) -> bool:
    """True if p (Pa) lies within the table pressure range [0.05 MPa, 25 MPa]."""
    return tables.meta[_M_P_MIN] <= p <= tables.meta[_M_P_MAX]


# inlined into its callers (the kernel's throttle, control stage and acceptance, ~7 calls a
# sample): 2–4 % of a GA evaluation, the same bits, ~+10 s of CPU for a cold compile
# (docs/benchmarks.md, session 19)
@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH, inline="always")
def ph_property(tables: SteamTables, prop: int, p: float, h: float) -> float:
    """Property ``prop`` (one of PH_*) at p (Pa), h (J/kg); SI units; NaN for a bad ``prop``."""
    i, t = _locate_x(tables.meta, p)
    return ph_property_at(tables, prop, i, t, p, h)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def ph_properties(tables: SteamTables, p: float, h: float, out: FloatArray) -> None:
    """Write all six PH_* properties at p (Pa), h (J/kg) into ``out[0:6]`` (SI units)."""
    i, t = _locate_x(tables.meta, p)
    j, u = _ph_cell(tables, i, t, h)
    for k in range(tables.ph.shape[0]):
        out[k] = _bicubic(tables.ph, k, i, j, t, u)
    out[PH_V] /= p


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def enthalpy_ps(tables: SteamTables, p: float, s: float) -> float:
    """Specific enthalpy h (J/kg) at p (Pa), s (J/(kg·K))."""
    i, t = _locate_x(tables.meta, p)
    return enthalpy_ps_at(tables, i, t, s)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def enthalpy_pt(tables: SteamTables, p: float, T: float) -> float:
    """Specific enthalpy h (J/kg) at p (Pa), T (K)."""
    i, t = _locate_x(tables.meta, p)
    return enthalpy_pt_at(tables, i, t, T)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def enthalpy_pt_at(tables: SteamTables, i: int, t: float, T: float) -> float:
    """Specific enthalpy h (J/kg) at a located pressure and T (K)."""
    T_lo = _cubic(tables.bounds, _B_TLOW, i, t)
    j, u = _locate_y(
        (T - T_lo) / (tables.meta[_M_T_MAX] - T_lo), tables.meta[_M_C_PT], tables.pt.shape[2]
    )
    return _bicubic(tables.pt, 0, i, j, t, u)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def ph_domain_position(tables: SteamTables, p: float, h: float) -> float:
    """Normalised enthalpy Y = (h − h_low(p)) / (h_high(p) − h_low(p)) of the (p, h) table.

    Y < 0: below the table's lower edge T_boundary(p) + 0.05 K (wet, too cold, region 1/3);
    Y > 1: above T_max = 923.15 K; NaN if p (Pa) is outside the table's pressure range.
    """
    if not pressure_in_range(tables, p):
        return math.nan
    i, t = _locate_x(tables.meta, p)
    return _ph_position(tables, i, t, h)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def ps_domain_position(tables: SteamTables, p: float, s: float) -> float:
    """Normalised entropy Y of the (p, s) table (as :func:`ph_domain_position`); s in J/(kg·K)."""
    if not pressure_in_range(tables, p):
        return math.nan
    i, t = _locate_x(tables.meta, p)
    s_lo = _cubic(tables.bounds, _B_SLOW, i, t)
    s_hi = _cubic(tables.bounds, _B_SHIGH, i, t)
    return (s - s_lo) / (s_hi - s_lo)


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def pt_domain_position(tables: SteamTables, p: float, T: float) -> float:
    """Normalised temperature Y of the (p, T) table (as :func:`ph_domain_position`); T in K."""
    if not pressure_in_range(tables, p):
        return math.nan
    i, t = _locate_x(tables.meta, p)
    T_lo = _cubic(tables.bounds, _B_TLOW, i, t)
    return (T - T_lo) / (tables.meta[_M_T_MAX] - T_lo)


# --------------------------------------------------------------------------------------------
# Array conveniences
# --------------------------------------------------------------------------------------------

_K_PH, _K_PS, _K_PT, _K_DOM = 0, 1, 2, 3


@njit(cache=True, nogil=True, error_model="numpy", fastmath=_FASTMATH)
def _apply(
    tables: SteamTables, kind: int, prop: int, a: FloatArray, b: FloatArray, out: FloatArray
) -> None:
    for n in range(a.size):
        if kind == _K_PH:
            out[n] = ph_property(tables, prop, a[n], b[n])
        elif kind == _K_PS:
            out[n] = enthalpy_ps(tables, a[n], b[n])
        elif kind == _K_PT:
            out[n] = enthalpy_pt(tables, a[n], b[n])
        else:
            out[n] = ph_domain_position(tables, a[n], b[n])


def _vectorised(
    kind: int, prop: int, p: ArrayLike, x: ArrayLike, tables: SteamTables | None
) -> FloatArray:
    tab = steam_tables() if tables is None else tables
    a, b = np.broadcast_arrays(np.asarray(p, dtype=np.float64), np.asarray(x, dtype=np.float64))
    af = np.ascontiguousarray(a).ravel()
    bf = np.ascontiguousarray(b).ravel()
    out = np.empty(af.size)
    _apply(tab, kind, prop, af, bf, out)
    return out.reshape(a.shape)


def tables_ph_property(
    prop: int, p: ArrayLike, h: ArrayLike, tables: SteamTables | None = None
) -> FloatArray:
    """Array version of :func:`ph_property`: property ``prop`` (PH_*) at p (Pa), h (J/kg)."""
    if not 0 <= int(prop) < _N_PH:
        raise ValueError(f"prop must be one of PH_T..PH_K (0..{_N_PH - 1}), got {prop!r}")
    return _vectorised(_K_PH, int(prop), p, h, tables)


def tables_temperature_ph(
    p: ArrayLike, h: ArrayLike, tables: SteamTables | None = None
) -> FloatArray:
    """Temperature T(p, h) in K from the tables; p in Pa, h in J/kg."""
    return _vectorised(_K_PH, PH_T, p, h, tables)


def tables_enthalpy_ps(p: ArrayLike, s: ArrayLike, tables: SteamTables | None = None) -> FloatArray:
    """Specific enthalpy h(p, s) in J/kg from the tables; p in Pa, s in J/(kg·K)."""
    return _vectorised(_K_PS, 0, p, s, tables)


def tables_enthalpy_pt(p: ArrayLike, T: ArrayLike, tables: SteamTables | None = None) -> FloatArray:
    """Specific enthalpy h(p, T) in J/kg from the tables; p in Pa, T in K."""
    return _vectorised(_K_PT, 0, p, T, tables)


def tables_ph_domain_position(
    p: ArrayLike, h: ArrayLike, tables: SteamTables | None = None
) -> FloatArray:
    """Array version of :func:`ph_domain_position` (NaN where p is out of range)."""
    return _vectorised(_K_DOM, 0, p, h, tables)
