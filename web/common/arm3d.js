// Forward kinematics of a URDF arm (sent as JSON by armhil) and a view of it on a 2D canvas
// with its own perspective projection — its links' visual geometry as flat-shaded triangles,
// and a stick figure of its joints — no WebGL, no library.
//
// The model JSON: { name, joints: [{ name, type, parent, child, xyz, rpy, axis, lower, upper,
// mimic: { joint, multiplier, offset } | null }] } with joints ordered from the root to the
// leaves, so one pass computes every link frame. A URDF with <visual>s adds
//   visuals: [{ link, xyz, rpy, color: [r, g, b, a] | null, geometry: { type: "box", size }
//     | { type: "cylinder" | "capsule", radius, length } | { type: "sphere", radius }
//     | { type: "mesh", mesh: index into meshes, scale } }],
//   meshes: [{ file, min, step, positions: [3 integers a vertex], triangles: [3 indices each],
//     color }] (vertex k = min + step * positions[3k..3k+3]),
//   fallbacks: [{ link, reason }] (links drawn as the stick figure: their mesh is unreadable).
// The visuals are drawn as flat-shaded filled triangles, farthest first (painter's order), the
// stick figure thin on top of them and as it always was for links without visuals.
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
  // points to [x, y, depth] in canvas pixels (its `camera` property holds the camera's axes).
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
    const project = function (p) {
      const d = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
      const z = d[0] * fwd[0] + d[1] * fwd[1] + d[2] * fwd[2];
      const x = d[0] * right[0] + d[1] * right[1] + d[2] * right[2];
      const y = d[0] * up[0] + d[1] * up[1] + d[2] * up[2];
      const zz = Math.max(z, 1e-3);
      return [width / 2 + (x * focal) / zz, height / 2 - (y * focal) / zz, z];
    };
    // The camera's axes and eye, for lighting.
    project.camera = { fwd, right, up, eye };
    return project;
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
        segs.push({ a: b, b: apply(m, [0, 0, 0.04]), joint: j, width: 4, color: "#444", bar: true });
      }
    });
    return { frames, segs };
  }

  // ---- Visual geometry ------------------------------------------------------------------

  // A mesh's vertices in its file's frame: [x0, y0, z0, x1, ...] from the quantised integers.
  function decodeMesh(mesh) {
    const q = mesh.positions || [];
    const out = new Float64Array(q.length);
    for (let i = 0; i < q.length; i++) out[i] = mesh.min[i % 3] + mesh.step * q[i];
    return out;
  }

  // Triangles of a primitive (or a mesh of `meshes`) in the visual's frame:
  // { positions: [x, y, z, ...], triangles: [a, b, c, ...] }, or null if it cannot be drawn.
  // Round shapes use `segments` around (16 by default).
  function tessellate(geometry, meshes, segments) {
    const n = Math.max(3, segments || 16);
    const P = [], T = [];
    const vertex = (x, y, z) => { P.push(x, y, z); return P.length / 3 - 1; };
    // Rings of a solid of revolution about z: each ring [radius, z]; the first and last may
    // have radius 0 (poles). Consecutive rings are joined by quads; end rings are capped.
    function lathe(rings) {
      const starts = rings.map(([r, z]) => {
        const start = P.length / 3;
        if (r === 0) vertex(0, 0, z);
        else for (let k = 0; k < n; k++) vertex(r * Math.cos((2 * Math.PI * k) / n), r * Math.sin((2 * Math.PI * k) / n), z);
        return start;
      });
      const at = (i, k) => (rings[i][0] === 0 ? starts[i] : starts[i] + (k % n));
      for (let i = 0; i + 1 < rings.length; i++) {
        for (let k = 0; k < n; k++) {
          const a = at(i, k), b = at(i, k + 1), c = at(i + 1, k + 1), d = at(i + 1, k);
          if (a !== b) T.push(a, b, c);
          if (c !== d) T.push(a, c, d);
        }
      }
      for (const i of [0, rings.length - 1]) {
        if (rings[i][0] === 0) continue;
        const centre = vertex(0, 0, rings[i][1]);
        for (let k = 0; k < n; k++) {
          if (i === 0) T.push(centre, at(i, k + 1), at(i, k));
          else T.push(centre, at(i, k), at(i, k + 1));
        }
      }
    }
    // Half-sphere rings from the equator (z0) to the pole, upwards (+1) or downwards (-1).
    function dome(r, z0, dir, steps) {
      const rings = [];
      for (let i = 0; i <= steps; i++) {
        const a = ((Math.PI / 2) * i) / steps;
        rings.push([i === steps ? 0 : r * Math.cos(a), z0 + dir * r * Math.sin(a)]);
      }
      return rings;
    }
    const g = geometry || {};
    if (g.type === "box") {
      const [x, y, z] = (g.size || [0, 0, 0]).map((v) => v / 2);
      for (const c of [[-x, -y, -z], [x, -y, -z], [x, y, -z], [-x, y, -z], [-x, -y, z], [x, -y, z], [x, y, z], [-x, y, z]]) vertex(...c);
      T.push(0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7);
    } else if (g.type === "cylinder") {
      lathe([[g.radius, -g.length / 2], [g.radius, g.length / 2]]);
    } else if (g.type === "sphere") {
      const half = Math.max(2, Math.round(n / 4));
      lathe(dome(g.radius, 0, -1, half).reverse().concat(dome(g.radius, 0, 1, half).slice(1)));
    } else if (g.type === "capsule") {
      const half = Math.max(2, Math.round(n / 4));
      lathe(dome(g.radius, -g.length / 2, -1, half).reverse().concat(dome(g.radius, g.length / 2, 1, half)));
    } else if (g.type === "mesh") {
      const mesh = meshes && meshes[g.mesh];
      if (!mesh) return null;
      const p = decodeMesh(mesh);
      const s = g.scale || [1, 1, 1];
      for (let i = 0; i < p.length; i++) p[i] *= s[i % 3];
      return { positions: p, triangles: mesh.triangles || [] };
    } else {
      return null;
    }
    return { positions: P, triangles: T };
  }

  // Whether a shape's triangles face outwards (+1: counter-clockwise seen from outside),
  // inwards (-1), or cannot be told (0: an open or inconsistently wound mesh, whose faces must
  // all be drawn). Told by nearly every edge being met in both directions (a closed, evenly
  // wound surface) and by the sign of the volume it encloses.
  function orientation(positions, triangles) {
    const n = positions.length / 3;
    const edges = new Set();
    for (let i = 0; i + 2 < triangles.length; i += 3) {
      for (let k = 0; k < 3; k++) edges.add(triangles[i + k] * n + triangles[i + ((k + 1) % 3)]);
    }
    let matched = 0, volume = 0;
    for (let i = 0; i + 2 < triangles.length; i += 3) {
      for (let k = 0; k < 3; k++) if (edges.has(triangles[i + ((k + 1) % 3)] * n + triangles[i + k])) matched++;
      const a = 3 * triangles[i], b = 3 * triangles[i + 1], c = 3 * triangles[i + 2];
      const P = positions;
      volume += P[a] * (P[b + 1] * P[c + 2] - P[b + 2] * P[c + 1])
        - P[a + 1] * (P[b] * P[c + 2] - P[b + 2] * P[c])
        + P[a + 2] * (P[b] * P[c + 1] - P[b + 1] * P[c]);
    }
    if (!triangles.length || matched < 0.95 * triangles.length) return 0;
    return volume > 0 ? 1 : volume < 0 ? -1 : 0;
  }

  const DEFAULT_VISUAL_COLOR = [0.62, 0.66, 0.72, 1];

  // Every visual of `model` ready to draw: { link, origin (16 numbers: the visual's pose in
  // its link), positions, triangles, color [r, g, b, a], facing (see `orientation`) }.
  // Computed once per view.
  function visualParts(model) {
    const parts = [];
    // Round primitives get 16 segments around, fewer when there are many (a URDF of a
    // thousand spheres stays within a few thousand triangles, as meshes are capped).
    const round = (model.visuals || []).filter((v) => ["cylinder", "sphere", "capsule"].includes(v.geometry.type)).length;
    const segments = round <= 30 ? 16 : Math.max(6, Math.round(16 * Math.sqrt(30 / round)));
    for (const v of model.visuals || []) {
      const shape = tessellate(v.geometry, model.meshes, segments);
      if (!shape || !shape.triangles.length) continue;
      const mesh = v.geometry.type === "mesh" ? model.meshes[v.geometry.mesh] : null;
      const color = (v.color || (mesh && mesh.color) || DEFAULT_VISUAL_COLOR).slice();
      parts.push({
        link: v.link, origin: fromXyzRpy(v.xyz, v.rpy), positions: shape.positions, triangles: shape.triangles, color,
        facing: orientation(shape.positions, shape.triangles),
      });
    }
    return parts;
  }

  // Shading levels of a triangle's colour (flat shading is quantised so canvas fill styles
  // can be reused).
  const SHADES = 24;

  // The triangles of `parts` posed by `frames` and seen through `proj` (a projector: it has
  // the camera's axes), farthest first: { count, order (triangle numbers), depth, x, y (3
  // screen points each), part, shade (0..SHADES) }. Lit from over the viewer's shoulder;
  // both sides of a triangle are lit alike. The back faces of a closed part whose winding is
  // known are left out (half the work, and none can cover a front face).
  function shadedTriangles(parts, frames, proj) {
    const cam = proj.camera || { fwd: [0, 0, -1], up: [0, 1, 0], right: [1, 0, 0], eye: [0, 0, 1e9] };
    const eye = cam.eye;
    const L = [0, 1, 2].map((i) => -cam.fwd[i] + 0.6 * cam.up[i] - 0.35 * cam.right[i]);
    const ln = Math.hypot(...L);
    for (let i = 0; i < 3; i++) L[i] /= ln;
    let total = 0;
    for (const p of parts) total += p.triangles.length / 3;
    const xs = new Float64Array(total * 3), ys = new Float64Array(total * 3);
    const depth = new Float64Array(total), shade = new Uint8Array(total), part = new Uint32Array(total);
    let count = 0;
    parts.forEach((p, pi) => {
      const frame = frames[p.link];
      if (!frame) return;
      const m = mul(frame, p.origin);
      const n = p.positions.length / 3;
      const w = new Float64Array(n * 3), s = new Float64Array(n * 3);
      for (let k = 0; k < n; k++) {
        const x = p.positions[3 * k], y = p.positions[3 * k + 1], z = p.positions[3 * k + 2];
        const wx = m[0] * x + m[1] * y + m[2] * z + m[3];
        const wy = m[4] * x + m[5] * y + m[6] * z + m[7];
        const wz = m[8] * x + m[9] * y + m[10] * z + m[11];
        w[3 * k] = wx; w[3 * k + 1] = wy; w[3 * k + 2] = wz;
        const q = proj([wx, wy, wz]);
        s[3 * k] = q[0]; s[3 * k + 1] = q[1]; s[3 * k + 2] = q[2];
      }
      const t = p.triangles;
      for (let i = 0; i + 2 < t.length; i += 3) {
        const a = t[i], b = t[i + 1], c = t[i + 2];
        if (a >= n || b >= n || c >= n) continue;
        // Behind the camera: not drawn.
        if (s[3 * a + 2] <= 1e-3 || s[3 * b + 2] <= 1e-3 || s[3 * c + 2] <= 1e-3) continue;
        const ux = w[3 * b] - w[3 * a], uy = w[3 * b + 1] - w[3 * a + 1], uz = w[3 * b + 2] - w[3 * a + 2];
        const vx = w[3 * c] - w[3 * a], vy = w[3 * c + 1] - w[3 * a + 1], vz = w[3 * c + 2] - w[3 * a + 2];
        const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        const len = Math.hypot(nx, ny, nz);
        if (!(len > 0)) continue;
        if (p.facing && p.facing * (nx * (eye[0] - w[3 * a]) + ny * (eye[1] - w[3 * a + 1]) + nz * (eye[2] - w[3 * a + 2])) <= 0) continue;
        const lambert = Math.abs(nx * L[0] + ny * L[1] + nz * L[2]) / len;
        shade[count] = Math.min(SHADES, Math.round((0.35 + 0.65 * lambert) * SHADES));
        depth[count] = (s[3 * a + 2] + s[3 * b + 2] + s[3 * c + 2]) / 3;
        xs[3 * count] = s[3 * a]; ys[3 * count] = s[3 * a + 1];
        xs[3 * count + 1] = s[3 * b]; ys[3 * count + 1] = s[3 * b + 1];
        xs[3 * count + 2] = s[3 * c]; ys[3 * count + 2] = s[3 * c + 1];
        part[count] = pi;
        count++;
      }
    });
    const order = new Uint32Array(count);
    for (let i = 0; i < count; i++) order[i] = i;
    order.sort((i, j) => depth[j] - depth[i]);
    return { count, order, depth, x: xs, y: ys, part, shade };
  }

  // The box holding every visual of `parts` posed by `frames`: { min, max }, or null.
  function visualBounds(parts, frames) {
    const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
    for (const p of parts) {
      if (!frames[p.link]) continue;
      const m = mul(frames[p.link], p.origin);
      for (let k = 0; k + 2 < p.positions.length; k += 3) {
        const q = apply(m, [p.positions[k], p.positions[k + 1], p.positions[k + 2]]);
        for (let i = 0; i < 3; i++) { min[i] = Math.min(min[i], q[i]); max[i] = Math.max(max[i], q[i]); }
      }
    }
    return min[0] <= max[0] ? { min, max } : null;
  }

  // Fills the triangles of `shadedTriangles` on a 2D context, each with its part's colour at
  // its shade. Each is grown by half a pixel (every edge moved out, corners mitred up to
  // 2 px), which closes the seams anti-aliasing leaves between neighbours (an outline would
  // too, at twice the cost).
  function fillTriangles(ctx, parts, tris) {
    const styles = parts.map((p) => {
      const alpha = p.color.length > 3 ? p.color[3] : 1;
      const out = [];
      for (let k = 0; k <= SHADES; k++) {
        const f = k / SHADES;
        // Lifted a little off black, so a black part still shows its shape.
        const c = [0, 1, 2].map((i) => Math.round(255 * (0.1 + 0.9 * Math.min(1, Math.max(0, p.color[i]))) * f));
        out.push(alpha < 1 ? `rgba(${c[0]},${c[1]},${c[2]},${alpha})` : `rgb(${c[0]},${c[1]},${c[2]})`);
      }
      return out;
    });
    const X = tris.x, Y = tris.y;
    const grown = new Float64Array(6);
    let style = null;
    for (let o = 0; o < tris.count; o++) {
      const i = tris.order[o];
      const next = styles[tris.part[i]][tris.shade[i]];
      if (next !== style) { style = next; ctx.fillStyle = style; }
      growTriangle(X, Y, 3 * i, 0.5, grown);
      ctx.beginPath();
      ctx.moveTo(grown[0], grown[1]);
      ctx.lineTo(grown[2], grown[3]);
      ctx.lineTo(grown[4], grown[5]);
      ctx.fill();
    }
  }

  // The triangle at X[at..at+3], Y[at..at+3] with every edge moved out by `d` (its corners
  // mitred, each moved at most 4·d), into out = [x0, y0, x1, y1, x2, y2].
  function growTriangle(X, Y, at, d, out) {
    // Which way is out: the winding's sign.
    const area = (X[at + 1] - X[at]) * (Y[at + 2] - Y[at]) - (X[at + 2] - X[at]) * (Y[at + 1] - Y[at]);
    const side = area >= 0 ? 1 : -1;
    for (let k = 0; k < 3; k++) {
      const a = at + ((k + 2) % 3), b = at + k, c = at + ((k + 1) % 3);
      // Outward unit normals of the edges a→b and b→c.
      let ux = Y[b] - Y[a], uy = X[a] - X[b];
      let vx = Y[c] - Y[b], vy = X[b] - X[c];
      const lu = Math.hypot(ux, uy) || 1, lv = Math.hypot(vx, vy) || 1;
      ux = (side * ux) / lu; uy = (side * uy) / lu;
      vx = (side * vx) / lv; vy = (side * vy) / lv;
      // The corner moves along the sum of the normals, far enough for both edges to move d.
      const mx = ux + vx, my = uy + vy;
      const dot = 1 + ux * vx + uy * vy;
      let f = dot > 1e-9 ? d / dot : 4 * d;
      const len = Math.hypot(mx, my) * f;
      if (len > 4 * d) f *= (4 * d) / len;
      out[2 * k] = X[b] + mx * f;
      out[2 * k + 1] = Y[b] + my * f;
    }
    return out;
  }

  // A view of `model` on `canvas`. Drag to orbit, wheel to zoom. `set(anglesDeg, gripperM,
  // base)` changes the pose (`base`: the root link's pose in the world, for a floating robot); `renderedDeg()` returns the angles last drawn; the canvas's data-angles and data-root
  // attributes hold them and the root link's position (tests read them), data-triangles the
  // visual triangles last filled and data-fallbacks the links whose geometry could not be
  // drawn (their reasons are the canvas's title, and a line at its foot).
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
    // Visual geometry, tessellated once; links with some are drawn solid, the stick figure
    // thin over them.
    const parts = visualParts(model);
    const solid = new Set(parts.map((p) => p.link));
    // Links with a moving joint at or below them: over solid links the thin chain leaves out
    // fixed joints to leaves (sensors, frames), which would only criss-cross the body.
    const moving = new Set();
    for (let i = model.joints.length - 1; i >= 0; i--) {
      const j = model.joints[i];
      if (j.type !== "fixed" || moving.has(j.child)) moving.add(j.parent), moving.add(j.child);
    }
    const fallbacks = model.fallbacks || [];
    if (fallbacks.length) {
      canvas.title = "Drawn as sticks (geometry not drawable):\n" + fallbacks.map((f) => f.link + ": " + f.reason).join("\n");
    }
    canvas.dataset.fallbacks = String(fallbacks.length);
    const fellBack = new Set(fallbacks.map((f) => f.link));
    let pose = { deg: [], gripperM: undefined, base: undefined };
    let framedOnBase = false;
    // A model with visuals is framed on them where it first stands (its meshes, not its
    // joint offsets, say how big it is).
    let framedOnVisuals = false;
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
      const values = valuesFromDeg(model, pose.deg, pose.gripperM);
      const { frames: fr, segs } = segments(model, values, pose.base);
      if (parts.length && !framedOnVisuals) {
        framedOnVisuals = true;
        const box = visualBounds(parts, fr);
        if (box) {
          cam.target = [0, 1, 2].map((i) => (box.min[i] + box.max[i]) / 2);
          const radius = Math.hypot(...[0, 1, 2].map((i) => box.max[i] - box.min[i])) / 2;
          cam.distance = Math.max(0.3, Math.min(8, 3.2 * radius));
        }
      }
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
      let triangles = 0;
      if (parts.length) {
        const tris = shadedTriangles(parts, fr, proj);
        fillTriangles(ctx, parts, tris);
        triangles = tris.count;
      }
      const items = [];
      for (const s of segs) {
        // A link drawn solid keeps a thin line of its chain on top; the line to a link whose
        // geometry could not be drawn stays as it was, standing in for it.
        const thin = solid.has(s.bar ? s.joint.child : s.joint.parent) && !(fellBack.has(s.joint.child) && !s.bar);
        if (thin && !s.bar && !moving.has(s.joint.child)) continue;
        const a = proj(s.a), b = proj(s.b);
        items.push({ s, a, b, thin, depth: (a[2] + b[2]) / 2 });
      }
      items.sort((x, y) => y.depth - x.depth);
      ctx.lineCap = "round";
      for (const it of items) {
        if (it.thin) {
          ctx.strokeStyle = "rgba(26, 32, 44, 0.55)";
          ctx.lineWidth = 1.5;
        } else {
          ctx.strokeStyle = it.s.color;
          ctx.lineWidth = Math.max(2, (it.s.width * 1.6) / Math.max(it.depth, 0.2));
        }
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
      canvas.dataset.triangles = String(triangles);
      if (fallbacks.length) {
        ctx.fillStyle = "#744210"; ctx.font = "12px sans-serif";
        const n = fallbacks.length;
        ctx.fillText(n + (n === 1 ? " link" : " links") + " drawn as sticks: geometry not readable (hover for why)", 8, h - 8);
      }
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
          framedOnVisuals = false;
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
    decodeMesh, tessellate, orientation, visualParts, visualBounds, shadedTriangles, fillTriangles, growTriangle,
  };
});
