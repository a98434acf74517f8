"""Issue 16, findings 6 and 7 at the CLI: no tracebacks from user errors, output paths checked
before any work, ``simulate`` errors in the file's terms, naive timestamps made explicit."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import steamtwin.model.simulate_file as simulate_file
from steamtwin.cli.main import EXIT_CODES, app
from steamtwin.dcs.plant import KKS_TAGS, plant_tag_map
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.geometry.pointcloud import write_point_cloud
from steamtwin.model.fom import INPUT_RANGES, InputError
from steamtwin.model.simulate_file import in_file_terms

pytestmark = pytest.mark.slow  # 25 s of the full suite (2026-11-27): not in the quick loop

runner = CliRunner()
HEADER = "time,main_steam_pressure,main_steam_temperature,main_steam_flow,hp_exhaust_pressure\n"
BINARY = bytes(range(256)) * 8


def _no_traceback(result) -> None:
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception


class _WorkStarted(RuntimeError):
    """Raised by a stand-in for a command's expensive step: the command got that far."""


def _work_started(*args, **kwargs):
    raise _WorkStarted("the command started its work")


# --- the top-level handler -------------------------------------------------------------------

def test_installed_script_gives_one_line_errors_and_tracebacks_with_debug(tmp_path):
    """The console script (pyproject: steamtwin.cli.main:app) runs under the handler."""
    folder = tmp_path / "out"
    folder.mkdir()
    script = str(Path(sys.executable).parent / "steamtwin")
    args = ["simulate", "--inputs", "in.csv", "--out", str(folder)]
    runs = [subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True) for argv in ([script, *args], [script, "--debug", *args])]
    (plain_out, plain_err), (_, debug_err) = (run.communicate(timeout=180) for run in runs)
    assert runs[0].returncode == 2
    assert plain_err.strip() == f"error: --out {folder}: is a folder; give a file name"
    assert "Traceback" not in plain_err + plain_out
    assert runs[1].returncode == 1
    assert "Traceback (most recent call last)" in debug_err
    assert "OutputPathError: --out" in debug_err


def test_help_documents_the_exit_codes_and_debug():
    result = runner.invoke(app, ["--help"])
    text = " ".join(result.output.split())
    assert result.exit_code == 0
    assert "Exit codes: 0 success; 1 the command failed" in text
    assert "2 bad usage or input" in text and "130 interrupted" in text
    assert "--debug" in text
    assert set(EXIT_CODES) == {0, 1, 2, 130}


@pytest.mark.parametrize(("error", "code", "message"), [
    (ValueError("bad value\nin two lines"), 2, "error: bad value in two lines\n"),
    (FileNotFoundError(2, "No such file or directory", "x.toml"), 2,
     "error: [Errno 2] No such file or directory: 'x.toml'\n"),
    (RuntimeError("boom"), 1, "error: RuntimeError: boom (unexpected; 'steamtwin --debug ...' "
                              "shows the traceback)\n"),
    (KeyboardInterrupt(), 130, "\nerror: interrupted\n"),
])
def test_an_exception_escaping_a_command_is_one_line_and_an_exit_code(
        tmp_path, monkeypatch, error, code, message):
    def fail(turbine):
        raise error

    monkeypatch.setattr(simulate_file, "load_spec", fail)
    args = ["simulate", "--inputs", "in.csv", "--out", str(tmp_path / "o.csv")]
    result = runner.invoke(app, args)
    assert result.exit_code == code
    assert result.output == message
    debug = runner.invoke(app, ["--debug", *args])
    if code == 130:  # Ctrl-C is not an error to debug: the same message and exit code
        assert (debug.exit_code, debug.output) == (code, message)
    else:  # re-raised as is: the caller (python) shows the traceback
        assert debug.exception is error


def test_typer_usage_errors_and_exits_keep_their_codes(tmp_path):
    result = runner.invoke(app, ["simulate", "--inputs", "x.csv", "--out", "o.csv", "--bogus"])
    assert result.exit_code == 2 and "No such option: --bogus" in result.output
    assert runner.invoke(app, ["plant", "--scenario", "nope", "--out", str(tmp_path)]
                         ).exit_code == 2  # a typer.Exit(2) from the command itself
    assert runner.invoke(app, ["turbine", "show", "--help"]).exit_code == 0


# --- output paths checked before the work ----------------------------------------------------

@pytest.mark.parametrize(("args", "message"), [
    (["simulate", "--inputs", "{inputs}", "--out", "{folder}"], "--out {folder}: is a folder"),
    (["dcs", "check", "{inputs}", "--tags", "missing.toml", "--json", "{folder}"],
     "--json {folder}: is a folder"),
    (["plant", "--scenario", "deep-peak-50", "--out", "{file}"], "--out {file}: is a file"),
    (["demo", "--out", "{file}"], "--out {file}: is a file"),
    (["geometry", "scan", "--out", "{file}"], "--out {file}: is a file"),
    (["geometry", "preprocess", "scan", "--out", "{folder}.ply"], "--out {folder}.ply: is a "
                                                                  "folder"),
    (["geometry", "preprocess", "scan", "--out", "fused.txt"], "unknown point-cloud format"),
    (["geometry", "reconstruct", "scan", "--out", "{folder}"], "--out {folder}: is a folder"),
    (["geometry", "reconstruct", "scan", "--out", "b.stl", "--report", "{folder}"],
     "--report {folder}.json: is a folder"),
    (["geometry", "mesh", "--out", "{folder}.vtu"], "--out {folder}.vtu: is a folder"),
    (["geometry", "mesh", "--out", "blade.stl"], "unknown mesh format '.stl'"),
    (["geometry", "assemble", "--out", "{folder}"], "--out {folder}: is a folder"),
    (["geometry", "uncertainty", "--out", "{folder}"], "--out {folder}: is a folder"),
])
def test_an_output_path_that_cannot_be_written_is_refused_before_any_work(
        tmp_path, monkeypatch, args, message):
    """Each command's expensive step is replaced by a marker that would turn the exit code
    into 1: exit code 2 with the path's message proves the check came first."""
    _stub_the_work(monkeypatch)
    monkeypatch.chdir(tmp_path)
    folder, file = tmp_path / "folder", tmp_path / "file"
    (folder.with_suffix(".ply")).mkdir(parents=True)
    folder.mkdir()
    (folder.with_suffix(".vtu")).mkdir()
    (folder.with_suffix(".json")).mkdir()
    file.write_text("x")
    inputs = tmp_path / "inputs.csv"
    inputs.write_text(HEADER + "0,16.7,538,1800,3.9\n")
    names = {"folder": str(folder), "file": str(file), "inputs": str(inputs)}
    result = runner.invoke(app, [arg.format(**names) for arg in args])
    assert result.exit_code == 2, result.output
    assert message.format(**names) in result.output
    _no_traceback(result)


def test_missing_output_folders_are_created(tmp_path):
    tags, data = tmp_path / "tags.toml", tmp_path / "history.csv"
    write_tag_map(plant_tag_map(), tags)
    _historian_csv(data)
    report = tmp_path / "new" / "deeper" / "quality.json"
    result = runner.invoke(app, ["dcs", "check", str(data), "--tags", str(tags), "--json",
                                 str(report)])
    assert result.exit_code in (0, 1), result.output
    assert '"findings"' in report.read_text(encoding="utf-8")


# --- simulate: errors in the file's terms, explicit time zones -------------------------------

def test_simulate_names_file_column_row_and_value_in_the_files_units(tmp_path):
    inputs = tmp_path / "plant-inputs.csv"
    inputs.write_text(HEADER + "2026-03-01T10:00:00Z,16.7,538,1800,3.9\n"
                               "2026-03-01T10:00:01Z,16.7,538,-500,3.9\n")
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out",
                                 str(tmp_path / "o.csv")])
    assert result.exit_code == 2
    assert result.output == (
        f"error: {inputs}: column 'main_steam_flow' data row 2 (line 3): -500 t/h is not a "
        "number within [3.6, 7200] t/h (1 bad row)\n")
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize(("column", "value_si", "expected"), [
    ("main_steam_pressure", 167e6, "column 'main_steam_pressure' data row 4 (line 5): 167 MPa "
                                   "is not a number within [1, 25] MPa (3 bad rows)"),
    ("main_steam_temperature", 263.15, "column 'main_steam_temperature' data row 4 (line 5): "
                                       "-10 °C is not a number within [250, 640] °C"),
    ("main_steam_flow", float("nan"), "column 'main_steam_flow' data row 4 (line 5): an empty "
                                      "cell is not a number within [3.6, 7200] t/h"),
])
def test_range_errors_are_reworded_in_wire_units(column, value_si, expected):
    low, high, unit = INPUT_RANGES[column]
    error = InputError.at(pd.RangeIndex(10), 3, column, "SI text", count=3, value=value_si,
                          limits=(low, high), unit=unit)
    assert in_file_terms(error, Path("in.csv")).startswith(f"in.csv: {expected}")


def test_other_model_errors_keep_their_reason_with_the_files_row():
    error = InputError.at(pd.RangeIndex(10), 6, None, "pressure ratio … ≥ 0.95")
    assert in_file_terms(error, Path("in.csv")) == "in.csv: data row 7 (line 8): pressure " \
                                                   "ratio … ≥ 0.95"
    whole = InputError("inputs must be a non-empty DataFrame of canonical signals")
    assert in_file_terms(whole, Path("in.csv")) == f"in.csv: {whole}"


def test_the_library_message_is_one_based_without_numpy_reprs(reference_model):
    frame = reference_model.design_inputs()
    frame = pd.concat([frame, frame.set_axis(frame.index + pd.Timedelta(seconds=1))])
    frame.iloc[1, frame.columns.get_loc("main_steam_flow")] = -500 / 3.6
    with pytest.raises(InputError) as caught:
        reference_model.check_inputs(frame)
    message = str(caught.value)
    assert message.startswith("inputs column 'main_steam_flow' row 2 (1-based; time "
                              "2000-01-01 00:00:01+00:00): -138.889 kg/s is not a number "
                              "within [1, 2000] kg/s (1 bad row)")
    assert "np.float64" not in message
    assert (caught.value.row, caught.value.column, caught.value.limits) == (
        1, "main_steam_flow", (1.0, 2000.0))


def _naive_inputs(path: Path, stamps: list[str]) -> Path:
    path.write_text(HEADER + "".join(f"{stamp},16.7,538,{1800 - 100 * k},3.9\n"
                                     for k, stamp in enumerate(stamps)))
    return path


def test_naive_timestamps_are_refused_without_a_time_zone(tmp_path, monkeypatch):
    monkeypatch.setattr(simulate_file, "FullOrderModel", _work_started)
    inputs = _naive_inputs(tmp_path / "local.csv", ["2026-03-01T10:00:00+08:00",
                                                   "2026-03-01 10:00:01", "2026-03-01 10:00:02"])
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out",
                                 str(tmp_path / "o.csv")])
    assert result.exit_code == 2
    assert result.output.startswith(
        f"error: {inputs}: column 'time' data row 2 (line 3): '2026-03-01 10:00:01' has no UTC "
        "offset (2 such rows)")
    assert "--time-zone" in result.output


def test_naive_timestamps_are_read_in_the_given_time_zone(tmp_path):
    """Into a folder that does not exist yet: it is created."""
    inputs = _naive_inputs(tmp_path / "local.csv", ["2026-03-01 10:00:00", "2026-03-01 10:00:01",
                                                   "2026-03-01T02:00:02Z"])
    out = tmp_path / "new" / "folder" / "outputs.csv"
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out", str(out),
                                 "--time-zone", "Asia/Shanghai"])
    assert result.exit_code == 0, result.output
    times = pd.read_csv(out)["time"].tolist()
    assert times == ["2026-03-01T02:00:00+00:00", "2026-03-01T02:00:01+00:00",
                     "2026-03-01T02:00:02+00:00"]


@pytest.mark.parametrize(("zone", "stamp", "expected"), [
    ("+08:00", "2026-03-01 10:00:00", None),
    ("UTC", "2026-03-01 10:00:00", None),
    ("Mars/Olympus", "2026-03-01 10:00:00", "--time-zone 'Mars/Olympus': not a time zone"),
    ("+15:00", "2026-03-01 10:00:00", "offsets lie within ±14:00"),
    ("Europe/Berlin", "2026-10-25 02:30:00", "'2026-10-25 02:30:00' is ambiguous or does not "
                                             "exist in Europe/Berlin"),
    ("Europe/Berlin", "2026-03-29 02:30:00", "does not exist in Europe/Berlin"),
])
def test_time_zone_option(tmp_path, monkeypatch, zone, stamp, expected):
    seen = {}

    def model(spec):
        seen["reached"] = True
        raise _WorkStarted("stop")

    monkeypatch.setattr(simulate_file, "FullOrderModel", model)
    inputs = _naive_inputs(tmp_path / "in.csv", [stamp])
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out",
                                 str(tmp_path / "o.csv"), "--time-zone", zone])
    if expected is None:
        assert seen == {"reached": True}
    else:
        assert result.exit_code == 2 and expected in result.output and not seen
    _no_traceback(result)


# --- bad files as input ----------------------------------------------------------------------

def test_a_binary_spec_is_a_clean_error_everywhere(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_bytes(BINARY)
    for args in (["turbine", "show", str(spec)],
                 ["simulate", "--turbine", str(spec), "--inputs", "x.csv", "--out",
                  str(tmp_path / "o.csv")],
                 ["geometry", "assemble", "--turbine", str(spec), "--out",
                  str(tmp_path / "a.stl")]):
        result = runner.invoke(app, args)
        assert result.exit_code == 2, result.output
        flat = "".join(result.output.replace("│", "").split())  # rich boxes wrap long lines
        assert "".join(str(spec).split()) in flat
        _no_traceback(result)


@pytest.mark.parametrize("kind", ["gbk", "folder", "missing", "binary"])
def test_dcs_check_names_any_bad_data_file(tmp_path, kind):
    tags = tmp_path / "tags.toml"
    write_tag_map(plant_tag_map(), tags)
    data = tmp_path / "history.csv"
    if kind == "gbk":
        _historian_csv(data)
        text = data.read_text(encoding="utf-8").splitlines()
        text = [text[0] + ",备注"] + [line + ",正常" for line in text[1:]]
        data.write_bytes(("\n".join(text) + "\n").encode("gbk"))
    elif kind == "folder":
        data.mkdir()
    elif kind == "binary":
        data.write_bytes(BINARY)
    result = runner.invoke(app, ["dcs", "check", str(data), "--tags", str(tags)])
    _no_traceback(result)
    if kind == "gbk":  # read (encoding sniffed) or refused with the file's name
        assert result.exit_code in (0, 1) or str(data) in result.output
    else:
        assert result.exit_code == 2 and f"error: {data}" in result.output


def test_simulate_names_an_inputs_file_that_is_not_utf8(tmp_path, monkeypatch):
    monkeypatch.setattr(simulate_file, "FullOrderModel", _work_started)
    inputs = tmp_path / "gbk.csv"
    inputs.write_bytes((HEADER.replace("time", "时间") + "0,16.7,538,1800,3.9\n").encode("gbk"))
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out",
                                 str(tmp_path / "o.csv")])
    assert result.exit_code == 2
    assert result.output.startswith(f"error: {inputs}: not UTF-8 text (byte 0xbc at offset 2)")


def test_geometry_refuses_a_short_point_cloud(tmp_path):
    cloud = tmp_path / "short.ply"
    write_point_cloud(np.random.default_rng(0).normal(size=(200, 3)), cloud)
    cloud.write_bytes(cloud.read_bytes()[:-500])
    result = runner.invoke(app, ["geometry", "reconstruct", str(cloud), "--out",
                                 str(tmp_path / "b.stl")])
    assert result.exit_code == 2 and f"error: {cloud}" in result.output
    _no_traceback(result)


# --- no argv makes a traceback ---------------------------------------------------------------

COMMANDS = [["simulate"], ["dcs", "check"], ["turbine", "show"], ["plant"], ["demo"],
            ["geometry", "scan"], ["geometry", "preprocess"], ["geometry", "reconstruct"],
            ["geometry", "mesh"], ["geometry", "assemble"], ["geometry", "uncertainty"]]
OPTIONS = ["--inputs", "--out", "--turbine", "--params", "--time-zone", "--json", "--tags",
           "--require", "--scenario", "--hours", "--layout", "--file-format", "--seed", "--row",
           "--points", "--views", "--samples", "--bound", "--spacing", "--rows", "--report",
           "--target-points", "--tolerance", "--element-size", "--stl", "--hold-hours",
           "--workers", "--full", "--debug"]
VALUES = ["{tags}", "{missing}", "{binary}", "{folder}", "{gbk}", "{naive}", "{empty}",
          "{folder}/x.csv", "-1", "0", "abc", "nan", "1e999", "", "reference", "Mars/Olympus",
          "hp1", "lp9", "deep-peak-50", "wide", "csv", "ply", "main_steam_flow,zz"]


def _stub_the_work(monkeypatch) -> None:
    """Replace every command's expensive step by :func:`_work_started`."""
    import steamtwin.cli.demo as demo_cli
    import steamtwin.cli.plant_options as plant_cli
    import steamtwin.geometry.workflow as workflow

    for module, name in [(simulate_file, "FullOrderModel"), (demo_cli, "run_demo"),
                         (plant_cli, "run_plant"), (workflow, "scan_blade"),
                         (workflow, "preprocess_views"), (workflow, "reconstruct_blade"),
                         (workflow, "blade_volume_mesh"), (workflow, "mesh_stl"),
                         (workflow, "build_assembly"), (workflow, "scan_uncertainty")]:
        monkeypatch.setattr(module, name, _work_started)


@pytest.fixture(scope="module")
def fuzz_files(tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    (root / "folder").mkdir()
    (root / "binary.bin").write_bytes(BINARY)
    (root / "gbk.csv").write_bytes(("time,备注\n0,正常\n").encode("gbk"))
    (root / "empty.csv").write_text("")
    _naive_inputs(root / "naive.csv", ["2026-03-01 10:00:00"])
    write_tag_map(plant_tag_map(), root / "tags.toml")
    return root


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(command=st.sampled_from(COMMANDS),
       fragments=st.lists(st.one_of(st.sampled_from(OPTIONS), st.sampled_from(VALUES)),
                          max_size=8))
def test_no_argv_makes_a_traceback(fuzz_files, command, fragments):
    names = {name: str(fuzz_files / file) for name, file in [
        ("missing", "missing.csv"), ("binary", "binary.bin"), ("folder", "folder"),
        ("gbk", "gbk.csv"), ("naive", "naive.csv"), ("empty", "empty.csv"),
        ("tags", "tags.toml")]}
    argv = [*command, *(fragment.format(**names) for fragment in fragments)]
    with pytest.MonkeyPatch.context() as monkeypatch:
        _stub_the_work(monkeypatch)
        monkeypatch.chdir(fuzz_files / "folder")
        result = runner.invoke(app, argv)
    assert result.exit_code in (0, 1, 2), (argv, result.output)
    _no_traceback(result)


def _historian_csv(path: Path) -> None:
    """A minute of the four model inputs under the virtual plant's KKS tags, wire units."""
    times = pd.date_range("2026-03-01 10:00:00", periods=60, freq="1s")
    rng = np.random.default_rng(3)
    pd.DataFrame({
        "Timestamp": times.strftime("%Y-%m-%d %H:%M:%S"),
        KKS_TAGS["main_steam_pressure"]: 11.0 + rng.normal(0, 0.01, times.size),
        KKS_TAGS["main_steam_temperature"]: 538.0 + rng.normal(0, 0.5, times.size),
        KKS_TAGS["main_steam_flow"]: 1000.0 + rng.normal(0, 5.0, times.size),
        KKS_TAGS["hp_exhaust_pressure"]: 2.2 + rng.normal(0, 0.005, times.size),
    }).to_csv(path, index=False)
