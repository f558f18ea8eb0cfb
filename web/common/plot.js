// Time plots on a 2D canvas: several series over one time axis, shaded windows (faults), a
// cursor, wheel zoom and drag pan on the time axis, hover read-out. No library.
(function (root, factory) {
  const api = factory();
  if (typeof module === "object" && module.exports) module.exports = api;
  else root.ArmHil = Object.assign(root.ArmHil || {}, api);
})(typeof self !== "undefined" ? self : this, function () {
  "use strict";

  const COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf"];

  // Round tick positions inside [lo, hi]: steps of 1, 2 or 5 × 10^k, about `count` of them.
  function niceTicks(lo, hi, count) {
    if (!(isFinite(lo) && isFinite(hi)) || hi <= lo) return [lo];
    const want = Math.max(1, count || 5);
    const mag = Math.pow(10, Math.floor(Math.log10((hi - lo) / want)));
    // The 1/2/5 step whose number of intervals is nearest to the count asked for.
    let step = mag;
    for (const m of [1, 2, 5, 10]) {
      if (Math.abs((hi - lo) / (m * mag) - want) < Math.abs((hi - lo) / step - want)) step = m * mag;
    }
    const ticks = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) {
      ticks.push(Math.abs(v) < step * 1e-9 ? 0 : +v.toPrecision(12));
    }
    return ticks;
  }

  // Value range of the series between sample indices i0..i1 (inclusive), with a 5 % margin
  // and never an empty range (a flat line gets ±1 around it).
  function valueBounds(series, i0, i1) {
    let lo = Infinity, hi = -Infinity;
    for (const ys of series) {
      for (let i = Math.max(0, i0); i <= Math.min(ys.length - 1, i1); i++) {
        const v = ys[i];
        if (v === null || v === undefined || !isFinite(v)) continue;
        if (v < lo) lo = v;
        if (v > hi) hi = v;
      }
    }
    if (lo === Infinity) return [-1, 1];
    if (hi - lo < 1e-9) return [lo - 1, hi + 1];
    const m = (hi - lo) * 0.05;
    return [lo - m, hi + m];
  }

  // Index of the sample of sorted `ts` nearest to `t` (-1 when empty).
  function nearestIndex(ts, t) {
    if (!ts.length) return -1;
    let lo = 0, hi = ts.length - 1;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (ts[mid] <= t) lo = mid; else hi = mid;
    }
    return Math.abs(ts[hi] - t) < Math.abs(ts[lo] - t) ? hi : lo;
  }

  // Zoom [x0, x1] by `factor` (< 1 zooms in) about `centre`, kept inside [min, max].
  function zoomRange(x0, x1, centre, factor, min, max) {
    let a = centre - (centre - x0) * factor;
    let b = centre + (x1 - centre) * factor;
    const full = max - min;
    if (b - a >= full || !(full > 0)) return [min, max];
    if (a < min) { b += min - a; a = min; }
    if (b > max) { a -= b - max; b = max; }
    return [a, b];
  }

  function fmt(v) {
    if (v === null || v === undefined) return "–";
    if (v === 0) return "0";
    const a = Math.abs(v);
    return a >= 100 ? v.toFixed(1) : a >= 1 ? v.toFixed(2) : v.toFixed(3);
  }

  // A plot in `canvas`: `opts` = { title, names: [...], height }. Methods: setData(ts, series),
  // setWindows([{from, to, label}]), setCursor(t), setView(x0, x1) / onView(cb),
  // onCursor(cb), follow(seconds) for live data.
  function createPlot(canvas, opts) {
    const ctx = canvas.getContext("2d");
    const L = 56, R = 12, T = 22, B = 22;
    let ts = [], series = [], windows = [], cursor = null, hover = null;
    let view = null, followS = 0;
    const listeners = { view: [], cursor: [] };
    let drag = null, dirty = true;

    const full = () => (ts.length ? [ts[0], Math.max(ts[ts.length - 1], ts[0] + 1e-3)] : [0, 1]);
    const range = () => {
      if (followS && ts.length) {
        const end = ts[ts.length - 1];
        const start = Math.max(ts[0], end - followS);
        return [start, Math.max(end, start + 1e-3)];
      }
      return view || full();
    };
    const xOf = (t, r) => L + ((t - r[0]) / (r[1] - r[0])) * (canvas.width - L - R);
    const tOf = (x, r) => r[0] + ((x - L) / (canvas.width - L - R)) * (r[1] - r[0]);

    function draw() {
      const w = canvas.width, h = canvas.height;
      const r = range();
      ctx.clearRect(0, 0, w, h);
      ctx.fillStyle = "#fff";
      ctx.fillRect(0, 0, w, h);
      const i0 = Math.max(0, nearestIndex(ts, r[0]) - 1);
      const i1 = Math.min(ts.length - 1, nearestIndex(ts, r[1]) + 1);
      const [lo, hi] = valueBounds(series, i0, i1);
      const yOf = (v) => T + (1 - (v - lo) / (hi - lo)) * (h - T - B);
      ctx.font = "11px sans-serif";
      for (const win of windows) {
        const a = Math.max(L, xOf(win.from, r)), b = Math.min(w - R, xOf(win.to, r));
        if (b <= a) continue;
        ctx.fillStyle = "rgba(229, 62, 62, 0.12)";
        ctx.fillRect(a, T, b - a, h - T - B);
        ctx.fillStyle = "#c53030";
        ctx.fillText(win.label, a + 2, T + 11);
      }
      ctx.strokeStyle = "#edf2f7";
      ctx.fillStyle = "#4a5568";
      ctx.lineWidth = 1;
      for (const v of niceTicks(lo, hi, 4)) {
        const y = yOf(v);
        ctx.beginPath(); ctx.moveTo(L, y); ctx.lineTo(w - R, y); ctx.stroke();
        ctx.fillText(fmt(v), 4, y + 4);
      }
      for (const t of niceTicks(r[0], r[1], 8)) {
        const x = xOf(t, r);
        ctx.beginPath(); ctx.moveTo(x, T); ctx.lineTo(x, h - B); ctx.stroke();
        ctx.fillText(t.toFixed(2) + " s", x - 14, h - 6);
      }
      ctx.save();
      ctx.beginPath(); ctx.rect(L, T, w - L - R, h - T - B); ctx.clip();
      series.forEach((ys, k) => {
        ctx.strokeStyle = COLORS[k % COLORS.length];
        ctx.lineWidth = 1.5;
        ctx.beginPath();
        let pen = false;
        // Draw at most about two points per pixel column.
        const stride = Math.max(1, Math.floor((i1 - i0) / (2 * (w - L - R))));
        for (let i = i0; i <= i1; i += stride) {
          const v = ys[i];
          if (v === null || v === undefined) { pen = false; continue; }
          const x = xOf(ts[i], r), y = yOf(v);
          if (pen) ctx.lineTo(x, y); else ctx.moveTo(x, y);
          pen = true;
        }
        ctx.stroke();
      });
      ctx.restore();
      ctx.fillStyle = "#1a202c";
      ctx.font = "bold 12px sans-serif";
      ctx.fillText(opts.title || "", L, 14);
      ctx.font = "11px sans-serif";
      let lx = L + ctx.measureText(opts.title || "").width + 40;
      (opts.names || []).forEach((n, k) => {
        ctx.fillStyle = COLORS[k % COLORS.length];
        ctx.fillRect(lx, 6, 10, 8);
        ctx.fillStyle = "#1a202c";
        ctx.fillText(n, lx + 13, 14);
        lx += ctx.measureText(n).width + 26;
      });
      if (cursor !== null) {
        const x = xOf(cursor, r);
        ctx.strokeStyle = "#2d3748"; ctx.lineWidth = 1.5;
        ctx.beginPath(); ctx.moveTo(x, T); ctx.lineTo(x, h - B); ctx.stroke();
      }
      if (hover !== null && ts.length) {
        const i = nearestIndex(ts, hover);
        const x = xOf(ts[i], r);
        ctx.strokeStyle = "#a0aec0"; ctx.setLineDash([3, 3]);
        ctx.beginPath(); ctx.moveTo(x, T); ctx.lineTo(x, h - B); ctx.stroke();
        ctx.setLineDash([]);
        const lines = [ts[i].toFixed(3) + " s"].concat(
          series.map((ys, k) => ((opts.names || [])[k] || "") + ": " + fmt(ys[i])));
        const bw = Math.max(...lines.map((s) => ctx.measureText(s).width)) + 10;
        const bx = x + bw + 12 > w ? x - bw - 6 : x + 6;
        ctx.fillStyle = "rgba(255,255,255,0.92)";
        ctx.fillRect(bx, T + 2, bw, lines.length * 13 + 6);
        ctx.strokeStyle = "#cbd5e0"; ctx.strokeRect(bx, T + 2, bw, lines.length * 13 + 6);
        lines.forEach((s, k) => {
          ctx.fillStyle = k === 0 ? "#1a202c" : COLORS[(k - 1) % COLORS.length];
          ctx.fillText(s, bx + 5, T + 15 + k * 13);
        });
      }
    }

    function loop() {
      if (dirty) { dirty = false; draw(); }
      requestAnimationFrame(loop);
    }
    requestAnimationFrame(loop);

    const emitView = () => listeners.view.forEach((f) => f(view));
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      const r = range(), f = full();
      const x = e.offsetX;
      view = zoomRange(r[0], r[1], tOf(x, r), e.deltaY > 0 ? 1.25 : 0.8, f[0], f[1]);
      followS = 0; dirty = true; emitView();
    }, { passive: false });
    canvas.addEventListener("mousedown", (e) => { drag = { x: e.offsetX, r: range(), moved: false }; });
    canvas.addEventListener("mousemove", (e) => {
      const r = range();
      hover = tOf(e.offsetX, r);
      if (drag && Math.abs(e.offsetX - drag.x) > 3) {
        const dt = tOf(drag.x, drag.r) - tOf(e.offsetX, drag.r);
        const f = full();
        view = zoomRange(drag.r[0] + dt, drag.r[1] + dt, 0, 1, f[0], f[1]);
        drag.moved = true; emitView();
      }
      dirty = true;
    });
    canvas.addEventListener("mouseleave", () => { hover = null; dirty = true; });
    canvas.addEventListener("mouseup", (e) => {
      if (drag && !drag.moved) {
        const t = tOf(e.offsetX, range());
        listeners.cursor.forEach((f) => f(t));
      }
      drag = null;
    });
    canvas.addEventListener("dblclick", () => { view = null; dirty = true; emitView(); });

    return {
      setData(newTs, newSeries) { ts = newTs; series = newSeries; dirty = true; },
      setWindows(w) { windows = w || []; dirty = true; },
      setCursor(t) { cursor = t; dirty = true; },
      setView(v) { view = v; dirty = true; },
      view: () => range(),
      follow(seconds) { followS = seconds; dirty = true; },
      onView(f) { listeners.view.push(f); },
      onCursor(f) { listeners.cursor.push(f); },
    };
  }

  return { niceTicks, valueBounds, nearestIndex, zoomRange, createPlot, PLOT_COLORS: COLORS };
});
