// Forward kinematics of the drawn arm against the emulator's own (fixture written by the Rust
// test `the_page_fk_fixture_is_current`), plus the transforms it is built from.
const test = require("node:test");
const assert = require("node:assert/strict");
const path = require("node:path");
const fs = require("node:fs");
const A = require("../../common/arm3d.js");

const close = (a, b, tol, what) => {
  for (let i = 0; i < 3; i++) assert.ok(Math.abs(a[i] - b[i]) < tol, `${what}: ${a} vs ${b}`);
};

test("rpy is fixed-axis X then Y then Z", () => {
  const m = A.fromXyzRpy([1, 2, 3], [0, 0, Math.PI / 2]);
  close(A.apply(m, [1, 0, 0]), [1, 3, 3], 1e-12, "yaw turns x into y");
  const p = A.fromXyzRpy([0, 0, 0], [Math.PI / 2, 0, Math.PI / 2]);
  // Roll first (y -> z), then yaw (x -> y): y ends on z.
  close(A.apply(p, [0, 1, 0]), [0, 0, 1], 1e-12, "roll then yaw");
});

test("a two-link planar arm reaches where trigonometry says", () => {
  const model = {
    joints: [
      { name: "a", type: "revolute", parent: "base", child: "l1", xyz: [0, 0, 0.1], rpy: [0, 0, 0], axis: [0, 0, 1] },
      { name: "b", type: "revolute", parent: "l1", child: "l2", xyz: [0.3, 0, 0], rpy: [0, 0, 0], axis: [0, 0, 1] },
      { name: "tip", type: "fixed", parent: "l2", child: "tip", xyz: [0.2, 0, 0], rpy: [0, 0, 0], axis: [1, 0, 0] },
    ],
  };
  const frames = A.linkFrames(model, A.valuesFromDeg(model, [90, -90]));
  close(A.origin(frames.l2), [0, 0.3, 0.1], 1e-12, "elbow");
  close(A.origin(frames.tip), [0.2, 0.3, 0.1], 1e-12, "tip");
  assert.deepEqual(A.armJoints(model).map((j) => j.name), ["a", "b"]);
});

test("a floating robot's links move with its root pose", () => {
  const model = {
    joints: [
      { name: "hip", type: "revolute", parent: "pelvis", child: "thigh", xyz: [0, 0, -0.1], rpy: [0, 0, 0], axis: [0, 1, 0] },
      { name: "knee", type: "revolute", parent: "thigh", child: "shin", xyz: [0, 0, -0.4], rpy: [0, 0, 0], axis: [0, 1, 0] },
    ],
  };
  // The pelvis lying on its side at 0.2 m: rotated +90 degrees about x, raised 0.2 m.
  const base = [1, 0, 0, 0.5, 0, 0, -1, 0, 0, 1, 0, 0.2, 0, 0, 0, 1];
  const frames = A.linkFrames(model, {}, base);
  close(A.origin(frames.pelvis), [0.5, 0, 0.2], 1e-12, "the root where the base says");
  // Down the leg (-z in the pelvis) is +y in the world once the pelvis is on its side.
  close(A.origin(frames.shin), [0.5, 0.5, 0.2], 1e-12, "the knee follows the root");
  // Without a base pose the root stays at the origin (arms on a fixed base).
  close(A.origin(A.linkFrames(model, {}).shin), [0, 0, -0.5], 1e-12, "fixed base");
});

test("a report's pose document places a robot from its trace columns", () => {
  const model = {
    joints: [
      { name: "hip", type: "revolute", parent: "pelvis", child: "thigh", xyz: [0, 0, -0.1], rpy: [0, 0, 0], axis: [0, 1, 0] },
      { name: "knee", type: "revolute", parent: "thigh", child: "shin", xyz: [0, 0, -0.4], rpy: [0, 0, 0], axis: [0, 1, 0] },
    ],
  };
  const pose = {
    // The knee's actuator is mounted backwards and zeroed at 0.1 rad.
    joints: [
      { column: "hip_rad", joint: "hip", direction: 1, offset: 0 },
      { column: "knee_rad", joint: "knee", direction: -1, offset: 0.1 },
    ],
    base: { position: ["bx", "by", "bz"], rpy: ["roll", "pitch", "yaw"] },
  };
  const trace = { hip_rad: 0.5, knee_rad: 0.2, bx: 1, bz: 0.3, pitch: -Math.PI / 2 };
  const read = (name) => (name in trace ? trace[name] : null);
  const p = A.poseFromColumns(model, pose, read);
  assert.ok(Math.abs(p.deg[0] - (0.5 * 180) / Math.PI) < 1e-9, `hip ${p.deg}`);
  assert.ok(Math.abs(p.deg[1] - (-0.1 * 180) / Math.PI) < 1e-9, `knee -0.2 + 0.1 rad: ${p.deg}`);
  // Pitched -90° (no y column: 0): the body's up (z) points to -x, so down the leg is +x.
  const frames = A.linkFrames(model, { hip: 0, knee: 0 }, p.base);
  close(A.origin(frames.pelvis), [1, 0, 0.3], 1e-12, "the root from the base columns");
  close(A.origin(frames.thigh), [1.1, 0, 0.3], 1e-12, "the hip below the pelvis, lying down");
  // A joint not traced yet is unknown (NaN), and a fixed base gives no root pose.
  const early = A.poseFromColumns(model, { joints: pose.joints, base: null }, () => null);
  assert.ok(early.deg.every((d) => Number.isNaN(d)));
  assert.equal(early.base, undefined);
});

test("mimic joints follow their leader", () => {
  const model = {
    joints: [
      { name: "f1", type: "prismatic", parent: "base", child: "a", xyz: [0, 0, 0], rpy: [0, 0, 0], axis: [0, 1, 0] },
      { name: "f2", type: "prismatic", parent: "base", child: "b", xyz: [0, 0, 0], rpy: [0, 0, 0], axis: [0, 1, 0], mimic: { joint: "f1", multiplier: -1, offset: 0 } },
    ],
  };
  const frames = A.linkFrames(model, A.valuesFromDeg(model, [], 0.06));
  close(A.origin(frames.a), [0, 0.03, 0], 1e-12, "finger 1");
  close(A.origin(frames.b), [0, -0.03, 0], 1e-12, "finger 2");
});

test("Piper links match the emulator's kinematics", () => {
  const file = path.join(__dirname, "..", "fixtures", "piper_fk.json");
  const { model, cases } = JSON.parse(fs.readFileSync(file, "utf8"));
  assert.equal(A.armJoints(model).length, 6);
  for (const c of cases) {
    const frames = A.linkFrames(model, A.valuesFromDeg(model, c.deg, c.gripper_m));
    for (const [link, want] of Object.entries(c.links)) {
      assert.ok(frames[link], `link ${link} drawn`);
      close(A.origin(frames[link]), want, 1e-6, `${link} at ${c.deg}`);
    }
  }
});

test("the projection puts the target in the middle and nearer points lower in depth", () => {
  const cam = { yaw: 0.3, pitch: 0.4, distance: 2, target: [0, 0, 0.2] };
  const proj = A.projector(cam, 400, 300);
  const c = proj([0, 0, 0.2]);
  assert.ok(Math.abs(c[0] - 200) < 1e-9 && Math.abs(c[1] - 150) < 1e-9);
  assert.ok(Math.abs(c[2] - 2) < 1e-9);
  const up = proj([0, 0, 0.5]);
  assert.ok(up[1] < c[1], "higher in the world is higher on screen");
});
