"""Benchmark: read a 24 h × 1 s × 50-tag historian export (≈ 4.3 M values) with a tag map.

Run: python benchmarks/bench_dcs_read.py — writes a wide and a long Parquet file to a temporary
folder (9 tags map to canonical signals in plant units, 41 are extras) and prints the median wall
time of :func:`steamtwin.dcs.readers.read_historian` and the values read per second, then the
time of reading plus :func:`steamtwin.dcs.quality.check_quality` over all 50 tags (the issue's
target: ≤ 5 s).
"""

from __future__ import annotations

import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.quality import QualityOptions, check_quality
from steamtwin.dcs.readers import read_historian
from steamtwin.dcs.tagmap import parse_tag_map

SECONDS = 24 * 3600
TAGS = 50
REPEATS = 3
MAPPED = {  # signal: (tag, unit, typical value in that unit)
    "main_steam_pressure": ("10LBA10CP001", "MPa", 16.7),
    "main_steam_temperature": ("10LBA10CT001", "degC", 538.0),
    "main_steam_flow": ("10LBA10CF001", "t/h", 1800.0),
    "control_stage_pressure": ("10MAA10CP001", "bar", 120.0),
    "control_stage_temperature": ("10MAA10CT001", "degC", 480.0),
    "hp_exhaust_pressure": ("10LBC10CP001", "kPa", 3800.0),
    "hp_exhaust_temperature": ("10LBC10CT001", "degC", 320.0),
    "hp_inner_casing_temperature": ("10MAA10CT011", "degC", 470.0),
    "load": ("10MKA01CE001", "MW", 600.0),
}


def _tag_map(layout: str):
    lines = ["[historian]", f'layout = "{layout}"', 'time_column = "Timestamp"',
             'time_zone = "Asia/Shanghai"']
    if layout == "long":
        lines += ['tag_column = "tag"', 'value_column = "value"']
    for signal, (tag, unit, _) in MAPPED.items():
        lines += [f"[signals.{signal}]", f'column = "{tag}"', f'unit = "{unit}"']
    return parse_tag_map("\n".join(lines), f"benchmark {layout} map")


def _wide_frame() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    times = pd.date_range("2026-03-01", periods=SECONDS, freq="1s", tz="Asia/Shanghai")
    columns: dict[str, object] = {"Timestamp": times}
    for tag, _, typical in MAPPED.values():
        columns[tag] = typical * (1.0 + 0.01 * rng.standard_normal(SECONDS))
    for number in range(TAGS - len(MAPPED)):
        columns[f"20XYZ{number:02d}CT001"] = 100.0 + rng.standard_normal(SECONDS)
    return pd.DataFrame(columns)


def _time(path: Path, tag_map) -> float:
    runs = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        data = read_historian(path, tag_map)
        runs.append(time.perf_counter() - start)
    assert data.signals.shape == (SECONDS, len(MAPPED))
    assert data.extras.shape[1] == TAGS - len(MAPPED)
    return statistics.median(runs)


def _time_read_and_check(path: Path, tag_map) -> tuple[float, int]:
    runs, findings = [], 0
    for _ in range(REPEATS):
        start = time.perf_counter()
        data = read_historian(path, tag_map)
        options = QualityOptions(
            tag_names={s: spec.column for s, spec in tag_map.signals.items()}, source=str(path))
        report = check_quality(pd.concat([data.signals, data.extras], axis=1), options)
        runs.append(time.perf_counter() - start)
        findings = len(report.findings)
    return statistics.median(runs), findings


def main() -> None:
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, pandas {pd.__version__}")
    values = SECONDS * TAGS
    with tempfile.TemporaryDirectory() as folder:
        wide = _wide_frame()
        wide_path = Path(folder) / "historian_wide.parquet"
        wide.to_parquet(wide_path, index=False)
        long = wide.melt(id_vars="Timestamp", var_name="tag", value_name="value")
        long_path = Path(folder) / "historian_long.parquet"
        long.to_parquet(long_path, index=False)
        del wide, long
        for layout, path in (("wide", wide_path), ("long", long_path)):
            seconds = _time(path, _tag_map(layout))
            size = path.stat().st_size / 1e6
            print(f"{layout:4s} Parquet ({size:.0f} MB, {values / 1e6:.2f} M values): "
                  f"{seconds:.2f} s median of {REPEATS}, {values / seconds / 1e6:.1f} M values/s")
            both, findings = _time_read_and_check(path, _tag_map(layout))
            print(f"{layout:4s} Parquet read + check_quality of all {TAGS} tags: {both:.2f} s "
                  f"median of {REPEATS} ({findings} findings)")


if __name__ == "__main__":
    main()
