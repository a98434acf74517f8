// steamtwin pages: what every page shares (no framework, no build step).
// The bearer token the operator types is kept in this tab's sessionStorage and sent with
// every API request; live samples come from /api/events (server-sent events), read with
// fetch() so that the token can go in a header (EventSource cannot send one).
"use strict";

const steamtwin = (() => {
  const unit = document.body.dataset.unit || null;
  const tokenField = document.getElementById("token");
  const statusLine = document.getElementById("status");
  tokenField.value = sessionStorage.getItem("steamtwin-token") || "";
  tokenField.addEventListener("change", () => {
    sessionStorage.setItem("steamtwin-token", tokenField.value.trim());
    window.location.reload();
  });

  function headers(extra = {}) {
    const token = sessionStorage.getItem("steamtwin-token");
    return token ? { ...extra, Authorization: `Bearer ${token}` } : extra;
  }

  function status(text, bad = false) {
    statusLine.textContent = text;
    statusLine.classList.toggle("bad", bad);
  }

  // GET (or POST with a JSON body) an API path; the answer's JSON, or an Error carrying the
  // service's message (and HTTP status) for the status line.
  async function api(path, body = undefined) {
    const init = body === undefined ? { headers: headers() }
      : { method: "POST", headers: headers({ "content-type": "application/json" }),
          body: JSON.stringify(body) };
    const response = await fetch(path, init);
    const answer = await response.json().catch(() => ({}));
    if (!response.ok) {
      const error = new Error(answer.error || `${response.status} ${response.statusText}`);
      error.status = response.status;
      throw error;
    }
    return answer;
  }

  function query(parameters) {
    const search = new URLSearchParams();
    for (const [key, value] of Object.entries(parameters)) {
      if (value !== undefined && value !== null && value !== "") search.set(key, value);
    }
    return search.toString();
  }

  // Follow the server-sent events of `unit`: handlers[event](data); reconnects after 2 s,
  // sending the last event's id (Last-Event-ID, as EventSource does) so that the service
  // first sends the samples stored meanwhile. `since`: the last sample time the page already
  // shows (its first request asks for what came after).
  async function follow(handlers, since = null) {
    const sleep = (ms) => new Promise((done) => setTimeout(done, ms));
    let lastId = since;
    for (;;) {
      try {
        const extra = lastId ? { "Last-Event-ID": lastId } : {};
        const response = await fetch(`/api/events?${query({ unit })}`,
                                     { headers: headers(extra) });
        if (!response.ok) throw new Error(`live feed: ${response.status}`);
        status("live");
        const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
        let buffer = "";
        for (;;) {
          const { value, done } = await reader.read();
          if (done) break;
          buffer += value;
          let cut;
          while ((cut = buffer.indexOf("\n\n")) >= 0) {
            const block = buffer.slice(0, cut);
            buffer = buffer.slice(cut + 2);
            let event = "message";
            let data = "";
            for (const line of block.split("\n")) {
              if (line.startsWith("event:")) event = line.slice(6).trim();
              else if (line.startsWith("data:")) data += line.slice(5).trim();
              else if (line.startsWith("id:")) lastId = line.slice(3).trim();
            }
            if (data && handlers[event]) handlers[event](JSON.parse(data));
          }
        }
      } catch (error) {
        status(`${error.message}; reconnecting`, true);
      }
      await sleep(2000);
    }
  }

  // A number in the signal's display unit: K → °C, Pa → MPa, W → MW (as the DCS shows them).
  const DISPLAY = { K: ["°C", (v) => v - 273.15], Pa: ["MPa", (v) => v / 1e6],
                    W: ["MW", (v) => v / 1e6] };
  function display(value, siUnit, digits = 2) {
    if (value === null || value === undefined) return "—";
    const [label, convert] = DISPLAY[siUnit] || [siUnit || "", (v) => v];
    return `${convert(value).toFixed(digits)} ${label}`;
  }

  function cell(row, text, tag = "td") {
    const element = document.createElement(tag);
    element.textContent = text;
    row.appendChild(element);
    return element;
  }

  // Fill a <table> with a header row and rows of text (textContent: never HTML).
  function table(element, head, rows) {
    element.replaceChildren();
    const top = element.insertRow();
    for (const name of head) cell(top, name, "th");
    return rows.map((values) => {
      const row = element.insertRow();
      for (const value of values) cell(row, value);
      return row;
    });
  }

  // Time-series charts: uPlot (MIT, © Leon Sorokin; static/vendor/uplot, ~50 kB — plotly.js
  // is 4.8 MB and only the blade page's 3-D mesh needs it). x is seconds since the epoch,
  // drawn in UTC; a null y is a gap, an undefined one (uPlot.join's alignment of series
  // sampled at other times) is spanned. The instance is kept on the element (`_uplot`):
  // its `data` are what the chart shows.
  const seconds = (time) => Date.parse(time) / 1000;
  const PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"];
  // 24-hour tick labels (uPlot's axis `values` table: tick step s, its format, then the
  // format where the year, month, day, hour, minute, second changes, and mode 1)
  const DAY = "\n{YYYY}-{MM}-{DD}";
  const TICKS = [
    [86400 * 365, "{YYYY}", null, null, null, null, null, null, 1],
    [86400 * 28, "{YYYY}-{MM}", null, null, null, null, null, null, 1],
    [86400, "{MM}-{DD}", "\n{YYYY}", null, null, null, null, null, 1],
    [60, "{HH}:{mm}", DAY, null, DAY, null, null, null, 1],
    [1, "{HH}:{mm}:{ss}", DAY, null, DAY, null, null, null, 1]];

  // Draw (or redraw) a chart in `element`: series [{label, stroke?, width?, ...}] and
  // data [xs, ys…]; `bands` fill between two series; `options` are passed on (hooks, cursor).
  // After each draw, `data-points` holds the number of finite y values drawn (the demo's
  // screenshot check reads it from the page's DOM: steamtwin.web.screenshots).
  function chart(element, { title, yLabel, series, data, bands = [], options = {} }) {
    if (element._uplot) element._uplot.destroy();
    const counted = (plot) => {
      element.dataset.points = plot.data.slice(1).reduce(
        (n, ys) => n + ys.filter((v) => Number.isFinite(v)).length, 0);
    };
    const hooks = { ...(options.hooks || {}) };
    hooks.draw = [...(hooks.draw || []), counted];
    const height = element.classList.contains("tall") ? 400 : 240;
    const width = () => Math.max(element.clientWidth, 200);
    const plot = new uPlot({
      title, width: width(), height, bands,
      tzDate: (ts) => uPlot.tzDate(new Date(ts * 1e3), "Etc/UTC"),
      scales: { x: { time: true } },
      axes: [{ values: TICKS }, { label: yLabel, size: 60 }],
      series: [{ label: "time (UTC)", value: "{YYYY}-{MM}-{DD} {HH}:{mm}:{ss}" }, ...series.map((s, k) => ({
        stroke: PALETTE[k % PALETTE.length], width: 1.5, ...s }))],
      ...options, hooks }, data, element);
    element._uplot = plot;
    if (!element._resizes) {  // follow the page's width (1366 px down to a tablet)
      element._resizes = new ResizeObserver(() => {
        const current = element._uplot;
        if (current && current.width !== width()) {
          current.setSize({ width: width(), height: current.height });
        }
      });
      element._resizes.observe(element);
    }
    return plot;
  }

  // A series answer → [xs, ys]: the raw values, or the buckets' means when downsampled.
  function points(series) {
    return [series.time.map(seconds), series.downsampled ? series.mean : series.value];
  }

  // The API's times are UTC with an offset; the tiles show them without one.
  const utc = (time) => (time ? time.replace(/(Z|\+00:00)$/, "") : time);

  return { unit, api, query, follow, status, display, table, chart, points, seconds, headers,
           utc };
})();
