// Calibration page: each parameter's trajectory (a step at every swap) and, per swap, the RMS
// of every stored residual in the 10 minutes before and after it — the historian keeps the
// swaps, not the recalibration's own RMSE.
"use strict";

(() => {
  const { unit, api, query, status, table, chart, seconds } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const WINDOW_MS = 600e3;

  const rms = (values) => {
    const finite = values.filter((v) => v !== null);
    return finite.length
      ? Math.sqrt(finite.reduce((sum, v) => sum + v * v, 0) / finite.length) : null;
  };

  async function residualRms(signals, from, to) {
    const answers = await Promise.all(signals.map((signal) => api(`${base}/series?${
      query({ source: "residual", signal, start: from, end: to })}`)));
    // raw samples (10 min at 1 Hz is below max_points); if bucketed, the buckets' means
    return answers.map((a) => rms(a.downsampled ? a.mean : a.value));
  }

  async function start() {
    const answer = await api(`${base}/parameters`);
    const byName = {};
    for (const swap of answer.trajectory) {
      (byName[swap.name] = byName[swap.name] || [[], []]);
      byName[swap.name][0].push(seconds(swap.time));
      byName[swap.name][1].push(swap.value);
    }
    const names = Object.keys(byName);
    chart(document.getElementById("trajectory"), {
      title: "parameter trajectory (multipliers, -)",
      // a step at each swap: the value holds until the next one
      series: names.map((label) => ({ label, paths: uPlot.paths.stepped({ align: 1 }),
                                      points: { show: true, size: 6 } })),
      data: names.length ? uPlot.join(names.map((name) => byName[name])) : [[]] });
    const times = [...new Set(answer.trajectory.map((s) => s.time))];
    const signals = (await api(`${base}/signals`)).filter((s) => s.source === "residual")
      .map((s) => s.signal);
    const rows = [];
    for (const time of times) {
      const swaps = answer.trajectory.filter((s) => s.time === time);
      const at = Date.parse(time);
      const iso = (ms) => new Date(ms).toISOString();
      const [before, after] = await Promise.all([
        residualRms(signals, iso(at - WINDOW_MS), iso(at - 1)),
        residualRms(signals, iso(at), iso(at + WINDOW_MS))]);
      const fmt = (values) => values.map((v, k) => `${signals[k]} ${
        v === null ? "—" : v.toPrecision(3)}`).join("; ");
      // the filter's 95 % interval beside each value it estimated (none for the others)
      const interval = (s) => (s.low === null || s.high === null ? ""
        : ` [${s.low.toPrecision(4)}, ${s.high.toPrecision(4)}]`);
      rows.push([time, swaps.map((s) => `${s.name} = ${s.value}${interval(s)}`).join(", "),
                 swaps[0].reason,
                 fmt(before), fmt(after)]);
    }
    table(document.getElementById("swaps"),
          ["time", "values [95 % interval]", "reason", "residual RMS before (SI)",
           "residual RMS after (SI)"],
          rows.length ? rows : [["no swap stored", "", "", "", ""]]);
    document.body.dataset.ready = "yes";
  }

  start().catch((error) => status(error.message, true));
})();
