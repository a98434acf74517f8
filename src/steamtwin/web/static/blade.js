// Blade page: the control-stage blade's outer surface coloured by the ROM's temperature field
// for the last stored sample or a chosen time (plotly mesh3d), and the probe temperatures;
// "replay" steps through a range (a load ramp) one field per step, as fast as they arrive.
"use strict";

(() => {
  const { unit, api, query, status, table } = steamtwin;
  const base = `/api/units/${encodeURIComponent(unit)}`;
  const div = document.getElementById("blade");
  const timeField = document.getElementById("time");
  let surface = null;

  async function show(time) {
    const field = await api(`${base}/blade?${query({ time })}`);
    const celsius = field.temperature.map((t) => t - 273.15);
    const [x, y, z] = [0, 1, 2].map((k) => surface.points.map((p) => p[k] * 1e3));
    const [i, j, k] = [0, 1, 2].map((c) => surface.triangles.map((t) => t[c]));
    const probeNames = Object.keys(surface.probes);
    const probe = (c) => probeNames.map((n) => surface.points[surface.probes[n]][c] * 1e3);
    const traces = [
      { type: "mesh3d", x, y, z, i, j, k, intensity: celsius, colorscale: "Jet",
        colorbar: { title: { text: "°C" } }, name: "blade surface",
        hovertemplate: "%{intensity:.1f} °C<extra></extra>" },
      { type: "scatter3d", mode: "markers+text", x: probe(0), y: probe(1), z: probe(2),
        text: probeNames.map((n) => n.replace("blade_", "")), name: "probes",
        marker: { size: 4, color: "#000" } }];
    await Plotly.react(div, traces, {
      margin: { l: 0, r: 0, t: 30, b: 0 }, title: { text: `blade temperature at ${field.time}`,
                                                    font: { size: 14 } },
      scene: { aspectmode: "data", xaxis: { title: { text: "x (mm)" } },
               yaxis: { title: { text: "y (mm)" } }, zaxis: { title: { text: "z (mm)" } } },
    }, { responsive: true, displaylogo: false });
    const inputs = Object.entries(field.inputs).map(([n, v]) => `${n} = ${v.toPrecision(5)}`);
    document.getElementById("summary").textContent = `sample ${field.time}; ROM inputs (SI): ${
      inputs.join(", ")}; surface ${(field.min - 273.15).toFixed(1)} … ${
      (field.max - 273.15).toFixed(1)} °C${field.extrapolation_distance > 0
        ? `; extrapolated (${field.extrapolation_distance.toFixed(3)} snapshot spans outside)`
        : ""}`;
    table(document.getElementById("probes"), ["probe", "ROM (°C)"],
          Object.entries(field.probes).map(([n, t]) => [n.replace("blade_", ""),
                                                        (t - 273.15).toFixed(1)]));
    div.dataset.time = field.time;
    div.dataset.points = celsius.filter((v) => Number.isFinite(v)).length;
    document.body.dataset.ready = "yes";
  }

  async function start() {
    try {
      surface = await api(`${base}/blade/surface`);
    } catch (error) {
      document.getElementById("summary").textContent = error.message;
      document.body.dataset.ready = "no-rom";
      return;
    }
    document.getElementById("query").addEventListener("submit", (event) => {
      event.preventDefault();
      show(timeField.value.trim()).catch((e) => status(e.message, true));
    });
    document.getElementById("latest").addEventListener("click", () => {
      timeField.value = "";
      show("").catch((e) => status(e.message, true));
    });
    let replaying = 0;  // the running replay's number; another number stops it
    document.getElementById("replay").addEventListener("submit", async (event) => {
      event.preventDefault();
      const run = ++replaying;
      const from = Date.parse(document.getElementById("replay-from").value.trim());
      const to = Date.parse(document.getElementById("replay-to").value.trim());
      const step = 1e3 * Number(document.getElementById("replay-step").value);
      if (!(from <= to) || !(step > 0)) {
        status("replay: give from ≤ to (ISO 8601 with offset) and a step > 0 s", true);
        return;
      }
      try {
        for (let t = from; t <= to && run === replaying; t += step) {
          await show(new Date(t).toISOString());
        }
      } catch (error) {
        status(error.message, true);
      }
    });
    document.getElementById("replay-stop").addEventListener("click", () => { replaying += 1; });
    await show("");
  }

  start().catch((error) => status(error.message, true));
})();
