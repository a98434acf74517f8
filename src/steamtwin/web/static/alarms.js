// Alarms page: every alarm of the unit (newest first), one alarm's evidence and the signals
// around it (10 minutes either side), and acknowledgement — with the token's holder as the
// operator, or the name typed in "operator" when the service has no tokens (loopback only).
"use strict";

(() => {
  const { unit, api, query, status, table, layout, plotConfig, points } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const operator = document.getElementById("operator");
  operator.value = sessionStorage.getItem("steamtwin-operator") || "";
  operator.addEventListener("change",
                            () => sessionStorage.setItem("steamtwin-operator", operator.value));
  const MARGIN_MS = 600e3;

  function button(row, text, action) {
    const element = document.createElement("button");
    element.type = "button";
    element.textContent = text;
    element.addEventListener("click", () => action().catch((e) => status(e.message, true)));
    row.insertCell().appendChild(element);
    return element;
  }

  async function acknowledge(alarm) {
    const body = operator.value.trim() ? { by: operator.value.trim() } : {};
    await api(`/api/alarms/${alarm.id}/acknowledge`, body);
    status(`alarm #${alarm.id} acknowledged`);
    await showList();
  }

  async function evidence(alarm) {
    const detail = await api(`/api/alarms/${alarm.id}`);
    document.getElementById("evidence-title").textContent =
      `Evidence of alarm #${alarm.id} (${alarm.kind})`;
    table(document.getElementById("evidence"), ["item", "value"],
          Object.entries(detail.evidence).map(([k, v]) => [k, JSON.stringify(v)]));
    const from = new Date(Date.parse(alarm.start) - MARGIN_MS).toISOString();
    const to = new Date(Date.parse(alarm.end || alarm.start) + MARGIN_MS).toISOString();
    const signals = await api(`${base}/signals`);
    const wanted = signals.filter((s) => (alarm.signal ? s.signal === alarm.signal
                                                       : s.source === "residual"));
    const answers = await Promise.all(wanted.map((s) => api(`${base}/series?${
      query({ source: s.source, signal: s.signal, start: from, end: to, max_points: 1200 })}`)));
    const traces = answers.map((a, k) => ({ ...points(a), mode: "lines",
                                            name: `${wanted[k].source} ${wanted[k].signal}` }));
    const marks = [alarm.start, alarm.end].filter(Boolean).map((t) => ({
      type: "line", xref: "x", yref: "paper", x0: t.replace(/(Z|\+00:00)$/, ""),
      x1: t.replace(/(Z|\+00:00)$/, ""), y0: 0, y1: 1, line: { dash: "dot", color: "#b00" } }));
    const div = document.getElementById("evidence-chart");
    await Plotly.react(div, traces, layout(`${alarm.signal || "residuals"} around the alarm`,
                                           { shapes: marks }), plotConfig);
    div.dataset.alarm = alarm.id;
  }

  async function showList() {
    const alarms = await api(`/api/alarms?${query({ unit })}`);
    const rows = table(document.getElementById("alarms"),
                       ["#", "kind", "signal", "start", "end", "acknowledged", "", ""],
                       alarms.map((a) => [a.id, a.kind, a.signal || "—", a.start,
                                          a.end || "active",
                                          a.acknowledged_by
                                            ? `${a.acknowledged_by} ${a.acknowledged_at}` : "no"]));
    rows.forEach((row, k) => {
      const alarm = alarms[k];
      row.dataset.alarm = alarm.id;
      row.classList.toggle("active", alarm.active);
      button(row, "evidence", () => evidence(alarm));
      const ack = button(row, "acknowledge", () => acknowledge(alarm));
      ack.disabled = alarm.acknowledged_at !== null;
    });
    return alarms;
  }

  async function start() {
    const alarms = await showList();
    if (alarms.length) await evidence(alarms[0]);
    document.body.dataset.ready = "yes";
  }

  start().catch((error) => status(error.message, true));
})();
