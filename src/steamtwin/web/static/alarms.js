// Alarms page: every alarm of the unit (newest first), one alarm's evidence and the signals
// around it (10 minutes either side), and acknowledgement — with the token's holder as the
// operator, or the name typed in "operator" when the service has no tokens (loopback only).
"use strict";

(() => {
  const { unit, api, query, status, table, chart, points, seconds } = steamtwin;
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

  // Dotted vertical lines at `times` (s) over the plotting area.
  function markTimes(plot, times) {
    const { ctx, bbox } = plot;
    ctx.save();
    ctx.strokeStyle = "#b00";
    ctx.setLineDash([4, 4]);
    for (const t of times) {
      const x = plot.valToPos(t, "x", true);
      if (x < bbox.left || x > bbox.left + bbox.width) continue;
      ctx.beginPath();
      ctx.moveTo(x, bbox.top);
      ctx.lineTo(x, bbox.top + bbox.height);
      ctx.stroke();
    }
    ctx.restore();
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
    const marks = [alarm.start, alarm.end].filter(Boolean).map(seconds);
    const div = document.getElementById("evidence-chart");
    chart(div, {
      title: `${alarm.signal || "residuals"} around the alarm (dotted: its start and end)`,
      series: wanted.map((s) => ({ label: `${s.source} ${s.signal}` })),
      data: answers.length ? uPlot.join(answers.map(points)) : [[]],
      options: { hooks: { draw: [(plot) => markTimes(plot, marks)] } } });
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
