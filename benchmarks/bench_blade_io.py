"""Blade input and output benchmark (issue 19, item 5): a fused mesh as the source, the fitted
surface as STEP/IGES, row metrics with edge radii on a blade without its nominal row.

An 80k-point cloud on the exact blade of ROW (σ 0.017 mm noise along the normal) is
reconstructed; the STL is then used as a fused-mesh source (80k area-uniform samples) and
reconstructed again (deviation from the exact blade of both); the second fit is exported as
STEP and IGES (time, faces, solid), the STEP is read back and meshed (volume against the STL's
and the exact blade's, side face against the B-spline); row metrics at hub, mid and tip with
the row's blade count, edge radii against the exact sections. Prints the figures as JSON.

Run: python benchmarks/bench_blade_io.py [row] [seed]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

from steamtwin.geometry.cad_export import write_cad
from steamtwin.geometry.fidelity import surface_deviation, surface_samples
from steamtwin.geometry.mesh_io import read_mesh_cloud, write_stl
from steamtwin.geometry.profile import make_blade, reference_surface
from steamtwin.geometry.reconstruct import reconstruct_blade
from steamtwin.geometry.row_metrics import blade_row_metrics, design_edge_rows
from steamtwin.geometry.volume_mesh import gmsh_session
from steamtwin.spec import load_spec

NOISE = 0.017e-3
POINTS = 80_000


def _noisy_cloud(blade: object, rng: np.random.Generator) -> np.ndarray:
    vertices, triangles, _ = reference_surface(blade)
    points, faces = trimesh.sample.sample_surface(
        trimesh.Trimesh(vertices, triangles, process=False), POINTS,
        seed=int(rng.integers(2**31)))
    normals = trimesh.Trimesh(vertices, triangles, process=False).face_normals[faces]
    return points + rng.normal(0.0, NOISE, (POINTS, 1)) * normals


def _deviation(blade: object, result: object) -> dict:
    points = surface_samples(result.vertices, result.triangles, 50_000,
                             np.random.default_rng(0))
    d = surface_deviation(blade, points, result.vertices, result.triangles, samples=50_000)
    return {"rms_mm": d.rms * 1e3, "max_mm": d.max * 1e3, "hausdorff_mm": d.hausdorff * 1e3}


def _step_figures(path: Path, surface: object, size: float) -> dict:
    with gmsh_session() as gmsh:
        gmsh.option.setString("Geometry.OCCTargetUnit", "M")
        gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
        faces = [tag for _, tag in gmsh.model.getEntities(2)]
        side = max(faces, key=lambda tag: gmsh.model.occ.getMass(2, tag))
        low, high = gmsh.model.getParametrizationBounds(2, side)
        rng = np.random.default_rng(1)
        uv = np.column_stack([rng.uniform(low[0], high[0], 2000),
                              rng.uniform(low[1], high[1], 2000)])
        xyz = np.reshape(gmsh.model.getValue(2, side, uv.ravel()), (-1, 3))
        error = float(np.abs(xyz[:, :2] - surface(uv[:, 0], xyz[:, 2])).max())
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.mesh.generate(2)
        nodes, coords, _ = gmsh.model.mesh.getNodes()
        index = np.zeros(int(nodes.max()) + 1, dtype=int)
        index[nodes.astype(int)] = np.arange(len(nodes))
        triangles = np.vstack([index[gmsh.model.mesh.getElements(2, tag)[2][0].astype(int)]
                               .reshape(-1, 3) for tag in faces])
        mesh = trimesh.Trimesh(coords.reshape(-1, 3), triangles)
        mesh.merge_vertices()
        return {"volumes": len(gmsh.model.getEntities(3)), "faces": len(faces),
                "side_face_max_error_um": error * 1e6, "meshed_volume_m3": abs(mesh.volume),
                "mesh_size_mm": size * 1e3}


def main(row: str = "hp1", seed: int = 0) -> dict:
    blade = make_blade(load_spec("reference"), row)
    rng = np.random.default_rng(seed)
    figures: dict = {"row": row, "seed": seed, "points": POINTS, "noise_mm": NOISE * 1e3}
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        start = time.perf_counter()
        first = reconstruct_blade(_noisy_cloud(blade, rng))
        figures["cloud_reconstruction_s"] = time.perf_counter() - start
        figures["cloud_deviation"] = _deviation(blade, first)
        stl = write_stl(first, folder / "blade.stl")
        start = time.perf_counter()
        cloud, sampling = read_mesh_cloud(stl, POINTS, random_state=seed)
        second = reconstruct_blade(cloud)
        figures["mesh_source_s"] = time.perf_counter() - start
        figures["mesh_sampling"] = sampling.as_dict()
        figures["mesh_source_deviation"] = _deviation(blade, second)
        start = time.perf_counter()
        export = write_cad(second.surface, second.root, second.tip,
                           [folder / "blade.step", folder / "blade.igs"])
        figures["cad_export_s"] = time.perf_counter() - start
        figures["cad"] = {"solid": export.solid, "faces": export.faces,
                          "control_points": list(export.control_points),
                          **_step_figures(folder / "blade.step", second.surface, 0.3e-3)}
        figures["cad"]["stl_volume_m3"] = second.volume
        figures["cad"]["exact_volume_m3"] = blade.volume
        figures["cad"]["volume_vs_stl"] = (figures["cad"]["meshed_volume_m3"] / second.volume
                                           - 1.0)
        start = time.perf_counter()
        sections = blade_row_metrics(second.vertices, second.triangles,
                                     blade_count=blade.profile.params.blade_count)
        figures["row_metrics_s"] = time.perf_counter() - start
        figures["row_metrics"] = {s.name: {r["metric"]: r["measured"] for r in s.rows()}
                                  for s in sections}
        figures["edge_radii_vs_design_mm"] = design_edge_rows(blade, second.vertices,
                                                              second.triangles)
    return figures


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("row", nargs="?", default="hp1")
    parser.add_argument("seed", nargs="?", type=int, default=0)
    arguments = parser.parse_args()
    print(json.dumps(main(arguments.row, arguments.seed), indent=2, default=float))
