// The links' visual geometry as arm3d.js draws it: quantised meshes decoded, primitives
// tessellated into closed outward-wound solids, visuals posed with their links, back faces
// left out, farthest triangles first and faces towards the light brighter.
const test = require("node:test");
const assert = require("node:assert/strict");
const A = require("../../common/arm3d.js");

const near = (a, b, tol, what) => assert.ok(Math.abs(a - b) < tol, `${what}: ${a} vs ${b}`);

// Every vertex of a shape: [[x, y, z], ...].
const points = (shape) => {
  const out = [];
  for (let k = 0; k < shape.positions.length; k += 3) out.push([shape.positions[k], shape.positions[k + 1], shape.positions[k + 2]]);
  return out;
};

test("a quantised mesh decodes to min + step × integer, scaled per axis", () => {
  const mesh = { min: [-0.1, 0, 1], step: 0.01, positions: [0, 0, 0, 10, 20, 30], triangles: [0, 1, 1] };
  const p = A.decodeMesh(mesh);
  assert.deepEqual(Array.from(p).map((v) => Math.round(v * 1e9) / 1e9), [-0.1, 0, 1, 0, 0.2, 1.3]);
  const scaled = A.tessellate({ type: "mesh", mesh: 0, scale: [2, -1, 1] }, [mesh]);
  near(scaled.positions[3], 0, 1e-12, "x of the far corner");
  near(scaled.positions[4], -0.2, 1e-12, "y mirrored");
  assert.equal(scaled.triangles, mesh.triangles);
  assert.equal(A.tessellate({ type: "mesh", mesh: 3 }, [mesh]), null, "a missing mesh is not drawn");
  assert.equal(A.tessellate({ type: "torus" }, []), null);
});

test("primitives are closed solids of their sizes, wound outwards", () => {
  const box = A.tessellate({ type: "box", size: [0.2, 0.4, 0.6] });
  assert.equal(box.triangles.length / 3, 12);
  for (const p of points(box)) {
    near(Math.abs(p[0]), 0.1, 1e-12, "x");
    near(Math.abs(p[1]), 0.2, 1e-12, "y");
    near(Math.abs(p[2]), 0.3, 1e-12, "z");
  }
  const sphere = A.tessellate({ type: "sphere", radius: 0.5 });
  for (const p of points(sphere)) near(Math.hypot(...p), 0.5, 1e-9, "on the sphere");
  const cylinder = A.tessellate({ type: "cylinder", radius: 0.1, length: 1 });
  for (const p of points(cylinder)) {
    assert.ok(Math.hypot(p[0], p[1]) <= 0.1 + 1e-12 && Math.abs(Math.abs(p[2]) - 0.5) < 1e-12, `${p}`);
  }
  const capsule = A.tessellate({ type: "capsule", radius: 0.1, length: 1 });
  const zs = points(capsule).map((p) => p[2]);
  near(Math.max(...zs), 0.6, 1e-12, "top pole: half the length plus the radius");
  near(Math.min(...zs), -0.6, 1e-12, "bottom pole");
  for (const shape of [box, sphere, cylinder, capsule]) {
    assert.equal(A.orientation(shape.positions, shape.triangles), 1);
    // Reversed windings are told too.
    const flipped = [];
    for (let i = 0; i < shape.triangles.length; i += 3) flipped.push(shape.triangles[i], shape.triangles[i + 2], shape.triangles[i + 1]);
    assert.equal(A.orientation(shape.positions, flipped), -1);
  }
  // An open surface (one triangle) cannot be told: all its faces are drawn.
  assert.equal(A.orientation([0, 0, 0, 1, 0, 0, 0, 1, 0], [0, 1, 2]), 0);
});

// A link `arm` on a revolute joint about z, carrying a 0.1 m cube 0.5 m along its x axis.
const model = {
  name: "t",
  root: "base",
  joints: [{ name: "j", type: "revolute", parent: "base", child: "arm", xyz: [0, 0, 0], rpy: [0, 0, 0], axis: [0, 0, 1] }],
  visuals: [
    { link: "arm", xyz: [0.5, 0, 0], rpy: [0, 0, 0], geometry: { type: "box", size: [0.1, 0.1, 0.1] }, color: [1, 0, 0, 1] },
    { link: "base", xyz: [0, 0, 0], rpy: [0, 0, 0], geometry: { type: "mesh", mesh: 0, scale: [1, 1, 1] }, color: null },
  ],
  meshes: [{ file: "m.stl", min: [0, 0, 0], step: 0.1, positions: [0, 0, 0, 1, 0, 0, 0, 1, 0], triangles: [0, 1, 2], color: [0, 1, 0, 1] }],
};

test("visuals move with their links and take their colour from the URDF, else the mesh", () => {
  const parts = A.visualParts(model);
  assert.equal(parts.length, 2);
  assert.deepEqual(parts[0].color, [1, 0, 0, 1]);
  assert.deepEqual(parts[1].color, [0, 1, 0, 1], "the mesh's own colour");
  const turned = A.linkFrames(model, { j: Math.PI / 2 });
  const box = A.visualBounds([parts[0]], turned);
  // Turned 90° about z, the cube is 0.5 m along y.
  near((box.min[1] + box.max[1]) / 2, 0.5, 1e-9, "centre y");
  near((box.min[0] + box.max[0]) / 2, 0, 1e-9, "centre x");
  near(box.max[2] - box.min[2], 0.1, 1e-9, "its size");
});

test("triangles come farthest first, without back faces, lit by their facing", () => {
  const parts = A.visualParts({ ...model, visuals: [model.visuals[0]] });
  const frames = A.linkFrames(model, {});
  // Looking along -x at the cube from +x (yaw 0 puts the eye on +x).
  const proj = A.projector({ yaw: 0, pitch: 0, distance: 2, target: [0.5, 0, 0] }, 400, 300);
  const tris = A.shadedTriangles(parts, frames, proj);
  // A closed cube seen face on from its axis shows its front face only (2 triangles at
  // depth 1.95): its sides face away from the eye and its far face (2.05) is behind.
  assert.equal(tris.count, 2);
  // From above and aside three faces show, each of 2 triangles, in painter's order.
  const aside = A.shadedTriangles(parts, frames, A.projector({ yaw: 0.6, pitch: 0.5, distance: 2, target: [0.5, 0, 0] }, 400, 300));
  assert.equal(aside.count, 6);
  for (let o = 1; o < aside.count; o++) {
    assert.ok(aside.depth[aside.order[o - 1]] >= aside.depth[aside.order[o]], "painter's order");
  }
  for (let i = 0; i < 2; i++) near(tris.depth[i], 1.95, 1e-9, "the front face");
  // The top face, towards the light (above the eye), is lit more than the side faces.
  // The top face's two triangles are the ones drawn highest on screen (least mean y).
  const meanY = (i) => (aside.y[3 * i] + aside.y[3 * i + 1] + aside.y[3 * i + 2]) / 3;
  const byHeight = [...Array(aside.count).keys()].sort((a, b) => meanY(a) - meanY(b));
  const top = byHeight.slice(0, 2).map((i) => aside.shade[i]);
  const sides = byHeight.slice(2).map((i) => aside.shade[i]);
  assert.ok(Math.min(...top) > Math.max(...sides), `top ${top} sides ${sides}`);
  // An open mesh (winding unknown) is drawn from both sides.
  const open = A.visualParts({ ...model, visuals: [model.visuals[1]] });
  assert.equal(open[0].facing, 0);
  for (const yaw of [0, Math.PI]) {
    const p = A.projector({ yaw, pitch: 1.2, distance: 2, target: [0, 0, 0] }, 400, 300);
    assert.equal(A.shadedTriangles(open, frames, p).count, 1, `seen from yaw ${yaw}`);
  }
});

test("fillTriangles fills each triangle once in its part's shade", () => {
  const parts = A.visualParts({ ...model, visuals: [model.visuals[0]] });
  const proj = A.projector({ yaw: 0.7, pitch: 0.5, distance: 2, target: [0.5, 0, 0] }, 400, 300);
  const tris = A.shadedTriangles(parts, A.linkFrames(model, {}), proj);
  const calls = { fill: 0, styles: new Set() };
  const ctx = {
    set fillStyle(v) { calls.styles.add(v); },
    beginPath() {}, moveTo() {}, lineTo() {}, closePath() {},
    fill() { calls.fill++; },
  };
  A.fillTriangles(ctx, parts, tris);
  assert.equal(calls.fill, tris.count);
  // Red, lifted off black and shaded: only the red channel is lit.
  for (const s of calls.styles) assert.match(s, /^rgb\(\d+,\d+,\d+\)$/);
  assert.ok([...calls.styles].every((s) => {
    const [r, g, b] = s.slice(4, -1).split(",").map(Number);
    return r > g && g === b;
  }));
});
