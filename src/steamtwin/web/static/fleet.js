// Fleet page: one card per unit (load, last sample, active alarms); a single unit goes
// straight to its own page.
"use strict";

(() => {
  const { api, query, status, display } = steamtwin;

  async function card(unit, alarms) {
    const box = document.createElement("a");
    box.className = "card";
    box.href = `/units/${encodeURIComponent(unit.name)}`;
    const title = document.createElement("h2");
    title.textContent = unit.name;
    const load = document.createElement("p");
    const last = document.createElement("p");
    last.textContent = `last sample ${unit.last_sample || "none"}`;
    const count = alarms.filter((a) => a.unit === unit.name).length;
    const alarm = document.createElement("p");
    alarm.className = count ? "alarm" : "";
    alarm.textContent = `${count} active alarm${count === 1 ? "" : "s"}`;
    box.append(title, load, last, alarm);
    document.getElementById("cards").appendChild(box);
    try {
      const path = `/api/units/${encodeURIComponent(unit.name)}`;
      const signals = await api(`${path}/signals`);
      if (!signals.some((s) => s.source === "measured" && s.signal === "load")) {
        load.textContent = "no load signal stored";
        return;
      }
      const series = await api(`${path}/series?${query({ signal: "load", span_s: 60 })}`);
      load.textContent = `load ${display(series.value[series.value.length - 1], "W", 1)}`;
    } catch (error) {
      load.textContent = error.message;
    }
  }

  async function start() {
    const units = await api("/api/units");
    if (units.length === 1) {
      window.location.replace(`/units/${encodeURIComponent(units[0].name)}`);
      return;
    }
    const alarms = await api("/api/alarms?active=true");
    await Promise.all(units.map((unit) => card(unit, alarms)));
    if (!units.length) document.getElementById("cards").textContent = "no units yet";
    document.body.dataset.ready = "yes";
  }

  start().catch((error) => status(error.message, true));
})();
