// History page: one signal over any stored range; zooming re-queries the API for that range
// (so a day's chart, downsampled with the extrema kept, turns into raw samples when zoomed
// in); CSV/Parquet links download the raw samples of the range shown.
"use strict";

(() => {
  const { unit, api, query, status, layout, plotConfig, headers, utcs } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const chart = document.getElementById("chart");
  const select = document.getElementById("signal");
  const startField = document.getElementById("start");
  const endField = document.getElementById("end");
  let siUnits = {};

  function traces(answer) {
    const x = utcs(answer.time);
    if (!answer.downsampled) {
      return [{ x, y: answer.value, mode: "lines", name: answer.signal }];
    }
    return [
      { x, y: answer.min, mode: "lines", line: { width: 0 }, showlegend: false,
        hoverinfo: "skip" },
      { x, y: answer.max, mode: "lines", line: { width: 0 }, fill: "tonexty",
        fillcolor: "rgba(31,119,180,0.25)", name: "min–max per bucket" },
      { x, y: answer.mean, mode: "lines", name: "mean per bucket" }];
  }

  async function show(start, end) {
    const [source, signal] = select.value.split("/");
    const range = { source, signal, start, end, span_s: start ? undefined : 7200 };
    const answer = await api(`${base}/series?${query(range)}`);
    const title = `${source} ${signal} [${siUnits[signal] || "-"}]`;
    await Plotly.react(chart, traces(answer), layout(title), plotConfig);
    document.getElementById("summary").textContent = `${answer.start} … ${answer.end}: ${
      answer.count} samples${answer.downsampled
        ? `, shown as ${answer.time.length} buckets of ${answer.bucket_s} s` : ""}`;
    for (const format of ["csv", "parquet"]) {
      const link = document.getElementById(format);
      link.href = `${base}/series/download?${query({ source, signal, start: answer.start,
                                                      end: answer.end, format })}`;
    }
    chart.dataset.count = answer.count;
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
    chart.on("plotly_relayout", (change) => {
      // a drag gives "xaxis.range[0]" and "[1]", Plotly.relayout may give "xaxis.range"
      const [from, to] = change["xaxis.range"]
        || [change["xaxis.range[0]"], change["xaxis.range[1]"]];
      if (from === undefined && !change["xaxis.autorange"]) return;
      // plotly gives the zoomed range as "YYYY-MM-DD hh:mm:ss.sss" in UTC (the data's zone)
      const iso = (text) => `${text.replace(" ", "T")}Z`;
      startField.value = from === undefined ? "" : iso(from);
      endField.value = to === undefined ? "" : iso(to);
      show(startField.value, endField.value).catch((error) => status(error.message, true));
    });
  }

  start().catch((error) => status(error.message, true));
})();
