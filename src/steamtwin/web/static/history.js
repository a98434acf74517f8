// History page: one signal over any stored range; zooming re-queries the API for that range
// (so a day's chart, downsampled with the extrema kept, turns into raw samples when zoomed
// in); CSV/Parquet links download the raw samples of the range shown.
"use strict";

(() => {
  const { unit, api, query, status, chart: draw, seconds, headers } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const chart = document.getElementById("chart");
  const select = document.getElementById("signal");
  const startField = document.getElementById("start");
  const endField = document.getElementById("end");
  let siUnits = {};

  // raw samples: one line; buckets: their min–max band and mean (M4 keeps the extrema)
  function traces(answer) {
    const x = answer.time.map(seconds);
    if (!answer.downsampled) {
      return { series: [{ label: answer.signal }], data: [x, answer.value], bands: [] };
    }
    return {
      series: [{ label: "min per bucket", stroke: "rgba(31,119,180,0.4)", width: 0 },
               { label: "max per bucket", stroke: "rgba(31,119,180,0.4)", width: 0 },
               { label: "mean per bucket", stroke: "#1f77b4" }],
      data: [x, answer.min, answer.max, answer.mean],
      bands: [{ series: [2, 1], fill: "rgba(31,119,180,0.25)" }] };
  }

  // A drag over the chart selects a time range: query it (raw samples once few enough).
  function zoomed(plot) {
    if (plot.select.width < 2) return;
    const iso = (left) => new Date(Math.round(plot.posToVal(left, "x")) * 1e3).toISOString();
    startField.value = iso(plot.select.left);
    endField.value = iso(plot.select.left + plot.select.width);
    plot.setSelect({ left: 0, width: 0, top: 0, height: 0 }, false);
    show(startField.value, endField.value).catch((error) => status(error.message, true));
  }

  async function show(start, end) {
    const [source, signal] = select.value.split("/");
    const range = { source, signal, start, end, span_s: start ? undefined : 7200 };
    const answer = await api(`${base}/series?${query(range)}`);
    const title = `${source} ${signal} [${siUnits[signal] || "-"}]`;
    draw(chart, { title, yLabel: siUnits[signal] || "-", ...traces(answer), options: {
      cursor: { drag: { x: true, y: false, setScale: false } },
      hooks: { setSelect: [zoomed] } } });
    document.getElementById("summary").textContent = `${answer.start} … ${answer.end}: ${
      answer.count} samples${answer.downsampled
        ? `, shown as ${answer.time.length} buckets of ${answer.bucket_s} s` : ""}`;
    for (const format of ["csv", "parquet"]) {
      const link = document.getElementById(format);
      link.href = `${base}/series/download?${query({ source, signal, start: answer.start,
                                                      end: answer.end, format })}`;
    }
    Object.assign(chart.dataset, { count: answer.count, start: answer.start, end: answer.end });
    document.body.dataset.ready = "yes";
  }

  // A download with the bearer token when one is set (a plain link cannot send it).
  async function download(event) {
    if (!headers().Authorization) return;
    event.preventDefault();
    const response = await fetch(event.currentTarget.href, { headers: headers() });
    if (!response.ok) { status(`download: ${response.status}`, true); return; }
    const name = /filename="([^"]+)"/.exec(response.headers.get("content-disposition"));
    const link = document.createElement("a");
    link.href = URL.createObjectURL(await response.blob());
    link.download = name ? name[1] : "series";
    link.click();
    URL.revokeObjectURL(link.href);
  }

  async function start() {
    const signals = await api(`${base}/signals`);
    siUnits = Object.fromEntries(signals.map((s) => [s.signal, s.si_unit]));
    for (const s of signals) {
      const option = document.createElement("option");
      option.value = `${s.source}/${s.signal}`;
      option.textContent = `${s.source} ${s.signal}`;
      select.appendChild(option);
    }
    document.getElementById("query").addEventListener("submit", (event) => {
      event.preventDefault();
      show(startField.value.trim(), endField.value.trim())
        .catch((error) => status(error.message, true));
    });
    for (const format of ["csv", "parquet"]) {
      document.getElementById(format).addEventListener("click", download);
    }
    await show("", "");
  }

  start().catch((error) => status(error.message, true));
})();
