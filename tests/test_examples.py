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
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import steamtwin

pytestmark = pytest.mark.slow  # 62 s of the full suite (2026-11-27): not in the quick loop

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TRUE_FLOW = 0.965  # PlantTruth's default flow coefficient (steamtwin.dcs.plant)


class Example:
    """``examples/<name>.py --quick --out <out> *args`` started in the background (the scripts
    are independent, so the reconstruction runs while the calibration does: on two cores the
    three take the time of the longest chain, not of all three). Its output goes to files
    beside ``out`` (a pipe nobody reads while the script runs would block it when full)."""

    def __init__(self, name: str, out: Path, *args: str | Path) -> None:
        package_root = str(Path(steamtwin.__file__).resolve().parents[1])
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(
            [package_root, *filter(None, [os.environ.get("PYTHONPATH")])]),
            "MPLBACKEND": "Agg"}
        self.name, self.out = name, out
        self.logs = out.with_name(f"{out.name}.stdout"), out.with_name(f"{out.name}.stderr")
        with self.logs[0].open("w") as stdout, self.logs[1].open("w") as stderr:
            self.process = subprocess.Popen(  # the child keeps its own copies of the files
                [sys.executable, str(EXAMPLES / f"{name}.py"), "--quick", "--out", str(out),
                 *map(str, args)], stdout=stdout, stderr=stderr, env=env)

    def output(self) -> str:
        """Wait for the script; its output (the test fails with it when the script did)."""
        try:
            self.process.wait(timeout=600)
        except subprocess.TimeoutExpired:
            self.stop()
            raise
        stdout, stderr = (path.read_text(encoding="utf-8") for path in self.logs)
        assert self.process.returncode == 0, f"{self.name}.py failed:\n{stdout}\n{stderr}"
        return stdout

    def stop(self) -> None:
        """End the script if it still runs."""
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


@pytest.fixture(scope="module")
def folders(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Each script's output folder."""
    return {name: tmp_path_factory.mktemp(name) for name in ("calibrate", "blade", "replay")}


@pytest.fixture(scope="module")
def examples(folders) -> Iterator[dict[str, Example]]:
    """The calibration and the reconstruction started at once; the replay of the calibrated
    twin joins when the calibration is done (:func:`calibrated`)."""
    running = {"calibrate": Example("calibrate_from_historian", folders["calibrate"]),
               "blade": Example("reconstruct_blade", folders["blade"])}
    yield running
    for example in running.values():  # a failed test leaves no script running
        example.stop()


@pytest.fixture(scope="module")
def calibrated(examples, folders) -> tuple[Path, str]:
    """The calibrated twin's folder and the script's output; starts the replay of that twin."""
    stdout = examples["calibrate"].output()
    twin = folders["calibrate"] / "twin"
    examples["replay"] = Example("replay_day", folders["replay"], "--twin", twin)
    return twin, stdout


def test_calibrate_from_historian_saves_a_twin_whose_interval_holds_the_truth(calibrated):
    folder, stdout = calibrated
    twin = steamtwin.Twin.load(folder)  # checks every file against twin.json
    flow = twin.parameters.flow_coefficient
    low, high = twin.intervals["flow_coefficient"]
    assert low <= flow <= high
    assert low <= TRUE_FLOW <= high and abs(flow - TRUE_FLOW) < 0.015
    assert set(twin.intervals) == {"flow_coefficient", "friction_coefficient",
                                   "heat_transfer_coefficient"}
    assert [step["step"] for step in twin.steps][:2] == ["from_spec", "calibrate"]
    assert steamtwin.ModelParameters.from_json(folder / "params.json") == twin.parameters
    assert f"{flow:.4f}" in stdout and f"[{low:.4f}, {high:.4f}]" in stdout


def test_reconstruct_blade_writes_a_watertight_stl_close_to_the_exact_blade(examples):
    import trimesh

    from steamtwin.geometry import make_blade
    from steamtwin.geometry.pointcloud import read_point_cloud

    examples["blade"].output()
    out = examples["blade"].out
    mesh = trimesh.load(out / "blade.stl")
    assert mesh.is_watertight and mesh.is_winding_consistent
    exact = make_blade(steamtwin.load_spec("reference"), "hp1")
    assert mesh.volume == pytest.approx(exact.volume, rel=0.005)  # 0.04 % measured
    report = json.loads((out / "deviation.json").read_text(encoding="utf-8"))
    deviation = report["deviation_mm"]
    assert deviation["rms"] < 0.02 and deviation["hausdorff"] < 0.2  # 0.005 / 0.06 measured
    throat = next(row for row in report["metrics"] if row["metric"] == "throat")
    assert abs(throat["error"]) < 0.05  # mm; 0.002 measured
    assert (out / "deviation.png").stat().st_size > 10_000
    assert len(read_point_cloud(out / "fused.ply")) > 5_000


def test_replay_day_through_the_calibrated_twin_keeps_the_residuals_small(calibrated,
                                                                          examples):
    stdout = examples["replay"].output()
    replay = examples["replay"].out
    table = pd.read_csv(replay / "residuals.csv").set_index("signal")
    # the uncalibrated twin (parameters 1, 1, 1) gives 4.1 K and 264 kPa on this day; a
    # calibration on 10 min at 50 % load brings them to 0.7 K and 39 kPa (measured)
    assert table.loc["control_stage_temperature", "rms"] < 1.5
    assert table.loc["control_stage_pressure", "rms"] < 1.0e5
    assert table.loc["hp_exhaust_temperature", "rms"] < 2.5
    assert (table["samples"] > 8_000).all()
    assert np.isfinite(table[["mean", "rms", "max_abs"]].to_numpy()).all()
    assert (replay / "measured_vs_twin.png").stat().st_size > 10_000
    flow = steamtwin.Twin.load(calibrated[0]).parameters.flow_coefficient
    assert f"flow {flow:.4f}," in stdout  # the calibrated twin was the one replayed
