// Unit page: tiles (load, main steam), measured vs twin per monitored temperature with the
// instrument-error band (twin ± 2σ, σ from the tag map), residuals, parameters, active
// alarms; the last 10 minutes, then extended live from /api/events.
"use strict";

(() => {
  const { unit, api, query, follow, status, display, table, chart, points, seconds,
          utc } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const WINDOW = 600;  // samples kept in the live charts (10 min at 1 Hz)
  const TILES = [["load", "load"], ["main_steam_pressure", "main-steam pressure"],
                 ["main_steam_temperature", "main-steam temperature"]];
  const charts = [];    // {div, keys: ["source/signal" or band…], sigma} per series
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
    const celsius = (values) => values.map((v) => (v === null ? null : v - 273.15));
    const [tx, ty] = points(twin);
    const band = (sign) => (twin.downsampled || sigma === null ? tx.map(() => null)
      : celsius(ty).map((v) => (v === null ? null : v + sign * 2 * sigma)));
    const [mx, my] = points(measured);
    chart(div, {
      title: info.meaning || info.signal, yLabel: "°C",
      series: [
        { label: "twin − 2σ", stroke: "rgba(31,119,180,0.3)", width: 0 },
        { label: sigma === null ? "no instrument σ in the tag map" : `twin + 2σ (σ ${sigma} K)`,
          stroke: "rgba(31,119,180,0.3)", width: 0 },
        { label: "twin", stroke: "#1f77b4" },
        { label: "measured", stroke: "#d62728", width: 1 }],
      bands: [{ series: [2, 1], fill: "rgba(31,119,180,0.2)" }],
      data: uPlot.join([[tx, band(-1), band(+1), celsius(ty)], [mx, celsius(my)]]) });
    charts.push({ div, signal: info.signal, sigma,
                  keys: ["band-", "band+", `twin/${info.signal}`, `measured/${info.signal}`] });
  }

  async function residualChart(names) {
    const div = document.getElementById("residuals");
    const answers = await Promise.all(names.map((name) => series("residual", name)));
    chart(div, { title: "measured − twin (SI)", series: names.map((label) => ({ label })),
                 data: answers.length ? uPlot.join(answers.map(points)) : [[]] });
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
    for (const [key, label] of TILES) {
      const value = sample.values[`measured/${key}`];
      if (value !== undefined) tiles[key].textContent = display(value, siUnits[key]);
    }
    tiles.time.textContent = utc(sample.time).replace("T", " ").slice(0, 19);
    const t = seconds(sample.time);
    for (const { div, keys, signal, sigma } of charts) {
      const twin = sample.values[`twin/${signal}`];
      const ys = keys.map((key) => {
        if (key === "band-" || key === "band+") {
          if (sigma === null || twin === undefined || twin === null) return null;
          return twin - 273.15 + (key === "band+" ? 2 : -2) * sigma;
        }
        const value = sample.values[key];
        if (value === undefined || value === null) return null;
        return signal ? value - 273.15 : value;
      });
      // append the sample (or replace the one at the same time) and keep the last WINDOW
      const data = div._uplot.data;
      const last = data[0].length - 1;
      if (last >= 0 && t < data[0][last]) continue;  // already drawn (a backfilled sample)
      const at = last >= 0 && data[0][last] === t ? last : data[0].length;
      const kept = at + 1 > WINDOW ? at + 1 - WINDOW : 0;
      const next = data.map((column, k) => {
        const copy = column.slice(kept, at);
        copy.push(k === 0 ? t : ys[k - 1]);
        return copy;
      });
      div._uplot.setData(next);
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
      const values = points(await series("measured", key))[1];
      tiles[key].textContent = display(values[values.length - 1], siUnits[key]);
    };
    let shown = null;  // the last stored sample when the page loaded
    const lastTime = async () => {
      const units = await api("/api/units");
      shown = units.find((u) => u.name === unit)?.last_sample || null;
      if (shown) tiles.time.textContent = utc(shown).replace("T", " ").slice(0, 19);
    };
    const temperatures = signals.filter((s) => s.source === "measured" && s.si_unit === "K"
                                         && stored.has(`twin/${s.signal}`));
    const residuals = signals.filter((s) => s.source === "residual").map((s) => s.signal);
    // every request at once (the charts' boxes are placed in order before any answer)
    await Promise.all([...TILES.map(([key]) => lastValue(key)), lastTime(),
                       ...temperatures.map(temperatureChart), residualChart(residuals),
                       showParameters(), showAlarms()]);
    document.body.dataset.ready = "yes";
    // the samples stored since `shown` (the provisional ones too) come first
    follow({ sample: onSample, alarms: showAlarms, alarm: showAlarms }, shown);
  }

  start().catch((error) => status(error.message, true));
})();
