"""``steamtwin rotor stress``'s library call on the virtual plant's day (issue 23, item 6).

Runs the plant's ``day`` (``hours`` scales its holds as the demo does: 2.5 h, the demo's default,
gives a 21-h record at 1 s), writes it as a historian export, reads it back through the quality
gate and calls :func:`steamtwin.rotor.report.rotor_stress` ``--repeat`` times (the first may
compile the numba kernels). Prints samples, wall and CPU time of each call and of its steps
(fit, ROM run with the FOM's steam side, life, report), the peak groove stress, the allowable
and the life consumed.

Run: python benchmarks/bench_rotor_stress_report.py [--hours 2.5] [--repeat 2] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from steamtwin.dcs.history import load_history
from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.rotor.report import rotor_stress
from steamtwin.spec import load_spec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=2.5)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench-rotor-stress-"))
    clock = time.perf_counter()
    files = write_plant(run_plant("day", hours=args.hours, random_state=args.seed),
                        out / "plant")
    history = load_history(files["historian"], files["tag_map"])
    print(f"plant day: {len(history.data)} samples, {time.perf_counter() - clock:.1f} s wall")
    for k in range(args.repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        result = rotor_stress([history], load_spec("reference"), out / f"report-{k}")
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        steps = json.loads(result.files["report.html"].with_name("report.json").read_text(
            encoding="utf-8"))["timings_s"]
        summary = result.life.summary()
        print(f"run {k + 1}: {wall:.1f} s wall, {cpu:.1f} s CPU; "
              + ", ".join(f"{name} {seconds:.1f} s" for name, seconds in steps.items()))
        print(f"  peak groove von Mises {result.frame['groove_von_mises'].max() / 1e6:.1f} MPa, "
              f"allowable {result.allowable_pa / 1e6:.1f} MPa; life consumed "
              f"{summary['total_damage']:.3g} (fatigue {summary['fatigue_damage']:.3g}, creep "
              f"{summary['creep_damage']:.3g}), {summary['ramps']} ramps, "
              f"{summary['cycles']:g} cycles")


if __name__ == "__main__":
    main()
