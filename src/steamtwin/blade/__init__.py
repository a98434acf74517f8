"""Temperature field of the control-stage rotor blade: P1 FEM with steam-side boundary conditions.

``BladeConduction(mesh, material)`` solves steady and transient conduction on a tetrahedral
``VolumeMesh``; ``SteamBoundary(conduction, spec).convection(state, params)`` turns the FOM's
governing-stage state into the convective boundary conditions; ``blade.verification`` holds the
analytic checks and the mesh-convergence study. See docs/rom.md.
"""

from steamtwin.blade.conduction import BladeConduction, SolverError
from steamtwin.blade.mesh import REGIONS, MeshError, SolidMesh, block_mesh
from steamtwin.blade.steam import (
    ControlStageState,
    SteamBoundary,
    control_stage_states,
    velocity_triangles,
)

__all__ = [
    "REGIONS",
    "BladeConduction",
    "ControlStageState",
    "MeshError",
    "SolidMesh",
    "SolverError",
    "SteamBoundary",
    "block_mesh",
    "control_stage_states",
    "velocity_triangles",
]
