// Unit page: tiles (load, main steam), measured vs twin per monitored temperature with the
// instrument-error band (twin ± 2σ, σ from the tag map), residuals, parameters, active
// alarms; the last 10 minutes, then extended live from /api/events.
"use strict";

(() => {
  const { unit, api, query, follow, status, display, table, layout, plotConfig, points, utc,
          utcs } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const WINDOW = 600;  // samples kept in the live charts (10 min at 1 Hz)
  const TILES = [["load", "load"], ["main_steam_pressure", "main-steam pressure"],
                 ["main_steam_temperature", "main-steam temperature"]];
  const charts = [];    // {div, keys: ["source/signal" or band…], sigma}
  const siUnits = {};
  const tiles = {};

  function tile(key, label) {
    const box = document.createElement("div");
    box.className = "tile";
    const name = document.createElement("span");
    name.textContent = label;
    const value = document.createElement("strong");
    value.textContent = "—";
    box.append(name, value);
    document.getElementById("tiles").appendChild(box);
    tiles[key] = value;
  }

  const series = (source, signal) =>
    api(`${base}/series?${query({ source, signal, span_s: WINDOW - 1, max_points: WINDOW })}`);

  async function temperatureChart(info) {
    const div = document.createElement("div");
    div.className = "chart";
    div.dataset.signal = info.signal;
    document.getElementById("temperatures").appendChild(div);
    const [measured, twin] = await Promise.all([series("measured", info.signal),
                                                series("twin", info.signal)]);
    const sigma = info.instrument_sigma;
    const band = (sign) => twin.downsampled || sigma === null ? [] :
      twin.value.map((v) => (v === null ? null : v - 273.15 + sign * 2 * sigma));
    const celsius = (values) => values.map((v) => (v === null ? null : v - 273.15));
    const m = points(measured);
    const t = points(twin);
    const traces = [
      { x: utcs(twin.time), y: band(-1), mode: "lines", line: { width: 0 }, hoverinfo: "skip",
        showlegend: false, name: "twin − 2σ" },
      { x: utcs(twin.time), y: band(+1), mode: "lines", line: { width: 0 }, fill: "tonexty",
        fillcolor: "rgba(31,119,180,0.2)",
        name: sigma === null ? "no instrument σ in the tag map" : `twin ± 2σ (σ ${sigma} K)` },
      { x: t.x, y: celsius(t.y), mode: "lines", name: "twin", line: { color: "#1f77b4" } },
      { x: m.x, y: celsius(m.y), mode: "lines", name: "measured",
        line: { color: "#d62728", width: 1 } }];
    await Plotly.newPlot(div, traces, layout(info.meaning || info.signal,
                                             { yaxis: { title: { text: "°C" } } }), plotConfig);
    charts.push({ div, signal: info.signal, sigma,
                  keys: ["band-", "band+", `twin/${info.signal}`, `measured/${info.signal}`] });
  }

  async function residualChart(names) {
    const div = document.getElementById("residuals");
    const answers = await Promise.all(names.map((name) => series("residual", name)));
    const traces = answers.map((answer, k) => ({ ...points(answer), mode: "lines",
                                                 name: names[k] }));
    await Plotly.newPlot(div, traces, layout("measured − twin (SI)"), plotConfig);
    charts.push({ div, keys: names.map((name) => `residual/${name}`) });
  }

  async function showParameters() {
    const answer = await api(`${base}/parameters`);
    const rows = Object.entries(answer.current).map(([name, p]) =>
      [name, p.value === null ? "—" : p.value.toPrecision(5), p.time || "", p.reason || ""]);
    table(document.getElementById("parameters"), ["parameter", "value", "since", "reason"],
          rows.length ? rows : [["none stored yet", "", "", ""]]);
  }

  async function showAlarms() {
    const active = await api(`/api/alarms?${query({ unit, active: true })}`);
    const list = document.getElementById("alarms");
    list.replaceChildren();
    for (const alarm of active) {
      const item = document.createElement("li");
      item.textContent = `#${alarm.id} ${alarm.kind}${alarm.signal ? ` (${alarm.signal})` : ""}`
        + ` since ${alarm.start}${alarm.acknowledged_by ? `, ack. ${alarm.acknowledged_by}` : ""}`;
      list.appendChild(item);
    }
    if (!active.length) list.textContent = "none";
  }

  function onSample(sample) {
    const x = utc(sample.time);
    for (const [key, label] of TILES) {
      const value = sample.values[`measured/${key}`];
      if (value !== undefined) tiles[key].textContent = display(value, siUnits[key]);
    }
    tiles.time.textContent = x.replace("T", " ").slice(0, 19);
    for (const chart of charts) {
      const twin = sample.values[`twin/${chart.signal}`];
      const ys = chart.keys.map((key) => {
        if (key === "band-" || key === "band+") {
          if (chart.sigma === null || twin === undefined || twin === null) return null;
          return twin - 273.15 + (key === "band+" ? 2 : -2) * chart.sigma;
        }
        const value = sample.values[key];
        if (value === undefined || value === null) return null;
        return chart.signal ? value - 273.15 : value;
      });
      Plotly.extendTraces(chart.div, { x: ys.map(() => [x]), y: ys.map((y) => [y]) },
                          ys.map((_, k) => k), WINDOW);
    }
  }

  async function start() {
    const signals = await api(`${base}/signals`);
    for (const s of signals) siUnits[s.signal] = s.si_unit;
    for (const [key, label] of TILES) tile(key, label);
    tile("time", "last sample (UTC)");
    const stored = new Set(signals.map((s) => `${s.source}/${s.signal}`));
    const lastValue = async (key) => {
      if (!stored.has(`measured/${key}`)) return;
      const values = points(await series("measured", key)).y;
      tiles[key].textContent = display(values[values.length - 1], siUnits[key]);
    };
    const lastTime = async () => {
      const units = await api("/api/units");
      const last = units.find((u) => u.name === unit)?.last_sample;
      if (last) tiles.time.textContent = utc(last).replace("T", " ").slice(0, 19);
    };
    const temperatures = signals.filter((s) => s.source === "measured" && s.si_unit === "K"
                                         && stored.has(`twin/${s.signal}`));
    const residuals = signals.filter((s) => s.source === "residual").map((s) => s.signal);
    // every request at once (the charts' boxes are placed in order before any answer)
    await Promise.all([...TILES.map(([key]) => lastValue(key)), lastTime(),
                       ...temperatures.map(temperatureChart), residualChart(residuals),
                       showParameters(), showAlarms()]);
    document.body.dataset.ready = "yes";
    follow({ sample: onSample, alarms: showAlarms, alarm: showAlarms });
  }

  start().catch((error) => status(error.message, true));
})();
