"""The three scripts in examples/ run as a user runs them (``python examples/X.py --quick``)
and their output files hold what the scripts claim: a calibrated twin whose flow coefficient
brackets the plant's truth, a watertight STL close to the exact blade, a replayed day whose
residuals the calibrated twin keeps small.

Each script runs in a fresh interpreter (``sys.executable``) importing the same steamtwin as
this test process, in a temporary folder.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import steamtwin

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TRUE_FLOW = 0.965  # PlantTruth's default flow coefficient (steamtwin.dcs.plant)


def run_example(name: str, *args: str | Path) -> str:
    """Run ``examples/<name>.py --quick *args``; return its output (the test fails with it)."""
    package_root = str(Path(steamtwin.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [package_root, *filter(None, [os.environ.get("PYTHONPATH")])]), "MPLBACKEND": "Agg"}
    result = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py"), "--quick",
                             *map(str, args)], capture_output=True, text=True, env=env,
                            timeout=600, check=False)
    assert result.returncode == 0, f"{name}.py failed:\n{result.stdout}\n{result.stderr}"
    return result.stdout


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp("calibrate")
    return out, run_example("calibrate_from_historian", "--out", out)


def test_calibrate_from_historian_saves_a_twin_whose_interval_holds_the_truth(calibrated):
    out, stdout = calibrated
    twin = steamtwin.Twin.load(out / "twin")  # checks every file against twin.json
    flow = twin.parameters.flow_coefficient
    low, high = twin.intervals["flow_coefficient"]
    assert low <= flow <= high
    assert low <= TRUE_FLOW <= high and abs(flow - TRUE_FLOW) < 0.015
    assert set(twin.intervals) == {"flow_coefficient", "friction_coefficient",
                                   "heat_transfer_coefficient"}
    assert [step["step"] for step in twin.steps][:2] == ["from_spec", "calibrate"]
    assert steamtwin.ModelParameters.from_json(out / "twin" / "params.json") == twin.parameters
    assert f"{flow:.4f}" in stdout and f"[{low:.4f}, {high:.4f}]" in stdout


def test_reconstruct_blade_writes_a_watertight_stl_close_to_the_exact_blade(tmp_path):
    import trimesh

    from steamtwin.geometry import make_blade
    from steamtwin.geometry.pointcloud import read_point_cloud

    run_example("reconstruct_blade", "--out", tmp_path)
    mesh = trimesh.load(tmp_path / "blade.stl")
    assert mesh.is_watertight and mesh.is_winding_consistent
    exact = make_blade(steamtwin.load_spec("reference"), "hp1")
    assert mesh.volume == pytest.approx(exact.volume, rel=0.005)  # 0.04 % measured
    report = json.loads((tmp_path / "deviation.json").read_text(encoding="utf-8"))
    deviation = report["deviation_mm"]
    assert deviation["rms"] < 0.02 and deviation["hausdorff"] < 0.2  # 0.005 / 0.06 measured
    throat = next(row for row in report["metrics"] if row["metric"] == "throat")
    assert abs(throat["error"]) < 0.05  # mm; 0.002 measured
    assert (tmp_path / "deviation_map.png").stat().st_size > 10_000
    assert len(read_point_cloud(tmp_path / "fused.ply")) > 5_000


def test_replay_day_through_the_calibrated_twin_keeps_the_residuals_small(calibrated,
                                                                          tmp_path):
    out, _ = calibrated
    stdout = run_example("replay_day", "--out", tmp_path, "--twin", out / "twin")
    table = pd.read_csv(tmp_path / "residuals.csv").set_index("signal")
    # the uncalibrated twin (parameters 1, 1, 1) gives 4.1 K and 264 kPa on this day; a
    # calibration on 10 min at 50 % load brings them to 0.7 K and 39 kPa (measured)
    assert table.loc["control_stage_temperature", "rms"] < 1.5
    assert table.loc["control_stage_pressure", "rms"] < 1.0e5
    assert table.loc["hp_exhaust_temperature", "rms"] < 2.5
    assert (table["samples"] > 8_000).all()
    assert np.isfinite(table[["mean", "rms", "max_abs"]].to_numpy()).all()
    assert (tmp_path / "measured_vs_twin.png").stat().st_size > 10_000
    assert "flow 0.9" in stdout  # the calibrated twin was the one replayed
