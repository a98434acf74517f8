"""What the dashboard screenshots add to the demo's live stage (issue 22, item 4).

Runs the demo's "blade ROM" and "live twin" stages only (:func:`steamtwin.pipeline.run_demo`
with small ROM settings): the live stage publishes the virtual plant over OPC UA, the live
service stores it and serves the dashboard, and headless Chromium shoots each unit page
(:mod:`steamtwin.web.screenshots`). Prints the live stage's wall time, the screenshots' share
(the report's ``live_twin`` table), each page's outcome, the process's CPU time, the reaped
children's CPU time (Chromium's renderer and GPU processes are not among them) and the
machine's load. Compare with a tree without the screenshots by running this script's
``run_demo`` call there (``--no-table-row``), alternately in the same minutes.

Run: python benchmarks/bench_demo_screenshots.py [--out DIR] [--no-table-row]
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time

from steamtwin.pipeline import DemoSettings, run_demo


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None, help="output folder (default: a temporary one)")
    parser.add_argument("--no-table-row", action="store_true",
                        help="a tree whose live_twin table has no screenshots row")
    args = parser.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="bench-demo-screenshots-")
    settings = DemoSettings.quick(stages=("blade ROM", "live twin"), snapshots=8, held_out=4,
                                  workers=1)
    load = os.getloadavg()
    wall, cpu = time.perf_counter(), time.process_time()
    result = run_demo(out, settings)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    rows = dict(zip(result.tables["live_twin"]["quantity"], result.tables["live_twin"]["value"],
                    strict=True))
    print(f"load average before: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}; "
          f"after: {' '.join(f'{v:.1f}' for v in os.getloadavg())}")
    print(f"run: {wall:.1f} s wall, {cpu:.1f} s CPU (this process), "
          f"{children.ru_utime + children.ru_stime:.1f} s CPU (reaped children)")
    print(f"live stage: {result.timings['live twin']:.1f} s wall")
    if not args.no_table_row:
        print(f"of which screenshots: {rows['of which dashboard screenshots (s)']:.1f} s")
        notes = [s for s in result.report.sections
                 if getattr(s, "heading", "") == "Dashboard screenshots"]
        for paragraph in notes[0].paragraphs if notes else ():
            print(paragraph)
    print(f"report: {result.out / 'report.html'}")


if __name__ == "__main__":
    main()
