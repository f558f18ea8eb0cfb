// Forward kinematics of a URDF arm (sent as JSON by armhil) and a wire-frame view of it on a
// 2D canvas with its own perspective projection: no WebGL, no library.
//
// The model JSON: { name, joints: [{ name, type, parent, child, xyz, rpy, axis, lower, upper,
// mimic: { joint, multiplier, offset } | null }] } with joints ordered from the root to the
// leaves, so one pass computes every link frame.
(function (root, factory) {
  const api = factory();
  if (typeof module === "object" && module.exports) module.exports = api;
  else root.ArmHil = Object.assign(root.ArmHil || {}, api);
})(typeof self !== "undefined" ? self : this, function () {
  "use strict";

  // 4x4 homogeneous transforms as row-major arrays of 16 numbers.
  const IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];

  function mul(a, b) {
    const out = new Array(16);
    for (let r = 0; r < 4; r++) {
      for (let c = 0; c < 4; c++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[r * 4 + k] * b[k * 4 + c];
        out[r * 4 + c] = s;
      }
    }
    return out;
  }

  // URDF rpy are fixed-axis X, Y, Z: R = Rz(yaw) * Ry(pitch) * Rx(roll).
  function fromXyzRpy(xyz, rpy) {
    const [x, y, z] = xyz || [0, 0, 0];
    const [r, p, w] = rpy || [0, 0, 0];
    const cr = Math.cos(r), sr = Math.sin(r);
    const cp = Math.cos(p), sp = Math.sin(p);
    const cw = Math.cos(w), sw = Math.sin(w);
    return [
      cw * cp, cw * sp * sr - sw * cr, cw * sp * cr + sw * sr, x,
      sw * cp, sw * sp * sr + cw * cr, sw * sp * cr - cw * sr, y,
      -sp, cp * sr, cp * cr, z,
      0, 0, 0, 1,
    ];
  }

  // Rotation by `angle` (rad) about the unit `axis` (Rodrigues).
  function rotation(axis, angle) {
    const n = Math.hypot(axis[0], axis[1], axis[2]) || 1;
    const [x, y, z] = [axis[0] / n, axis[1] / n, axis[2] / n];
    const c = Math.cos(angle), s = Math.sin(angle), t = 1 - c;
    return [
      t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0,
      t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0,
      t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0,
      0, 0, 0, 1,
    ];
  }

  function translation(axis, d) {
    const m = IDENTITY.slice();
    m[3] = axis[0] * d;
    m[7] = axis[1] * d;
    m[11] = axis[2] * d;
    return m;
  }

  function origin(m) {
    return [m[3], m[7], m[11]];
  }

  function apply(m, p) {
    return [
      m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3],
      m[4] * p[0] + m[5] * p[1] + m[6] * p[2] + m[7],
      m[8] * p[0] + m[9] * p[1] + m[10] * p[2] + m[11],
    ];
  }

  // The moving joints a caller sets: revolute/continuous/prismatic joints without <mimic>.
  function actuatedJoints(model) {
    return model.joints.filter((j) => j.type !== "fixed" && !j.mimic);
  }

  // The revolute joints of the arm (the ones a trace's j1_deg.. columns drive), in order.
  function armJoints(model) {
    return actuatedJoints(model).filter((j) => j.type !== "prismatic");
  }

  // Joint values by name: `values` (name -> rad or m) plus the mimic joints that follow them.
  function resolveMimic(model, values) {
    const out = Object.assign({}, values);
    for (const j of model.joints) {
      if (j.mimic) {
        const lead = out[j.mimic.joint] || 0;
        out[j.name] = lead * j.mimic.multiplier + j.mimic.offset;
      }
    }
    return out;
  }

  // Frame of every link for joint values by name (missing ones are 0): in the base frame, or in
  // the world when `base` (the root link's pose, 16 numbers by rows) is given — a floating
  // robot's root moves.
  function linkFrames(model, values, base) {
    const q = resolveMimic(model, values || {});
    const frames = {};
    const rootName = model.joints.length ? model.joints[0].parent : model.root;
    frames[rootName] = Array.isArray(base) && base.length === 16 ? base.slice() : IDENTITY.slice();
    for (const j of model.joints) {
      const parent = frames[j.parent] || IDENTITY;
      let m = mul(parent, fromXyzRpy(j.xyz, j.rpy));
      const v = q[j.name] || 0;
      if (j.type === "revolute" || j.type === "continuous") m = mul(m, rotation(j.axis, v));
      else if (j.type === "prismatic") m = mul(m, translation(j.axis, v));
      frames[j.child] = m;
    }
    return frames;
  }

  // Joint values by name from the arm's angles in degrees (j1..jN) and the gripper opening in
  // metres (split between the prismatic joints: each finger travels half).
  function valuesFromDeg(model, anglesDeg, gripperM) {
    const values = {};
    armJoints(model).forEach((j, i) => {
      const a = anglesDeg[i];
      if (typeof a === "number" && isFinite(a)) values[j.name] = (a * Math.PI) / 180;
    });
    if (typeof gripperM === "number" && isFinite(gripperM)) {
      for (const j of actuatedJoints(model)) {
        if (j.type === "prismatic") values[j.name] = gripperM / 2;
      }
    }
    return values;
  }

  // A robot's pose from its trace, as a report's `pose` document maps the columns: `read(name)`
  // gives a column's value at the cursor (null when not traced yet). Each joint is
  // direction · value + offset (rad); the root link is placed from the base columns (any
  // missing count as 0). Returns the angles for `set` (degrees, armJoints order; NaN where
  // unknown) and the root pose (16 numbers by rows, or undefined for a fixed base).
  function poseFromColumns(model, pose, read) {
    const rad = {};
    for (const j of pose.joints) {
      const v = read(j.column);
      if (typeof v === "number" && isFinite(v)) rad[j.joint] = j.direction * v + j.offset;
    }
    const deg = armJoints(model).map((j) => (j.name in rad ? (rad[j.name] * 180) / Math.PI : NaN));
    let base;
    if (pose.base) {
      const value = (name) => {
        const v = read(name);
        return typeof v === "number" && isFinite(v) ? v : 0;
      };
      base = fromXyzRpy(pose.base.position.map(value), pose.base.rpy.map(value));
    }
    return { deg, base };
  }

  // A camera orbiting `target`: yaw/pitch in rad, distance in m. Returns a projector from world
  // points to [x, y, depth] in canvas pixels.
  function projector(cam, width, height) {
    const cy = Math.cos(cam.yaw), sy = Math.sin(cam.yaw);
    const cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
    // Camera axes: right, up, forward (towards the target), world Z up.
    const fwd = [-cp * cy, -cp * sy, -sp];
    const right = [-sy, cy, 0];
    const up = [
      right[1] * fwd[2] - right[2] * fwd[1],
      right[2] * fwd[0] - right[0] * fwd[2],
      right[0] * fwd[1] - right[1] * fwd[0],
    ];
    const eye = [
      cam.target[0] - fwd[0] * cam.distance,
      cam.target[1] - fwd[1] * cam.distance,
      cam.target[2] - fwd[2] * cam.distance,
    ];
    const focal = Math.min(width, height) * 1.4;
    return function (p) {
      const d = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
      const z = d[0] * fwd[0] + d[1] * fwd[1] + d[2] * fwd[2];
      const x = d[0] * right[0] + d[1] * right[1] + d[2] * right[2];
      const y = d[0] * up[0] + d[1] * up[1] + d[2] * up[2];
      const zz = Math.max(z, 1e-3);
      return [width / 2 + (x * focal) / zz, height / 2 - (y * focal) / zz, z];
    };
  }

  const LINK_COLORS = ["#4a5568", "#2b6cb0", "#2f855a", "#c05621", "#6b46c1", "#b83280", "#2c7a7b", "#975a16"];

  // Segments to draw for joint values: each joint links its parent's origin to its own.
  function segments(model, values, base) {
    const frames = linkFrames(model, values, base);
    const segs = [];
    model.joints.forEach((j, i) => {
      const a = origin(frames[j.parent] || IDENTITY);
      const m = frames[j.child];
      const b = origin(m);
      const finger = j.type === "prismatic" || (j.mimic && j.type === "prismatic");
      segs.push({ a, b, joint: j, width: finger ? 4 : 9, color: finger ? "#444" : LINK_COLORS[i % LINK_COLORS.length] });
      if (finger) {
        // A finger: a short bar along the joint's child z axis.
        segs.push({ a: b, b: apply(m, [0, 0, 0.04]), joint: j, width: 4, color: "#444" });
      }
    });
    return { frames, segs };
  }

  // A view of `model` on `canvas`. Drag to orbit, wheel to zoom. `set(anglesDeg, gripperM,
  // base)` changes the pose (`base`: the root link's pose in the world, for a floating robot); `renderedDeg()` returns the angles last drawn; the canvas's data-angles and data-root
  // attributes hold them and the root link's position (tests read them).
  function createArmView(canvas, model) {
    const ctx = canvas.getContext("2d");
    // Frame the model whatever its pose: no link is further from the root than the longest
    // chain of joint offsets (a tree's branches, a humanoid's limbs, are not added up).
    const reach = {};
    let size = 0.3;
    for (const j of model.joints) {
      reach[j.child] = (reach[j.parent] || 0) + Math.hypot(...(j.xyz || [0, 0, 0]));
      size = Math.max(size, reach[j.child]);
    }
    const cam = { yaw: 0.9, pitch: 0.4, distance: 1.3 * size, target: [0, 0, 0.3 * size] };
    let pose = { deg: [], gripperM: undefined, base: undefined };
    let framedOnBase = false;
    let drawn = [];
    let dirty = true;
    let frames = 0;
    let drag = null;
    canvas.addEventListener("mousedown", (e) => { drag = [e.clientX, e.clientY]; });
    window.addEventListener("mouseup", () => { drag = null; });
    window.addEventListener("mousemove", (e) => {
      if (!drag) return;
      cam.yaw -= (e.clientX - drag[0]) * 0.01;
      cam.pitch = Math.max(-1.4, Math.min(1.4, cam.pitch + (e.clientY - drag[1]) * 0.01));
      drag = [e.clientX, e.clientY];
      dirty = true;
    });
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      cam.distance = Math.max(0.3, Math.min(8, cam.distance * (e.deltaY > 0 ? 1.1 : 0.9)));
      dirty = true;
    }, { passive: false });

    function draw() {
      const w = canvas.width, h = canvas.height;
      ctx.clearRect(0, 0, w, h);
      ctx.fillStyle = "#f7fafc";
      ctx.fillRect(0, 0, w, h);
      const proj = projector(cam, w, h);
      // Floor grid, 0.1 m pitch.
      ctx.strokeStyle = "#e2e8f0";
      ctx.lineWidth = 1;
      for (let i = -5; i <= 5; i++) {
        const l = [proj([i / 10, -0.5, 0]), proj([i / 10, 0.5, 0])];
        const m = [proj([-0.5, i / 10, 0]), proj([0.5, i / 10, 0])];
        for (const [p, q] of [l, m]) {
          ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(q[0], q[1]); ctx.stroke();
        }
      }
      const values = valuesFromDeg(model, pose.deg, pose.gripperM);
      const { frames: fr, segs } = segments(model, values, pose.base);
      const items = segs.map((s) => {
        const a = proj(s.a), b = proj(s.b);
        return { s, a, b, depth: (a[2] + b[2]) / 2 };
      });
      items.sort((x, y) => y.depth - x.depth);
      ctx.lineCap = "round";
      for (const it of items) {
        ctx.strokeStyle = it.s.color;
        ctx.lineWidth = Math.max(2, (it.s.width * 1.6) / Math.max(it.depth, 0.2));
        ctx.beginPath(); ctx.moveTo(it.a[0], it.a[1]); ctx.lineTo(it.b[0], it.b[1]); ctx.stroke();
      }
      // Joints: a dot and a short line along the rotation axis.
      for (const j of armJoints(model)) {
        const m = fr[j.child];
        if (!m) continue;
        const p = proj(origin(m));
        const ax = proj(apply(m, j.axis.map((v) => v * 0.05)));
        ctx.strokeStyle = "#e53e3e"; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(ax[0], ax[1]); ctx.stroke();
        ctx.fillStyle = "#1a202c";
        ctx.beginPath(); ctx.arc(p[0], p[1], 4, 0, 2 * Math.PI); ctx.fill();
      }
      drawn = armJoints(model).map((j) => ((values[j.name] || 0) * 180) / Math.PI);
      frames++;
      canvas.dataset.angles = drawn.map((a) => a.toFixed(2)).join(",");
      const root = fr[model.joints.length ? model.joints[0].parent : model.root];
      if (root) canvas.dataset.root = origin(root).map((v) => v.toFixed(3)).join(",");
      canvas.dataset.frames = String(frames);
    }

    function loop() {
      if (dirty) { dirty = false; draw(); }
      requestAnimationFrame(loop);
    }
    requestAnimationFrame(loop);

    return {
      set(anglesDeg, gripperM, base) {
        if (base && !framedOnBase) {
          // A floating robot: look at its root where it first stands, from far enough that
          // the limbs above and below it (the longest chain each way) fit.
          framedOnBase = true;
          cam.target = [base[3], base[7], base[11]];
          cam.distance = 2.8 * size;
        }
        pose = { deg: anglesDeg.slice(), gripperM, base };
        dirty = true;
      },
      renderedDeg: () => drawn.slice(),
      framesDrawn: () => frames,
      camera: cam,
      redraw() { dirty = true; },
    };
  }

  // One dial per motor (RobStride): the angle as a needle and its value in degrees. Same
  // interface as createArmView: set(anglesDeg), renderedDeg(), framesDrawn().
  function createDialsView(canvas, labels) {
    const ctx = canvas.getContext("2d");
    let angles = labels.map(() => 0), drawn = [], frames = 0, dirty = true;
    function draw() {
      const w = canvas.width, h = canvas.height, n = labels.length;
      const r = Math.min(h / 2 - 30, w / (2 * n) - 16);
      ctx.clearRect(0, 0, w, h);
      ctx.fillStyle = "#f7fafc"; ctx.fillRect(0, 0, w, h);
      labels.forEach((label, i) => {
        const cx = (w / n) * (i + 0.5), cy = h / 2;
        ctx.strokeStyle = "#a0aec0"; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.arc(cx, cy, r, 0, 2 * Math.PI); ctx.stroke();
        for (let k = 0; k < 12; k++) {
          const a = (k * Math.PI) / 6;
          ctx.beginPath(); ctx.moveTo(cx + r * 0.9 * Math.sin(a), cy - r * 0.9 * Math.cos(a));
          ctx.lineTo(cx + r * Math.sin(a), cy - r * Math.cos(a)); ctx.stroke();
        }
        const a = ((angles[i] || 0) * Math.PI) / 180;
        ctx.strokeStyle = "#c05621"; ctx.lineWidth = 5; ctx.lineCap = "round";
        ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(cx + r * 0.8 * Math.sin(a), cy - r * 0.8 * Math.cos(a)); ctx.stroke();
        ctx.fillStyle = "#1a202c"; ctx.font = "13px sans-serif"; ctx.textAlign = "center";
        ctx.fillText(label + ": " + (isFinite(angles[i]) ? angles[i].toFixed(1) : "–") + "°", cx, cy + r + 20);
        ctx.textAlign = "start";
      });
      drawn = angles.slice();
      frames++;
      canvas.dataset.angles = drawn.map((x) => x.toFixed(2)).join(",");
      canvas.dataset.frames = String(frames);
    }
    (function loop() { if (dirty) { dirty = false; draw(); } requestAnimationFrame(loop); })();
    return {
      set(deg) { angles = deg.slice(); dirty = true; },
      redraw() { dirty = true; },
      renderedDeg: () => drawn.slice(),
      framesDrawn: () => frames,
    };
  }

  return {
    createDialsView,
    mul, fromXyzRpy, rotation, translation, apply, origin,
    linkFrames, valuesFromDeg, poseFromColumns, armJoints, actuatedJoints, projector, segments, createArmView,
  };
});
