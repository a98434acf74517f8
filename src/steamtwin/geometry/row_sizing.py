"""Blade rows sized from the turbine spec: the row names, the design choices with their
sources, :class:`RowDesign` (a row's mean section and its free-vortex twist and taper) and the
sizing of the HP rotor rows; the IP stator rows are estimated in :mod:`.ip_rows`, and
:func:`steamtwin.geometry.profile.row_design` picks between the two.

The public row-design module that :mod:`.profile` and :mod:`.ip_rows` both build on (it
breaks the import cycle the two once had).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from steamtwin.geometry.pritchard import GeometryError, PritchardParameters
from steamtwin.spec import TurbineSpec

HP_ROWS = tuple(f"hp{k}" for k in range(1, 14))


IP_ROWS = tuple(f"ip{k}" for k in range(1, 10))


ROWS = HP_ROWS + IP_ROWS


# Design choices for sizing the sections, each with its source:
#: Zweifel's optimum tangential loading coefficient, used to set the axial chord from the pitch
#: (Zweifel 1945, Brown Boveri Rev. 32; Dixon & Hall, Fluid Mechanics and Thermodynamics of
#: Turbomachinery, 7th ed. 2014, §3.6: Z ≈ 0.8).
ZWEIFEL = 0.8


#: Unguided turning 5-10° is usual for subsonic turbine blading (Pritchard 1985, his example
#: blades; Moustapha et al., Axial and Radial Turbines, 2003, ch. 4).
UNGUIDED_TURNING = math.radians(7.0)


#: Inlet half-wedge angle and leading-edge radius / axial chord: Pritchard's example rotor
#: (1985) uses ε_in ≈ 10-25°, r_le ≈ 0.04-0.08·Cx. The 130° impulse section of the control stage
#: takes a thin wedge: with Pritchard's cubic suction side any thicker nose pinches the passage
#: upstream below :data:`MIN_PASSAGE_RATIO` of the throat (checked in ``pritchard_profile``).
INLET_HALF_WEDGE = {"impulse": math.radians(4.0), "reaction": math.radians(12.0)}


LEADING_EDGE_RADIUS_RATIO = {"impulse": 0.05, "reaction": 0.06}


#: Trailing-edge radius: 1.5 % of the axial chord, at least 0.35 mm for milling
#: (Moustapha et al. 2003 §4.4: t_te/o ≈ 0.02-0.1 for HP blading).
TRAILING_EDGE_RADIUS_RATIO = 0.015


MIN_TRAILING_EDGE_RADIUS = 0.35e-3


#: Tip/hub chord ratio: the governing stage's short impulse blades are prismatic; the reaction
#: blades are slightly tapered to relieve the root of centrifugal load (engineering choice within
#: the 0.8-1.0 of HP drum blading, Traupel 2001 §19).
TAPER_RATIO = {"impulse": 1.0, "reaction": 0.9}


@dataclass(frozen=True)
class RowDesign:
    """One blade row sized from the turbine spec (SI units; angles in rad).

    ``mean_section`` holds Pritchard's parameters at the mean radius. ``hub_radius``/``tip_radius``
    bound the blade in z; ``taper_ratio`` is tip chord / hub chord; the twist follows the
    free-vortex stagger ``stagger(r)`` (:meth:`section_rotation`).
    """

    row: str
    kind: str  # "rotor" or "stator"
    mean_section: PritchardParameters
    hub_radius: float
    tip_radius: float
    taper_ratio: float
    axial_velocity: float  # m/s
    inlet_swirl_radius: float  # c_theta * r upstream of the row (m²/s), free vortex constant
    outlet_swirl_radius: float  # c_theta * r downstream of the row (m²/s)
    angular_speed: float  # rad/s of the blade frame's relative motion (0 for stators)

    @property
    def mean_radius(self) -> float:
        return self.mean_section.radius

    @property
    def span(self) -> float:
        return self.tip_radius - self.hub_radius

    def blade_angles(self, radius: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Free-vortex relative inlet/outlet flow angles at ``radius`` (rad, from axial).

        c_θ·r = const and constant axial velocity (the free-vortex design, Dixon & Hall §6.2).
        """
        return free_vortex_angles(radius, self.angular_speed, self.axial_velocity,
                                  self.inlet_swirl_radius, self.outlet_swirl_radius)

    def section_rotation(self, radius: float | np.ndarray) -> np.ndarray:
        """Twist (rad, anticlockwise in x-y) of the section at ``radius`` relative to the mean.

        The stagger of a section follows the mean of its blade angles (circular-arc camber line);
        the twist is its change from the mean radius.
        """
        inlet, outlet = self.blade_angles(radius)
        inlet_m, outlet_m = self.blade_angles(self.mean_radius)
        return 0.5 * (inlet + outlet) - 0.5 * (inlet_m + outlet_m)

    def chord_scale(self, radius: float | np.ndarray) -> np.ndarray:
        """Chord of the section at ``radius`` relative to the mean section (linear taper)."""
        f = (np.asarray(radius, dtype=float) - self.hub_radius) / self.span
        return (1.0 + (self.taper_ratio - 1.0) * f) / (1.0 + 0.5 * (self.taper_ratio - 1.0))


def free_vortex_angles(radius: float | np.ndarray, angular_speed: float, axial_velocity: float,
                       inlet_swirl_radius: float, outlet_swirl_radius: float
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Relative inlet/outlet flow angles (rad, from axial) of a free-vortex row at ``radius``.

    c_θ·r = const and constant axial velocity (free vortex, Dixon & Hall 2014 §6.2); the blade
    frame moves at ``angular_speed`` (rad/s, 0 for a stator).
    """
    r = np.asarray(radius, dtype=float)
    u = angular_speed * r
    inlet = np.arctan((inlet_swirl_radius / r - u) / axial_velocity)
    outlet = np.arctan((outlet_swirl_radius / r - u) / axial_velocity)
    return inlet, outlet


def section_from_angles(radius: float, blade_count: int, inlet: float, outlet: float,
                         style: str) -> PritchardParameters:
    """Pritchard parameters of a section from its blade angles (rad, from axial)."""
    pitch = 2.0 * math.pi * radius / blade_count
    # Zweifel: Z = 2 (s/Cx) cos²β2 (tan β1 − tan β2)  (angles of opposite sign, Dixon & Hall §3.6)
    axial_chord = 2.0 * pitch * math.cos(outlet) ** 2 * (math.tan(inlet) - math.tan(outlet))
    axial_chord /= ZWEIFEL
    # stagger of a circular-arc camber line = mean of the blade angles (Dixon & Hall §3.4)
    stagger = 0.5 * (inlet + outlet)
    return PritchardParameters(
        radius=radius,
        axial_chord=axial_chord,
        tangential_chord=-axial_chord * math.tan(stagger),
        unguided_turning=UNGUIDED_TURNING,
        inlet_angle=inlet,
        inlet_half_wedge=INLET_HALF_WEDGE[style],
        leading_edge_radius=LEADING_EDGE_RADIUS_RATIO[style] * axial_chord,
        outlet_angle=outlet,
        trailing_edge_radius=max(TRAILING_EDGE_RADIUS_RATIO * axial_chord,
                                 MIN_TRAILING_EDGE_RADIUS),
        blade_count=blade_count,
        # throat by the cosine rule o = s·cos|β2| (Ainley & Mathieson 1951, ARC R&M 2974)
        throat=pitch * math.cos(outlet),
    )


def hp_row_design(spec: TurbineSpec, row: str) -> RowDesign:
    """Size HP rotor row ``row`` (``hp1``…``hp13``) from the turbine spec.

    HP rotor rows: ``hp1`` is the control-stage rotor, ``hp2``… the pressure stages. Velocity
    triangles at the mean radius: stator exit angle α1 (spec, from the wheel plane), zero exit
    swirl and constant axial velocity, with the blade speed from the optimum velocity ratio for
    the stage reaction Λ, u/c1 = cos α1 / (2(1 − Λ)) — which is exactly the reaction of that
    triangle (Dixon & Hall 2014 §4.5; impulse: u/c1 = cos α1 / 2).
    IP stator rows are sized by :func:`steamtwin.geometry.ip_rows.ip_row_design`.
    """
    if row not in HP_ROWS:
        raise GeometryError(f"unknown HP row {row!r}; known: {', '.join(HP_ROWS)}")
    index = HP_ROWS.index(row)
    if index == 0:
        blading, style = spec.control_stage.blading, "impulse"
    else:
        if index > len(spec.stages):
            raise GeometryError(f"row {row!r}: spec {spec.name!r} has only "
                                f"{len(spec.stages)} pressure stages")
        blading, style = spec.stages[index - 1].blading, "reaction"
    omega = spec.design.rotational_speed
    radius = 0.5 * blading.mean_diameter
    u = omega * radius
    alpha1 = blading.nozzle_exit_angle  # from the wheel plane (steam-turbine convention)
    c1 = u * 2.0 * (1.0 - blading.reaction) / math.cos(alpha1)
    axial_velocity = c1 * math.sin(alpha1)
    swirl_in = c1 * math.cos(alpha1) * radius
    inlet, outlet = free_vortex_angles(radius, omega, axial_velocity, swirl_in, 0.0)
    return RowDesign(
        row=row,
        kind="rotor",
        mean_section=section_from_angles(radius, blading.blade_count, float(inlet),
                                         float(outlet), style),
        hub_radius=radius - 0.5 * blading.blade_height,
        tip_radius=radius + 0.5 * blading.blade_height,
        taper_ratio=TAPER_RATIO[style],
        axial_velocity=axial_velocity,
        inlet_swirl_radius=swirl_in,
        outlet_swirl_radius=0.0,
        angular_speed=omega,
    )
