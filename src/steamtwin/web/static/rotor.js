// Rotor page: the rotor model's equivalent stress (tensile positive; docs/rotor.md) at the
// groove root and the bore against the allowable (± the configured value), their metal temperatures, and the
// fatigue and creep damage consumed over the chosen range (GET /api/units/{unit}/rotor:
// rotor_life on the stored series), refreshed every 30 s; on request, the ramp advisor's
// fastest ramp to a chosen load.
"use strict";

(() => {
  const { unit, api, query, status, display, table, chart, points, utc } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const REFRESH_MS = 30000;
  const LOCATIONS = [["groove", "groove root"], ["bore", "bore"]];
  const mpa = (values) => values.map((v) => (v === null || v === undefined ? v : v / 1e6));
  const celsius = (values) => values.map((v) => (v === null || v === undefined ? v
    : v - 273.15));
  const damage = (value) => (value === null || value === undefined ? "—"
    : value.toExponential(3));

  function tiles(answer) {
    const box = document.getElementById("tiles");
    box.replaceChildren();
    const values = answer.latest.values;
    const entries = [
      ["groove-root stress", display(values.rotor_groove_stress, "Pa", 1)],
      ["bore stress", display(values.rotor_bore_stress, "Pa", 1)],
      ["groove-root temperature", display(values.rotor_groove_temperature, "K", 1)],
      ["bore temperature", display(values.rotor_bore_temperature, "K", 1)],
      ["allowable", answer.allowable_pa === null ? "not configured"
        : display(answer.allowable_pa, "Pa", 0)],
      ["last sample (UTC)", utc(answer.latest.time) || "—"]];
    for (const [label, text] of entries) {
      const tile = document.createElement("div");
      tile.className = "tile";
      const name = document.createElement("span");
      name.textContent = label;
      const value = document.createElement("strong");
      value.textContent = text;
      tile.append(name, value);
      box.appendChild(tile);
    }
  }

  const series = (signal, span) =>
    api(`${base}/series?${query({ source: "twin", signal, span_s: span })}`);

  async function charts(answer, span) {
    const [groove, bore, grooveT, boreT] = await Promise.all([
      series("rotor_groove_stress", span), series("rotor_bore_stress", span),
      series("rotor_groove_temperature", span), series("rotor_bore_temperature", span)]);
    const stress = uPlot.join([points(groove), points(bore)]);
    const lines = [{ label: "groove root" }, { label: "bore" }];
    const data = [stress[0], mpa(stress[1]), mpa(stress[2])];
    if (answer.allowable_pa !== null) {  // ± allowable: tensile and compressive limit
      const limit = answer.allowable_pa / 1e6;
      lines.push({ label: `allowable ±${limit.toFixed(0)} MPa`, stroke: "#000", dash: [6, 4] },
                 { label: "−allowable", stroke: "#000", dash: [6, 4] });
      data.push(data[0].map(() => limit), data[0].map(() => -limit));
    }
    chart(document.getElementById("stress"), {
      title: "equivalent stress (tensile positive)", yLabel: "MPa", series: lines, data });
    const temperature = uPlot.join([points(grooveT), points(boreT)]);
    chart(document.getElementById("temperature"), {
      title: "rotor metal temperature", yLabel: "°C",
      series: [{ label: "groove root" }, { label: "bore" }],
      data: [temperature[0], celsius(temperature[1]), celsius(temperature[2])] });
  }

  function life(answer) {
    const found = answer.life.locations;
    table(document.getElementById("life"),
          ["location", "hours", "cycles", "largest range", "ramps", "fatigue damage",
           "creep damage", "total"],
          LOCATIONS.map(([key, label]) => {
            const l = found[key];
            return l ? [label, l.hours.toFixed(2), l.cycles.toFixed(1),
                        display(l.largest_range_pa, "Pa", 1), String(l.ramps),
                        damage(l.fatigue_damage), damage(l.creep_damage),
                        damage(l.total_damage)]
              : [label, "—", "—", "—", "—", "—", "—", answer.life.note || ""];
          }));
    const days = found.groove ? found.groove.per_day : [];
    table(document.getElementById("days"),
          ["day (UTC)", "groove fatigue", "groove creep", "bore fatigue", "bore creep"],
          days.length ? days.map((day, k) => [day.day.slice(0, 10),
            damage(day.fatigue_damage), damage(day.creep_damage),
            damage(found.bore.per_day[k].fatigue_damage),
            damage(found.bore.per_day[k].creep_damage)])
            : [["no rotor samples in the range", "", "", "", ""]]);
  }

  async function show() {
    const span = document.getElementById("span").value;
    const answer = await api(`${base}/rotor?${query({ span_s: span })}`);
    tiles(answer);
    life(answer);
    await charts(answer, span);
    status(`updated ${new Date().toISOString().slice(11, 19)} UTC`);
    document.body.dataset.ready = "yes";
  }

  // The advisor's fastest ramp from the last saved rotor state to the chosen load
  // (GET …/rotor/advice); its refusal (no model file, no allowable, a load off the line) is
  // shown beside the form.
  async function advise() {
    const note = document.getElementById("advice-note");
    const to = Number(document.getElementById("advice-to").value) / 100;
    const hold = Number(document.getElementById("advice-hold").value) * 60;
    note.textContent = "computing …";
    try {
      const a = await api(`${base}/rotor/advice?${query({ to, hold_s: hold })}`);
      note.textContent = `from ${(100 * a.from_load).toFixed(1)} % (rotor state of ${
        utc(a.state_time)} UTC) to ${(100 * a.to_load).toFixed(1)} %: at most ${
        a.rate_percent_per_min.toFixed(2)} %/min (${a.limited_by === "allowable"
        ? "limited by the allowable" : "the rate cap"}), ${(a.ramp_s / 60).toFixed(1)} min`;
      table(document.getElementById("advice"),
            ["location", "peak stress", "allowable", "fatigue damage", "creep damage"],
            LOCATIONS.map(([key, label]) => [label, display(a.peak_pa[key], "Pa", 1),
              a.allowable_pa[key].map((v) => display(v, "Pa", 0)).join(" … "),
              damage(a.fatigue_damage[key]), damage(a.creep_damage[key])]));
    } catch (error) {
      note.textContent = error.message;
      document.getElementById("advice").replaceChildren();
    }
  }

  document.getElementById("advise").addEventListener("submit", (event) => {
    event.preventDefault();
    advise();
  });
  const run = () => show().catch((error) => status(error.message, true));
  document.getElementById("query").addEventListener("submit", (event) => {
    event.preventDefault();
    run();
  });
  run();
  setInterval(run, REFRESH_MS);
})();
