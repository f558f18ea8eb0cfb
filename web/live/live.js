// The live page of `armhil sim <device> --ui`: connects to /ws, draws the arm and strips from
// the state messages, and sends fault commands from the fault panel.
(function () {
  "use strict";
  const A = window.ArmHil;
  const app = document.getElementById("app");
  const HISTORY_S = 15;

  const el = A.el;
  const fit = A.fitCanvas;

  // What tests and scripts read: the angles last drawn, frames drawn per second, the last
  // state and acknowledgement.
  const live = { ready: false, state: null, hello: null, acks: [], fps: 0, states: 0,
    renderedDeg: () => [], framesDrawn: () => 0 };
  window.armhilLive = live;

  const header = el("header", {}, [el("h1", { id: "title", text: "armhil live" }),
    el("p", { class: "meta" }, [el("span", { id: "conn", text: "connecting…" }), " · ",
      el("span", { id: "clock", text: "" }), " · ", el("span", { id: "fps", text: "" })])]);
  document.body.insertBefore(header, app);

  const armCanvas = el("canvas", { class: "arm", id: "arm-view" });
  const status = el("div", { class: "kv", id: "status" });
  const faultPanel = el("div", { id: "fault-panel" });
  const busPanel = el("div", { id: "bus" });
  app.appendChild(el("div", { class: "row" }, [
    el("div", { class: "panel grow" }, [armCanvas]),
    el("div", { class: "panel", style: "flex: 0 1 380px" }, [
      el("h2", { text: "Controller" }), status,
      el("h2", { text: "Faults" }), faultPanel,
      el("h2", { text: "Bus" }), busPanel]),
  ]));
  const strips = [
    { key: "joints_deg", title: "position (deg)" },
    { key: "velocity_deg_s", title: "velocity (deg/s)" },
    { key: "torque_nm", title: "torque (N·m)" },
    { key: "temperature_c", title: "temperature (°C)" },
  ];
  const stripPanel = el("div", { class: "panel", id: "strips" });
  app.appendChild(stripPanel);

  let ws = null;
  let view = null;
  const history = { t: [], series: {} };

  function kv(pairs) {
    status.textContent = "";
    for (const [k, v] of pairs) {
      status.appendChild(el("b", { text: k }));
      status.appendChild(el("span", { "data-key": k, text: v }));
    }
  }

  function buildFaultPanel(faults) {
    const select = el("select", { id: "fault-kind" }, faults.map((f) => el("option", { value: f.name, text: f.name })));
    const params = el("div", { id: "fault-params", class: "kv" });
    const desc = el("p", { class: "meta", id: "fault-desc" });
    const ack = el("p", { class: "meta", id: "fault-ack" });
    const active = el("div", { class: "faults-active", id: "faults-active" });
    const inject = el("button", { id: "fault-inject", text: "Inject" });
    const clear = el("button", { id: "fault-clear", text: "Clear" });
    function showParams() {
      const f = faults.find((x) => x.name === select.value);
      params.textContent = "";
      desc.textContent = f ? f.description : "";
      for (const p of (f ? f.params : [])) {
        params.appendChild(el("label", { for: "fault-arg-" + p.name, text: p.name + (p.required ? " *" : "") }));
        // The emulator's fault table says what a value may be: a range, or a list of words.
        const words = p.words || [];
        const range = p.min != null && p.max != null ? p.min + " … " + p.max : "";
        const accepts = words.length ? words.join(" | ") : range;
        params.appendChild(el("input", { id: "fault-arg-" + p.name, "data-param": p.name,
          "data-word": words.length ? "1" : "",
          title: p.description + (accepts ? " (" + accepts + ")" : ""),
          placeholder: p.default == null ? accepts : String(p.default),
          value: p.required && p.default != null ? String(p.default) : p.name === "joint" ? "1" : "" }));
      }
    }
    function send(type) {
      const args = {};
      for (const input of params.querySelectorAll("input")) {
        if (input.value.trim() === "") continue;
        const n = Number(input.value);
        args[input.dataset.param] = isFinite(n) && !input.dataset.word ? n : input.value.trim();
      }
      if (ws && ws.readyState === 1) ws.send(JSON.stringify({ type, fault: select.value, args }));
    }
    select.addEventListener("change", showParams);
    inject.addEventListener("click", () => send("inject"));
    clear.addEventListener("click", () => send("clear"));
    faultPanel.textContent = "";
    faultPanel.append(select, desc, params, el("div", { class: "row" }, [inject, clear]), ack, active);
    showParams();
  }

  function buildStrips(names) {
    stripPanel.textContent = "";
    for (const s of strips) {
      const c = el("canvas", { class: "plot", "data-strip": s.key });
      stripPanel.appendChild(c);
      fit(c);
      s.plot = A.createPlot(c, { title: s.title, names });
      s.plot.follow(10);
      history.series[s.key] = names.map(() => []);
    }
  }

  function onHello(h) {
    live.hello = h;
    document.getElementById("title").textContent = h.title || h.device;
    let names;
    if (h.model) {
      fit(armCanvas);
      view = A.createArmView(armCanvas, h.model);
      names = A.armJoints(h.model).map((_, i) => "J" + (i + 1));
    } else if (h.motors) {
      armCanvas.style.height = "260px";
      fit(armCanvas);
      const dials = A.createDialsView(armCanvas, h.motors.map((id) => "motor " + id));
      view = { set: (deg) => dials.set(deg), renderedDeg: dials.renderedDeg, framesDrawn: dials.framesDrawn };
      names = h.motors.map((id) => "motor " + id);
    } else {
      names = [];
    }
    // A robot's strips are its actuators (the 3D view sets every joint of its URDF).
    if (h.strip_names) names = h.strip_names;
    if (view) {
      live.renderedDeg = () => view.renderedDeg();
      live.framesDrawn = () => view.framesDrawn();
    }
    buildFaultPanel(h.faults || []);
    buildStrips(names);
    live.ready = true;
  }

  // Text panels change slowly to the eye: rebuilt at most this often, so the canvas keeps the
  // frame rate.
  const PANEL_PERIOD_MS = 200;
  const STRIP_PERIOD_MS = 40;
  let panelsAt = 0;
  let stripsAt = 0;

  function onState(s) {
    live.state = s;
    live.states++;
    if (view) view.set(s.physical_deg || s.joints_deg, s.gripper_mm === undefined ? undefined : s.gripper_mm / 1000, s.base_pose);
    pushHistory(s);
    const now = performance.now();
    if (now - panelsAt < PANEL_PERIOD_MS) return;
    panelsAt = now;
    showPanels(s);
  }

  function showPanels(s) {
    document.getElementById("clock").textContent = "t = " + s.t.toFixed(2) + " s";
    const st = s.status || {};
    if (s.panel) {
      kv(s.panel);
      showFaultsAndBus(s);
      return;
    }
    if (s.motors) {
      kv(s.motors.map((m) => ["motor " + m.id + " (" + m.model + ")",
        m.mode + ", run_mode " + m.run_mode + ", " + m.bus_voltage_v.toFixed(1) + " V, faults: " +
        (m.faults.length ? m.faults.join(",") : "none") + (m.listening ? "" : " (deaf to this bus)")]));
      showFaultsAndBus(s);
      return;
    }
    kv([
      ["ctrl_mode", st.ctrl_mode], ["arm_status", st.arm_status], ["motion", st.motion],
      ["enabled", (st.enabled || []).map((e, i) => (e ? "J" + (i + 1) : "")).filter(Boolean).join(" ") || "none"],
      ["driver faults", (st.driver_faults || []).map((f, i) => (f.length ? "J" + (i + 1) + ": " + f.join(",") : "")).filter(Boolean).join("; ") || "none"],
      ["gripper", s.gripper_mm.toFixed(1) + " mm, " + s.gripper_force_n.toFixed(1) + " N" + (st.gripper_enabled ? "" : " (off)")],
      ["contacts", String(s.contacts)],
    ]);
    showFaultsAndBus(s);
  }

  function showFaultsAndBus(s) {
    const active = document.getElementById("faults-active");
    if (active) {
      active.textContent = "";
      for (const f of s.faults) active.appendChild(el("span", { text: f }));
    }
    busPanel.textContent = "";
    if (!s.bus) {
      busPanel.appendChild(el("p", { class: "meta", text: "no CAN bus (JSON over TCP, state over UDP)" }));
      return;
    }
    const bus = s.bus;
    busPanel.appendChild(el("p", { id: "bus-load", text: "load: " + (bus.load_percent === null ? "–" : bus.load_percent.toFixed(1) + " %") }));
    const rows = bus.ids.map((r) => el("tr", {}, [el("td", { text: r[0] }), el("td", { text: String(r[1]) }), el("td", { text: r[2].toFixed(0) })]));
    const t = el("table", {}, [el("thead", {}, [el("tr", {}, ["ID", "frames", "per s"].map((h) => el("th", { text: h })))]), el("tbody", {}, rows)]);
    busPanel.appendChild(el("div", { class: "scroll", style: "max-height: 220px" }, [t]));
  }

  // Strips: keep the last HISTORY_S seconds.
  function pushHistory(s) {
    history.t.push(s.t);
    let drop = 0;
    while (drop < history.t.length && history.t[drop] < s.t - HISTORY_S) drop++;
    if (drop) history.t.splice(0, drop);
    for (const strip of strips) {
      const series = history.series[strip.key];
      if (!series) continue;
      series.forEach((ys, i) => {
        ys.push(s[strip.key] ? s[strip.key][i] : null);
        if (drop) ys.splice(0, drop);
      });
    }
    // The strips scroll smoothly at 25 Hz; drawing them at every message would take frames
    // from the 3D view.
    const now = performance.now();
    if (now - stripsAt < STRIP_PERIOD_MS) return;
    stripsAt = now;
    for (const strip of strips) {
      if (strip.plot) strip.plot.setData(history.t, history.series[strip.key]);
    }
  }

  function connect() {
    // A server reachable from other machines requires the token of the URL it printed on
    // every request, its WebSocket included.
    const token = new URLSearchParams(location.search).get("token");
    const query = token ? "?token=" + encodeURIComponent(token) : "";
    const url = (location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws" + query;
    ws = new WebSocket(url);
    const conn = document.getElementById("conn");
    ws.onopen = () => { conn.textContent = "connected"; };
    ws.onclose = () => { conn.textContent = "disconnected; retrying"; setTimeout(connect, 1000); };
    ws.onmessage = (e) => {
      let m;
      try { m = JSON.parse(e.data); } catch (err) { return; }
      if (m.type === "hello") onHello(m);
      else if (m.type === "state") onState(m);
      else if (m.type === "ack") {
        live.acks.push(m);
        const ack = document.getElementById("fault-ack");
        if (ack) { ack.textContent = m.message; ack.style.color = m.ok ? "#2f855a" : "#c53030"; }
      }
    };
  }

  // Frames drawn per second, measured over each second.
  let lastFrames = 0;
  setInterval(() => {
    if (!view) return;
    const n = view.framesDrawn();
    live.fps = n - lastFrames;
    lastFrames = n;
    document.getElementById("fps").textContent = live.fps + " frames/s";
  }, 1000);

  connect();
})();
