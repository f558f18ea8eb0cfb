// report.html: builds the report from the JSON document embedded in the page. The 3D replay,
// the time slider and every plot share one cursor: moving one moves the others.
(function () {
  "use strict";
  const A = window.ArmHil;
  const data = JSON.parse(document.getElementById("armhil-data").textContent);
  const app = document.getElementById("app");

  const el = A.el;
  const fitCanvas = A.fitCanvas;
  function table(headers, rows, cls) {
    const t = el("table", cls ? { class: cls } : {});
    t.appendChild(el("thead", {}, [el("tr", {}, headers.map((h) => el("th", { text: h })))]));
    const body = el("tbody");
    for (const r of rows) body.appendChild(r);
    t.appendChild(body);
    return t;
  }

  // Trace columns as floats (integers × quantum), by name.
  const ts = data.trace.t;
  const cols = {};
  for (const c of data.trace.columns) {
    cols[c.name] = { group: c.group, values: c.values.map((v) => (v === null ? null : v * c.quantum)) };
  }
  const groups = [];
  for (const c of data.trace.columns) {
    let g = groups.find((x) => x.name === c.group);
    if (!g) groups.push((g = { name: c.group, cols: [] }));
    g.cols.push(c.name);
  }

  const cursorListeners = [];
  let cursorT = 0;
  function setCursor(t, from) {
    cursorT = Math.max(0, Math.min(t, data.duration || t));
    for (const f of cursorListeners) if (f !== from) f(cursorT);
  }
  window.armhilReport = { setCursor: (t) => setCursor(t, null), cursor: () => cursorT, data };

  // Steps.
  const stepRows = data.steps.map((s) => {
    const detail = s.expected !== null && s.expected !== undefined
      ? "expected: " + s.expected + " — actual: " + s.actual
      : s.reply.map((kv) => kv[0] + "=" + kv[1]).join(" ");
    const tr = el("tr", { class: s.outcome, "data-start": s.started }, [
      el("td", { text: String(s.index + 1) }), el("td", { text: String(s.line) }),
      el("td", { text: s.label + (s.id ? " #" + s.id : "") }),
      el("td", { text: s.started.toFixed(3) }), el("td", { text: s.took.toFixed(3) }),
      el("td", { text: s.outcome.replace("_", " ") }), el("td", { text: detail }),
    ]);
    tr.addEventListener("click", () => setCursor(s.started + s.took, null));
    return tr;
  });
  cursorListeners.push((t) => {
    data.steps.forEach((s, i) => {
      const on = t >= s.started && t <= s.started + s.took && s.outcome !== "not_run";
      stepRows[i].classList.toggle("active", on);
    });
  });

  // The replay: the arm at the cursor, a slider over the run.
  const replay = el("div", { class: "panel grow", id: "replay" });
  const jointCols = Object.keys(cols).filter((n) => /^j\d+_deg$/.test(n))
    .sort((a, b) => parseInt(a.slice(1)) - parseInt(b.slice(1)));
  // RobStride motors: angle columns m<ID>_rad, drawn as dials.
  const motorCols = Object.keys(cols).filter((n) => /^m\d+_rad$/.test(n));
  const slider = el("input", { type: "range", min: "0", max: String(data.duration || 0), step: "0.001", value: "0", id: "time-slider" });
  const timeLabel = el("span", { id: "time-label", text: "0.000 s" });
  replay.appendChild(el("h2", { text: "Replay" }));
  let view = null;
  // A robot names the columns that pose it (joints by URDF name, a floating root's pose).
  const posed = data.model && data.pose ? data.pose : null;
  if (data.model && (posed || jointCols.length)) {
    const canvas = el("canvas", { class: "arm", id: "arm-view" });
    replay.appendChild(canvas);
    requestAnimationFrame(() => {
      fitCanvas(canvas);
      view = A.createArmView(canvas, data.model);
      poseAt(cursorT);
    });
  } else if (motorCols.length) {
    const canvas = el("canvas", { class: "arm", id: "arm-view", style: "height: 260px" });
    replay.appendChild(canvas);
    requestAnimationFrame(() => {
      fitCanvas(canvas);
      view = A.createDialsView(canvas, motorCols.map((n) => "motor " + n.slice(1, -4)));
      poseAt(cursorT);
    });
  } else {
    replay.appendChild(el("p", { class: "meta", text: "No arm to draw for this bench (or no joint angles traced)." }));
  }
  replay.appendChild(el("div", { class: "row" }, [slider, timeLabel]));
  function poseAt(t) {
    slider.value = String(t);
    timeLabel.textContent = t.toFixed(3) + " s";
    if (!view || !ts.length) return;
    const i = A.nearestIndex(ts, t);
    if (posed) {
      const p = A.poseFromColumns(data.model, posed, (name) => (cols[name] ? cols[name].values[i] : null));
      view.set(p.deg, undefined, p.base);
      return;
    }
    if (!jointCols.length) {
      view.set(motorCols.map((n) => (cols[n].values[i] === null ? NaN : (cols[n].values[i] * 180) / Math.PI)));
      return;
    }
    const deg = jointCols.map((n) => cols[n].values[i]);
    const g = cols.gripper_mm ? cols.gripper_mm.values[i] : null;
    view.set(deg.map((v) => (v === null ? NaN : v)), g === null ? undefined : g / 1000);
  }
  cursorListeners.push(poseAt);
  slider.addEventListener("input", () => setCursor(parseFloat(slider.value), null));

  // Faults and bus figures beside the replay.
  const side = el("div", { class: "panel", style: "flex: 0 1 360px" });
  side.appendChild(el("h2", { text: "Fault windows" }));
  side.appendChild(data.windows.length
    ? table(["from (s)", "to (s)", "fault"], data.windows.map((w) => {
      const tr = el("tr", {}, [el("td", { text: w.from.toFixed(3) }), el("td", { text: w.to.toFixed(3) }), el("td", { text: w.label })]);
      tr.addEventListener("click", () => setCursor(w.from, null));
      return tr;
    }))
    : el("p", { class: "meta", text: "none" }));
  side.appendChild(el("h2", { text: "Bus" }));
  const b = data.bus;
  side.appendChild(el("div", { class: "kv" }, [
    el("b", { text: "frames" }), el("span", { text: String(b.frames) }),
    el("b", { text: "load" }), el("span", { text: b.load_percent === null ? "–" : b.load_percent.toFixed(1) + " %" }),
    el("b", { text: "CRC errors" }), el("span", { text: String(b.errors) }),
    el("b", { text: "dropped" }), el("span", { text: String(b.dropped) }),
  ]));
  if (b.recording_omitted) {
    side.appendChild(el("p", { class: "meta", text: "Recording: " + b.recording_omitted + "." }));
  }
  if (b.frames_by_id.length) {
    side.appendChild(el("div", { class: "scroll", style: "max-height: 200px" }, [
      table(["ID", "frames"], b.frames_by_id.map((r) => el("tr", {}, [el("td", { text: r[0] }), el("td", { text: String(r[1]) })]))),
    ]));
  }

  app.appendChild(el("div", { class: "row" }, [replay, side]));
  app.appendChild(el("div", { class: "panel" }, [el("h2", { text: "Steps" }),
    table(["#", "line", "step", "start (s)", "took (s)", "outcome", "detail"], stepRows, "steps")]));

  // Plots, one per signal group, sharing the time view and the cursor.
  const plots = [];
  const plotPanel = el("div", { class: "panel", id: "plots" }, [el("h2", { text: "Plots (wheel: zoom, drag: pan, double-click: reset, click: move the cursor)" })]);
  for (const g of groups) {
    const c = el("canvas", { class: "plot", "data-group": g.name });
    plotPanel.appendChild(c);
    plots.push({ c, g });
  }
  if (ts.length) app.appendChild(plotPanel);
  requestAnimationFrame(() => {
    for (const p of plots) {
      fitCanvas(p.c);
      const plot = A.createPlot(p.c, { title: p.g.name, names: p.g.cols });
      plot.setData(ts, p.g.cols.map((n) => cols[n].values));
      plot.setWindows(data.windows);
      plot.onCursor((t) => setCursor(t, null));
      plot.onView((v) => plots.forEach((o) => o.plot && o.plot !== plot && o.plot.setView(v)));
      p.plot = plot;
      cursorListeners.push((t) => plot.setCursor(t));
    }
    const failure = data.steps.find((s) => s.outcome === "failed" || s.outcome === "timed_out");
    setCursor(failure ? failure.started + failure.took : 0, null);
  });

  // The bus recording, decoded.
  const fr = data.frames;
  if (fr.total) {
    const filter = el("input", { type: "search", placeholder: "filter (ID, name or field text)", id: "frame-filter" });
    const rows = fr.rows.map((r) => {
      const tr = el("tr", {}, [el("td", { text: String(r[0]) }), el("td", { text: r[1].toFixed(6) }), el("td", { text: r[2] }),
        el("td", { text: r[3] }), el("td", { text: r[4] }), el("td", { text: r[5] })]);
      tr.addEventListener("click", () => setCursor(r[1], null));
      return tr;
    });
    const note = fr.rows.length < fr.total
      ? fr.rows.length + " of " + fr.total + " frames: the start and the frames around the first failure (bus.log / bus.pcap hold all)"
      : fr.total + " frames";
    filter.addEventListener("input", () => {
      const q = filter.value.toLowerCase();
      fr.rows.forEach((r, i) => {
        const hit = !q || (r[2] + " " + r[4] + " " + r[5]).toLowerCase().includes(q);
        rows[i].style.display = hit ? "" : "none";
      });
    });
    app.appendChild(el("div", { class: "panel", id: "frames" }, [el("h2", { text: "Bus recording" }),
      el("p", { class: "meta", text: note }), filter,
      el("div", { class: "scroll" }, [table(["#", "time (s)", "ID", "data", "message", "fields"], rows, "frames")])]));
  }
})();
