"""CAD export of a reconstructed blade: the B-spline side and the cap planes as STEP and IGES.

The side is the periodic cubic B-spline :class:`~steamtwin.geometry.bspline.PeriodicSurface`
``(x, y)(s, z)``. CAD exchange wants a clamped (non-periodic) B-spline, so the periodic one is
converted exactly by knot insertion at the seam s = 0 (Piegl & Tiller, The NURBS Book, 2nd ed.
1997, §5.2, Boehm's algorithm — scipy's ``BSpline.insert_knot``): with s = 0 and s = 1 raised to
multiplicity degree + 1 the curve between them is a clamped B-spline whose control points are
the inserted ones, the same curve to rounding. The third coordinate is the parameter z itself;
a cubic B-spline reproduces a linear function with the Greville abscissae of its knots as
coefficients (de Boor, A Practical Guide to Splines, 2001, ch. IX), so the control points are
``(x, y, Greville(z))`` and the surface is exactly ``(x(s, z), y(s, z), z)``.

The solid is built in gmsh's OpenCASCADE kernel: the side face is cut (``fragment``) by two
rectangles lying in the cap planes (:class:`~steamtwin.geometry.segmentation.CapPlane`), the
piece of the side between them and the two pieces of the rectangles inside it are kept and
closed into a shell and a volume — the same solid as the STL of
:func:`~steamtwin.geometry.reconstruct.triangulate`, with exact faces. When the kernel cannot
close it, the three faces are written without a volume (:attr:`CadExport.solid` False).
Files are written in millimetres (the unit STEP and IGES declare by default; a CAD system reads
the size right); the model is built in metres × 1000.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import BSpline, NdBSpline

from steamtwin.errors import GeometryAreaError
from steamtwin.geometry.bspline import DEGREE, PeriodicSurface, periodic_knots
from steamtwin.geometry.segmentation import CapPlane
from steamtwin.geometry.volume_mesh import gmsh_session

#: File suffixes written, by format.
CAD_SUFFIXES = {".step": "STEP", ".stp": "STEP", ".igs": "IGES", ".iges": "IGES"}
#: Model units per metre: the files are in millimetres.
MM_PER_M = 1e3


class CadExportError(GeometryAreaError):
    """A CAD file that cannot be written; the message names the file and the problem."""


@dataclass(frozen=True)
class ClampedSurface:
    """A clamped tensor-product cubic B-spline in the form of CAD kernels (m).

    ``knots_u``/``knots_v`` distinct knots with ``multiplicities_u``/``multiplicities_v``
    (end multiplicity degree + 1); ``control_points`` (nu, nv, 3) in m. u ∈ [0, 1] is the
    periodic ``s`` of the side (first and last control row coincide: the seam), v is z (m).
    """

    knots_u: np.ndarray
    multiplicities_u: np.ndarray
    knots_v: np.ndarray
    multiplicities_v: np.ndarray
    control_points: np.ndarray

    def __call__(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Points (n, 3) of the surface (m) at parameters ``u`` ∈ [0, 1] and ``v`` (m)."""
        knots = (np.repeat(self.knots_u, self.multiplicities_u),
                 np.repeat(self.knots_v, self.multiplicities_v))
        spline = NdBSpline(knots, self.control_points, DEGREE)
        return spline(np.column_stack([np.asarray(u, float), np.asarray(v, float)]))


@dataclass(frozen=True)
class CadExport:
    """What :func:`write_cad` wrote: ``paths``; ``solid`` whether the faces close into a
    volume; ``faces`` the number of faces (side and caps); ``control_points`` (nu, nv) of the
    side; ``unit`` of the files."""

    paths: tuple[Path, ...]
    solid: bool
    faces: int
    control_points: tuple[int, int]
    unit: str = "mm"


def clamped_side(surface: PeriodicSurface) -> ClampedSurface:
    """The side surface as a clamped B-spline (exact: knot insertion at the seam, Piegl &
    Tiller §5.2), with z as third coordinate (Greville abscissae)."""
    breaks, m = surface.breaks, len(surface.breaks)
    wrapped = np.concatenate([surface.coefficients, surface.coefficients[:DEGREE]], axis=0)
    spline = BSpline(periodic_knots(breaks), wrapped, DEGREE)
    # s = 0 and s = 1 are simple knots of the unwrapped periodic spline: raise both to
    # multiplicity degree + 1; the control points between them are those of the clamped curve
    spline = spline.insert_knot(0.0, DEGREE).insert_knot(1.0, DEGREE)
    first = int(np.flatnonzero(spline.t == 0.0)[0])
    xy = spline.c[first:first + m + DEGREE]  # (m + 3, nz, 2)
    z_knots = surface.z_knots
    greville = np.array([z_knots[j + 1:j + DEGREE + 1].mean()
                         for j in range(len(z_knots) - DEGREE - 1)])
    z = np.broadcast_to(greville[None, :, None], (*xy.shape[:2], 1))
    knots_v, multiplicities_v = np.unique(z_knots, return_counts=True)
    return ClampedSurface(
        knots_u=np.append(breaks, 1.0),
        multiplicities_u=np.array([DEGREE + 1] + [1] * (m - 1) + [DEGREE + 1]),
        knots_v=knots_v, multiplicities_v=multiplicities_v,
        control_points=np.concatenate([xy, z], axis=2))


def write_cad(surface: PeriodicSurface, root: CapPlane, tip: CapPlane,
              paths: list[str | Path]) -> CadExport:
    """Write the side ``surface`` closed by the ``root`` and ``tip`` cap planes (m) to every
    path, STEP (.step/.stp) or IGES (.igs/.iges) by its suffix, in millimetres.

    Raises :class:`CadExportError` naming the file for an unknown suffix or when the kernel
    cannot build or write the faces.
    """
    paths = [Path(p) for p in paths]
    for path in paths:
        if path.suffix.lower() not in CAD_SUFFIXES:
            raise CadExportError(f"{path}: unknown CAD format {path.suffix!r}; expected one of "
                                 f"{', '.join(CAD_SUFFIXES)}")
    clamped = clamped_side(surface)
    with gmsh_session() as gmsh:
        try:
            solid, faces = _build(gmsh, clamped, root, tip)
        except Exception as error:  # gmsh raises bare Exceptions carrying OCC's message
            raise CadExportError(f"{paths[0] if paths else 'CAD'}: the OpenCASCADE kernel "
                                 f"could not build the blade's faces: {error}") from None
        for path in paths:
            path.parent.mkdir(parents=True, exist_ok=True)
            try:
                with _quiet_stdout():
                    gmsh.write(str(path))
            except Exception as error:  # as above
                raise CadExportError(f"{path}: cannot write the "
                                     f"{CAD_SUFFIXES[path.suffix.lower()]} file: {error}"
                                     ) from None
    return CadExport(paths=tuple(paths), solid=solid, faces=faces,
                     control_points=clamped.control_points.shape[:2])


def _build(gmsh: object, clamped: ClampedSurface, root: CapPlane, tip: CapPlane
           ) -> tuple[bool, int]:
    """Side face, cap faces and (when the kernel closes them) the volume, in mm; returns
    (solid, number of faces)."""
    occ = gmsh.model.occ
    points = clamped.control_points * MM_PER_M
    nu, nv = points.shape[:2]
    # gmsh orders the control points u fastest
    tags = [occ.addPoint(*points[i, j]) for j in range(nv) for i in range(nu)]
    side = occ.addBSplineSurface(
        tags, nu, degreeU=DEGREE, degreeV=DEGREE,
        knotsU=list(clamped.knots_u), knotsV=list(clamped.knots_v * MM_PER_M),
        multiplicitiesU=[int(k) for k in clamped.multiplicities_u],
        multiplicitiesV=[int(k) for k in clamped.multiplicities_v])
    occ.remove([(0, tag) for tag in tags])
    # rectangles in the cap planes, centred on the blade and twice its size
    centre = points[:, :, :2].reshape(-1, 2).mean(axis=0) / MM_PER_M
    half = 2.0 * float(np.abs(points[:, :, :2].reshape(-1, 2) / MM_PER_M - centre).max())
    rectangles = [_rectangle(occ, plane, centre, half) for plane in (root, tip)]
    _, pieces = occ.fragment([(2, side)], [(2, r) for r in rectangles])
    occ.synchronize()

    def between(tag: int) -> bool:
        x, y, z = np.array(occ.getCenterOfMass(2, tag)) / MM_PER_M
        xy = np.array([[x, y]])
        return float(root.height(xy)[0]) < z < float(tip.height(xy)[0])

    kept = [tag for _, tag in pieces[0] if between(tag)]
    # the piece of each rectangle inside the side is the smaller one
    kept += [min(piece, key=lambda dim_tag: occ.getMass(*dim_tag))[1] for piece in pieces[1:]]
    occ.remove([dim_tag for dim_tag in occ.getEntities(2) if dim_tag[1] not in kept],
               recursive=True)
    try:
        occ.addVolume([occ.addSurfaceLoop(kept)])
        solid = True
    except Exception:  # the kernel could not close the shell: the faces alone are written
        solid = False
    occ.synchronize()
    return solid, len(kept)


def _rectangle(occ: object, plane: CapPlane, centre: np.ndarray, half: float) -> int:
    """A square of half-width ``half`` (m) in ``plane`` centred above ``centre`` (m), in mm;
    placed by a rotation and a translation so that it stays a plane (a general affine map
    would turn it into a B-spline)."""
    _, b, c = plane.coefficients
    normal = np.array([-b, -c, 1.0]) / np.linalg.norm([-b, -c, 1.0])
    size = 2.0 * half * MM_PER_M
    tag = occ.addRectangle(-0.5 * size, -0.5 * size, 0.0, size, size)
    axis = np.cross([0.0, 0.0, 1.0], normal)
    if np.linalg.norm(axis) > 0.0:
        angle = float(np.arccos(np.clip(normal[2], -1.0, 1.0)))
        occ.rotate([(2, tag)], 0.0, 0.0, 0.0, *axis, angle)
    origin = np.append(centre, plane.height(centre[None, :])[0]) * MM_PER_M
    occ.translate([(2, tag)], *origin)
    return tag


@contextlib.contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence the process's stdout (file descriptor 1): OpenCASCADE's STEP writer prints its
    transfer statistics there whatever gmsh's verbosity."""
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "w", encoding="utf-8") as null:
        os.dup2(null.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)
