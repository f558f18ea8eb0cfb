// Browser tests in headless Chromium (playwright-core, the system's /usr/bin/chromium):
// the live view of `armhil sim piper --ui` follows a MOVE J and injects/clears a fault; the
// RobStride, Damiao, Realman, humanoid and OpenArm live views show their devices, follow their
// clients (socketcand, TCP) and report faults from the page's desk; a failing scenario's
// report.html opened from disk shows the failure and replays with the slider, and a meshed
// robot's report draws its links' visuals. Screenshots go to $ARMHIL_SCREENSHOTS (default
// out/web).
//
// Needs ARMHIL_BIN (the armhil binary); scripts/ci/web.sh sets it.
const test = require("node:test");
const assert = require("node:assert/strict");
const fs = require("node:fs");
const os = require("node:os");
const path = require("node:path");
const net = require("node:net");
const { spawn, spawnSync } = require("node:child_process");
const { chromium } = require("playwright-core");

const ROOT = path.resolve(__dirname, "..", "..", "..");
const BIN = process.env.ARMHIL_BIN || path.join(ROOT, "target", "debug", "armhil");
const CHROMIUM = process.env.CHROMIUM || "/usr/bin/chromium";
const SHOTS = path.resolve(ROOT, process.env.ARMHIL_SCREENSHOTS || "out/web");
const FIXTURES = path.join(__dirname, "..", "fixtures");
const FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync"];

fs.mkdirSync(SHOTS, { recursive: true });

function freePort() {
  return new Promise((resolve, reject) => {
    const srv = net.createServer();
    srv.listen(0, "127.0.0.1", () => {
      const { port } = srv.address();
      srv.close(() => resolve(port));
    });
    srv.on("error", reject);
  });
}

async function browser() {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "armhil-chromium-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM, headless: true, args: ["--headless", ...FLAGS],
    viewport: { width: 1280, height: 900 },
  });
  return { context, profile };
}

async function until(what, check, timeoutMs) {
  const end = Date.now() + timeoutMs;
  let last;
  while (Date.now() < end) {
    last = await check();
    if (last) return last;
    await new Promise((r) => setTimeout(r, 100));
  }
  throw new Error(`timed out waiting for ${what}`);
}

// `armhil sim ARGS --ui 127.0.0.1:UI` until its web view is up, and a Chromium page on it with
// the first state received; both are stopped when the test ends.
async function livePage(t, args, ui) {
  let err = "";
  const sim = spawn(BIN, ["sim", ...args, "--ui", `127.0.0.1:${ui}`], { stdio: ["ignore", "ignore", "pipe"] });
  sim.stderr.on("data", (d) => { err += d; });
  t.after(() => sim.kill("SIGINT"));
  await until("the web view to start", () => {
    if (sim.exitCode !== null) throw new Error("armhil sim exited: " + err);
    return err.includes("web view on http://");
  }, 30000);
  const { context, profile } = await browser();
  t.after(async () => {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
  });
  const page = await context.newPage();
  await page.goto(`http://127.0.0.1:${ui}/`);
  await page.waitForFunction(() => window.armhilLive && window.armhilLive.ready && window.armhilLive.state, null, { timeout: 10000 });
  return page;
}

// A socketcand client (CAN over TCP, docs/socketcand.md) in raw mode on `channel` of the
// emulator's server: `send(id, bytes)` puts a frame on the bus, `frames` collects what it
// receives ([id hex, data hex] pairs).
async function socketcand(t, port, channel) {
  const sock = net.connect(port, "127.0.0.1");
  t.after(() => sock.destroy());
  let text = "";
  const frames = [];
  sock.on("data", (d) => {
    text += d;
    for (const m of text.matchAll(/< frame ([0-9A-Fa-f]+) [0-9.]+ ([0-9A-Fa-f]*) >/g)) frames.push([m[1], m[2]]);
    text = text.replace(/< frame [^>]* >/g, "");
  });
  const reply = async (what, word) => {
    await until(what, () => text.includes(word), 5000);
    text = text.replace(word, "");
  };
  await reply("the socketcand greeting", "< hi >");
  sock.write(`< open ${channel} >`);
  await reply(`${channel} open`, "< ok >");
  sock.write("< rawmode >");
  await reply("raw mode", "< ok >");
  const hex = (b) => b.toString(16).toUpperCase().padStart(2, "0");
  return {
    frames,
    send(id, bytes) { sock.write(`< send ${id.toString(16).toUpperCase().padStart(3, "0")} ${bytes.length} ${bytes.map(hex).join(" ")} >`); },
  };
}

// Damiao's host commands (docs/protocols/damiao.md): a special command `FF … FF code` (FC
// enable, FD disable, FB clear a latched error), and an MIT command packed over the motor's
// ranges (PMAX rad, VMAX rad/s, TMAX N·m).
const damiao = {
  special: (code) => [0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, code],
  mit({ p, v = 0, kp, kd, t = 0 }, { pmax = 12.5, vmax, tmax }) {
    const u = (x, lo, hi, bits) => Math.trunc(((Math.min(hi, Math.max(lo, x)) - lo) * (2 ** bits - 1)) / (hi - lo));
    const P = u(p, -pmax, pmax, 16), V = u(v, -vmax, vmax, 12), KP = u(kp, 0, 500, 12);
    const KD = u(kd, 0, 5, 12), T = u(t, -tmax, tmax, 12);
    return [P >> 8, P & 0xFF, V >> 4, ((V & 0xF) << 4) | (KP >> 8), KP & 0xFF, KD >> 4, ((KD & 0xF) << 4) | (T >> 8), T & 0xFF];
  },
};

test("the live view follows a MOVE J and injects and clears a fault", async (t) => {
  const can = await freePort();
  const ui = await freePort();
  const page = await livePage(t, ["piper", "--socketcand", `127.0.0.1:${can}`], ui);
  // Before any command the drawn arm is where the emulator's physics has it (a disabled arm
  // sags under gravity).
  const before = await until("the drawn angles", () => page.evaluate(() => {
    const a = window.armhilLive.renderedDeg();
    const s = window.armhilLive.state.physical_deg;
    return a.length === 6 && a.every((v, i) => Math.abs(v - s[i]) < 2) ? a : null;
  }), 5000);
  assert.equal(before.length, 6);

  // Drive the emulator with a scenario over socketcand while the page watches.
  const out = fs.mkdtempSync(path.join(os.tmpdir(), "armhil-live-"));
  const run = spawn(BIN, ["run", "--socketcand", `127.0.0.1:${can}`, "--out", out, path.join(FIXTURES, "live_move_j.yaml")],
    { stdio: ["ignore", "pipe", "pipe"] });
  let runOut = "";
  run.stdout.on("data", (d) => { runOut += d; });
  run.stderr.on("data", (d) => { runOut += d; });
  const target = [40, 50, -60, 20, 30, 45];
  const drawn = await until("the drawn arm to reach the MOVE J target", async () => {
    const a = await page.evaluate(() => window.armhilLive.renderedDeg());
    return a.every((v, i) => Math.abs(v - target[i]) < 1.0) ? a : null;
  }, 30000);
  const runCode = await new Promise((r) => (run.exitCode !== null ? r(run.exitCode) : run.on("exit", r)));
  assert.equal(runCode, 0, runOut);
  // The canvas carries the same angles for anyone reading the DOM.
  const attr = await page.getAttribute("#arm-view", "data-angles");
  const fromDom = attr.split(",").map(Number);
  assert.ok(fromDom.every((v, i) => Math.abs(v - target[i]) < 1.0), `data-angles ${attr} (drawn ${drawn})`);
  // Frame rate over 3 s while the arm holds still (each state message is drawn).
  const count = () => page.evaluate(() => [window.armhilLive.framesDrawn(), window.armhilLive.states, performance.now()]);
  const [f0, s0, t0] = await count();
  await new Promise((r) => setTimeout(r, 3000));
  const [f1, s1, t1] = await count();
  const fps = ((f1 - f0) * 1000) / (t1 - t0);
  const sps = ((s1 - s0) * 1000) / (t1 - t0);
  console.log(`# live view: ${fps.toFixed(1)} frames/s drawn, ${sps.toFixed(1)} state messages/s`);
  // The view must animate (the state stream reaches the canvas); the frame rate itself is a
  // performance figure, printed here and by measure.js, not a pass/fail threshold that a busy
  // CI machine could break.
  assert.ok(fps > 2 && sps > 2, `draws at ${fps} frames/s from ${sps} states/s`);
  const ids = await page.evaluate(() => window.armhilLive.state.bus.ids.map((r) => r[0]));
  assert.ok(ids.includes("2A5"), `bus figures list the joint feedback: ${ids}`);
  await page.screenshot({ path: path.join(SHOTS, "live.png") });

  // A fault from the panel: the emulator reports it in the state it streams.
  await page.selectOption("#fault-kind", "motor_over_temp");
  await page.fill("#fault-arg-joint", "2");
  await page.fill("#fault-arg-temp_c", "95");
  await page.click("#fault-inject");
  await until("the emulator to report the fault", () => page.evaluate(() => {
    const s = window.armhilLive.state;
    return s.faults.some((f) => f.includes("motor_over_temp")) && s.status.driver_faults[1].length > 0
      && Math.abs(s.temperature_c[1] - 95) < 1;
  }), 5000);
  const ack = await page.textContent("#fault-ack");
  assert.match(ack, /injected motor_over_temp/);
  // The text panels refresh at 5 Hz.
  await until("the panel to show the fault", async () => /over_temp/.test(await page.textContent("#status")), 2000);
  await page.screenshot({ path: path.join(SHOTS, "live_fault.png") });
  await page.click("#fault-clear");
  await until("the fault to clear", () => page.evaluate(() => window.armhilLive.state.faults.length === 0
    && window.armhilLive.state.temperature_c[1] < 90), 5000);
  // A malformed command is refused, not fatal.
  const acks = await page.evaluate(() => window.armhilLive.acks.length);
  await page.selectOption("#fault-kind", "external_torque");
  // The field says what the emulator's fault table accepts.
  assert.match(await page.getAttribute("#fault-arg-torque_nm", "title"), /\(-320 … 320\)$/);
  await page.selectOption("#fault-kind", "ntc_over_temp");
  assert.equal(await page.getAttribute("#fault-arg-board", "placeholder"), "main | brake_resistor");
  await page.selectOption("#fault-kind", "external_torque");
  await page.fill("#fault-arg-joint", "9");
  await page.click("#fault-inject");
  const refusal = await until("the refusal", () => page.evaluate((n) => window.armhilLive.acks[n], acks), 5000);
  assert.equal(refusal.ok, false);
  assert.match(refusal.message, /joint/);
  assert.match(await page.textContent("#fault-ack"), /joint/);
});

test("the RobStride live view shows each motor's dial and reports an injected fault", async (t) => {
  const can = await freePort();
  const ui = await freePort();
  const page = await livePage(t, ["robstride", "--socketcand", `127.0.0.1:${can}`, "--motor", "1:RS03", "--motor", "2:RS00"], ui);
  await until("two dials drawn", async () => ((await page.getAttribute("#arm-view", "data-angles")) || "").split(",").length === 2, 5000);
  await page.selectOption("#fault-kind", "under_voltage");
  await page.fill("#fault-arg-motor", "2");
  await page.click("#fault-inject");
  await until("motor 2 to report under_voltage", () => page.evaluate(() => {
    const m = window.armhilLive.state.motors.find((x) => x.id === 2);
    return m.faults.includes("under_voltage") && m.bus_voltage_v < 12;
  }), 5000);
  const m1 = await page.evaluate(() => window.armhilLive.state.motors.find((x) => x.id === 1).faults);
  assert.deepEqual(m1, [], "motor 1 untouched");
  await until("the panel to show the fault", async () => /under_voltage/.test(await page.textContent("#status")), 2000);
  await page.screenshot({ path: path.join(SHOTS, "live_robstride.png") });
  await page.click("#fault-clear");
  await until("the cause to clear", () => page.evaluate(() => window.armhilLive.state.faults.length === 0
    && window.armhilLive.state.motors.find((x) => x.id === 2).bus_voltage_v > 20), 5000);
});

test("the robot live view draws the fallen humanoid at its base pose and cuts a bus from the panel", async (t) => {
  const can = await freePort();
  const ui = await freePort();
  // No gantry (a floating robot hangs on one until enabled by default).
  const page = await livePage(t, ["robot", path.join(ROOT, "robots", "humanoid.yaml"), "--gantry", "off", "--socketcand", `127.0.0.1:${can}`], ui);
  // Never enabled, the humanoid falls: its pelvis ends near the ground, and the page draws
  // the root where the emulator says (the base pose's z is the pelvis height).
  await until("the humanoid to fall", () => page.evaluate(() => window.armhilLive.state.base_position_m[2] < 0.5), 10000);
  const pose = await page.evaluate(() => window.armhilLive.state.base_pose);
  assert.equal(pose.length, 16);
  const strips = await page.evaluate(() => window.armhilLive.hello.strip_names.length);
  assert.equal(strips, 20, "a strip per actuator");
  await page.selectOption("#fault-kind", "bus_lost");
  await page.fill("#fault-arg-bus", "can2");
  await page.click("#fault-inject");
  await until("can2 to be cut off", async () => /bus can2[^]*LOST/.test(await page.textContent("#status")), 3000);
  await page.evaluate(() => window.scrollTo(0, 0));
  await page.screenshot({ path: path.join(SHOTS, "live_robot.png") });
  await page.click("#fault-clear");
  await until("can2 back", () => page.evaluate(() => window.armhilLive.state.faults.length === 0), 3000);
});

test("the Damiao live view shows a dial per motor, follows a socketcand client and reports an injected fault", async (t) => {
  const can = await freePort();
  const ui = await freePort();
  const page = await livePage(t, ["damiao", "--motor", "1:DM4310", "--motor", "2:DM4340", "--socketcand", `127.0.0.1:${can}`], ui);
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  // A dial per motor, named by its ESC_ID; both motors power on disabled, in MIT mode.
  assert.deepEqual(await page.evaluate(() => window.armhilLive.hello.motors), [1, 2]);
  await until("two dials drawn", async () => ((await page.getAttribute("#arm-view", "data-angles")) || "").split(",").length === 2, 5000);
  const motors = await page.evaluate(() => window.armhilLive.state.motors.map((m) => [m.id, m.model, m.mst_id, m.state_name]));
  assert.deepEqual(motors, [[1, "DM4310", 0x11, "disabled"], [2, "DM4340", 0x12, "disabled"]]);
  assert.equal(await page.locator("canvas.plot").count(), 4, "position, velocity, torque and temperature strips");

  // A host on the socketcand bus enables motor 1 and turns it to 1 rad with an MIT command:
  // the motor answers on its feedback id, the page says enabled and its dial follows.
  const host = await socketcand(t, can, "can0");
  host.send(0x001, damiao.special(0xFC));
  await until("motor 1's feedback to the enable", () => host.frames.some(([id]) => id === "011"), 5000);
  await until("the page to say motor 1 enabled", () => page.evaluate(() => {
    const [m1, m2] = window.armhilLive.state.motors;
    return m1.enabled && m1.state_name === "enabled" && !m2.enabled && m2.state_name === "disabled";
  }), 5000);
  // Commanded every 10 ms, as a host's control loop does.
  const turn = damiao.mit({ p: 1.0, kp: 5, kd: 0.3 }, { vmax: 30, tmax: 10 });
  const loop = setInterval(() => host.send(0x001, turn), 10);
  t.after(() => clearInterval(loop));
  const dial = await until("motor 1's dial at 1 rad", async () => {
    const a = await page.evaluate(() => window.armhilLive.renderedDeg());
    return a.length === 2 && Math.abs(a[0] - 57.3) < 3 && Math.abs(a[1]) < 0.5 ? a : null;
  }, 10000);
  const reported = await page.evaluate(() => window.armhilLive.state.motors[0].position_rad);
  assert.ok(Math.abs((reported * 180) / Math.PI - dial[0]) < 2, `dial ${dial[0]}° for ${reported} rad`);
  await until("the panel to show motor 1 enabled", async () => /enabled, mit, state enabled/.test(await page.textContent("#status")), 2000);
  // The bus figures count the host's commands and the motor's answers, about 100 a second
  // each (the timer is late on a busy machine).
  const rate = (id) => page.evaluate((id) => (window.armhilLive.state.bus.ids.find((r) => r[0] === id) || [id, 0, 0])[2], id);
  await until("the bus figures to count the control loop", async () => (await rate("001")) > 30 && (await rate("011")) > 30, 5000);

  // A fault from the page's desk: over-voltage on motor 2, the Damiao table's own.
  const offered = await page.evaluate(() => window.armhilLive.hello.faults.map((f) => f.name));
  for (const f of ["over_voltage", "under_voltage", "mos_over_temperature", "coil_over_temperature", "comm_lost", "overload"]) {
    assert.ok(offered.includes(f), `the fault desk offers ${f}: ${offered}`);
  }
  await page.selectOption("#fault-kind", "over_voltage");
  await page.fill("#fault-arg-motor", "2");
  await page.fill("#fault-arg-voltage_v", "40");
  await page.click("#fault-inject");
  await until("motor 2 to report over_voltage", () => page.evaluate(() => {
    const m = window.armhilLive.state.motors.find((x) => x.id === 2);
    return m.faults.includes("over_voltage") && m.state_name === "over_voltage" && Math.abs(m.bus_voltage_v - 40) < 0.5;
  }), 5000);
  assert.match(await page.textContent("#fault-ack"), /injected over_voltage voltage_v=40 on motor 2/);
  const m1 = await page.evaluate(() => window.armhilLive.state.motors.find((x) => x.id === 1));
  assert.deepEqual([m1.faults, m1.state_name], [[], "enabled"], "motor 1 untouched");
  await until("the panel to show the fault", async () => /state over_voltage[^]*faults: over_voltage/.test(await page.textContent("#status")), 2000);
  assert.match(await page.textContent("#faults-active"), /over_voltage voltage_v=40 on motor 2/);
  await page.screenshot({ path: path.join(SHOTS, "live_damiao.png") });

  // The host stops: the bus goes quiet and its figures fall to 0 within two seconds (they
  // are the last second's), the totals kept.
  clearInterval(loop);
  await until("the quiet bus to read 0 frames/s", async () => (await rate("001")) === 0 && (await rate("011")) === 0
    && (await page.evaluate(() => window.armhilLive.state.bus.load_percent)) === 0, 5000);
  assert.ok(await page.evaluate(() => window.armhilLive.state.bus.ids.find((r) => r[0] === "011")[1] > 30), "totals kept");
  assert.equal(await page.evaluate(() => window.armhilLive.state.motors[0].state_name), "enabled", "the motor holds its last command");

  // Clear removes the cause; the latch stays until the host's clear-error command, as on the
  // motor.
  await page.click("#fault-clear");
  await until("the supply back to normal", () => page.evaluate(() => window.armhilLive.state.faults.length === 0
    && window.armhilLive.state.motors[1].bus_voltage_v < 30), 5000);
  assert.equal(await page.evaluate(() => window.armhilLive.state.motors[1].state_name), "over_voltage", "latched until cleared on the bus");
  host.send(0x002, damiao.special(0xFB));
  await until("motor 2's latch cleared", () => page.evaluate(() => {
    const m = window.armhilLive.state.motors[1];
    return m.faults.length === 0 && m.state_name === "disabled";
  }), 5000);
  assert.deepEqual(errors, []);
});

test("the OpenArm live view draws both 7-DoF arms with grippers on their 16 Damiao motors", async (t) => {
  const can = await freePort();
  const ui = await freePort();
  const page = await livePage(t, ["robot", path.join(ROOT, "robots", "openarm.yaml"), "--socketcand", `127.0.0.1:${can}`], ui);
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  // The model from urdf/openarm.urdf: 16 revolute joints (7 per arm and a gripper each), the
  // fingers mimic their gripper; a strip per actuator.
  const model = await page.evaluate(() => {
    const h = window.armhilLive.hello;
    return { joints: window.ArmHil.armJoints(h.model).map((j) => j.name), strips: h.strip_names, links: h.model.visuals.length };
  });
  const names = (side) => [1, 2, 3, 4, 5, 6, 7].map((i) => `${side}_joint${i}`).concat(`${side}_gripper`);
  assert.equal(model.joints.length, 16);
  assert.deepEqual([...model.joints].sort(), [...names("left"), ...names("right")].sort());
  assert.deepEqual(model.strips, [...names("right"), ...names("left")]);
  // A visual per link: the pedestal, and per arm link0..link7, the hand and two fingers.
  assert.equal(model.links, 23);
  // Drawn where the emulator's physics has it, every link solid (no fallback to sticks).
  const drawn = await until("the drawn angles", () => page.evaluate(() => {
    const a = window.armhilLive.renderedDeg();
    const s = window.armhilLive.state.physical_deg;
    return a.length === 16 && s.length === 16 && a.every((v, i) => Math.abs(v - s[i]) < 2) ? a : null;
  }), 5000);
  assert.equal(drawn.length, 16);
  assert.equal(await page.getAttribute("#arm-view", "data-fallbacks"), "0");
  const triangles = Number(await page.getAttribute("#arm-view", "data-triangles"));
  assert.ok(triangles > 200, `${triangles} triangles drawn`);
  assert.equal(await page.getAttribute("#arm-view", "data-root"), "0.000,0.000,0.000", "a fixed pedestal at the origin");

  // Link poses as the page computes them from the angles it drew (the same kinematics the
  // canvas is drawn with): positions in the world, metres.
  const poses = () => page.evaluate(() => {
    const L = window.armhilLive, A = window.ArmHil, m = L.hello.model;
    const frames = A.linkFrames(m, A.valuesFromDeg(m, L.renderedDeg()), L.state.base_pose);
    return Object.fromEntries(Object.entries(frames).map(([k, f]) => [k, A.origin(f)]));
  });
  const p = await poses();
  const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
  for (const side of ["left", "right"]) {
    for (const link of [0, 1, 2, 3, 4, 5, 6, 7].map((i) => `${side}_link${i}`).concat(`${side}_hand`, `${side}_finger1`, `${side}_finger2`)) {
      assert.ok(p[link] && p[link].every(Number.isFinite), `${link} posed: ${p[link]}`);
    }
    // Each arm is a chain of its own: the hand is well away from the shoulder, above the floor.
    assert.ok(dist(p[`${side}_link0`], p[`${side}_hand`]) > 0.3, `${side} arm's reach ${dist(p[`${side}_link0`], p[`${side}_hand`])}`);
    assert.ok(p[`${side}_hand`][2] > 0.05, `${side} hand above the floor: ${p[`${side}_hand`]}`);
  }
  // The two arms stand apart, mounted either side of the pedestal (right at -y, left at +y, at
  // the URDF's 0.698 m), and nothing overlaps: every link of one arm is away from the other's.
  assert.ok(Math.abs(p.right_link0[1] + 0.031) < 1e-3 && Math.abs(p.left_link0[1] - 0.031) < 1e-3, `bases ${p.right_link0} ${p.left_link0}`);
  assert.ok(Math.abs(p.right_link0[2] - 0.698) < 1e-3 && Math.abs(p.left_link0[2] - 0.698) < 1e-3);
  for (const i of [2, 3, 4, 5, 6, 7]) {
    assert.ok(p[`right_link${i}`][1] < -0.1 && p[`left_link${i}`][1] > 0.1, `link${i}: right ${p[`right_link${i}`]}, left ${p[`left_link${i}`]}`);
  }
  assert.ok(p.right_hand[1] < -0.1 && p.left_hand[1] > 0.1 && dist(p.right_hand, p.left_hand) > 0.2, `hands ${p.right_hand} ${p.left_hand}`);

  // The panel: a row per joint with its Damiao motor (model, id, bus), and the fault desk
  // offers the Damiao table.
  await until("the actuator panel", async () => /left_gripper/.test(await page.textContent("#status")), 2000);
  const rows = await page.evaluate(() => window.armhilLive.state.panel.map((r) => r[0]));
  const models = { joint1: "DM8009", joint2: "DM8009", joint3: "DM4340", joint4: "DM4340", joint5: "DM4310", joint6: "DM4310", joint7: "DM4310", gripper: "DM4310" };
  for (const [bus, side] of [["can0", "right"], ["can1", "left"]]) {
    Object.entries(models).forEach(([j, m], i) => {
      const row = `${side}_${j} (damiao ${m} id ${i + 1} on ${bus})`;
      assert.ok(rows.includes(row), `panel lists ${row}: ${rows}`);
    });
  }
  const faults = await page.evaluate(() => window.armhilLive.hello.faults.map((f) => f.name));
  for (const f of ["over_voltage", "mos_over_temperature", "coil_over_temperature", "comm_lost", "bus_lost", "external_torque"]) {
    assert.ok(faults.includes(f), `the fault desk offers ${f}: ${faults}`);
  }

  // A host on can1 enables the left elbow (left_joint4, id 4) and bends it to 1.2 rad with an
  // MIT command: the left arm is drawn bent, the right one keeps hanging (each arm's joints
  // reach their own chain; the left shoulder, free, swings under the bent arm's weight).
  const host = await socketcand(t, can, "can1");
  host.send(0x004, damiao.special(0xFC));
  await until("the elbow's feedback on can1", () => host.frames.some(([id]) => id === "014"), 5000);
  host.send(0x004, damiao.mit({ p: 1.2, kp: 40, kd: 1.5 }, { vmax: 10, tmax: 28 }));
  const elbow = model.joints.indexOf("left_joint4");
  await until("the left elbow drawn bent", () => page.evaluate((k) => {
    const a = window.armhilLive.renderedDeg();
    const s = window.armhilLive.state.physical_deg;
    return Math.abs(a[k] - 68.8) < 6 && Math.abs(a[k] - s[k]) < 2;
  }, elbow), 10000);
  const q = await poses();
  assert.ok(dist(q.left_hand, p.left_hand) > 0.1, `the left hand moved: ${p.left_hand} → ${q.left_hand}`);
  assert.ok(dist(q.right_hand, p.right_hand) < 0.05, `the right hand stayed: ${p.right_hand} → ${q.right_hand}`);
  // The panel says which joint a host enabled: the left elbow, and no other.
  const states = await page.evaluate(() => window.armhilLive.state.panel.filter((r) => /_joint|_gripper/.test(r[0])).map((r) => [r[0].split(" ")[0], r[1].split(",")[0]]));
  assert.equal(states.length, 16, `${states}`);
  for (const [joint, state] of states) {
    assert.equal(state, joint === "left_joint4" ? "enabled" : "disabled", `${joint}: ${state}`);
  }
  // The enable and its answer are counted on can1.
  const ids = await page.evaluate(() => window.armhilLive.state.bus.ids.map((r) => r[0]));
  assert.ok(ids.includes("can1 004") && ids.includes("can1 014"), `bus figures: ${ids}`);

  // A Damiao fault on one joint shows in its row.
  await page.selectOption("#fault-kind", "mos_over_temperature");
  await page.fill("#fault-arg-joint", "right_joint2");
  await page.click("#fault-inject");
  await until("right_joint2 to report it", async () => /right_joint2 \(damiao DM8009 id 2 on can0\)disabled, mit, [\d.]+ °C, faults: mos_over_temperature/.test(await page.textContent("#status")), 5000);
  await page.evaluate(() => window.scrollTo(0, 0));
  await page.screenshot({ path: path.join(SHOTS, "live_openarm.png") });
  await page.click("#fault-clear");
  await until("the fault's cause cleared", () => page.evaluate(() => window.armhilLive.state.faults.length === 0), 5000);
  assert.deepEqual(errors, []);
});

test("the Realman live view follows a movej, lists its TCP client and reports a joint error", async (t) => {
  const tcp = await freePort();
  const ui = await freePort();
  const page = await livePage(t, ["realman", "--port", String(tcp)], ui);
  // A client of the JSON protocol: joints in 0.001°.
  const client = net.connect(tcp, "127.0.0.1");
  t.after(() => client.destroy());
  await new Promise((r) => client.once("connect", r));
  const target = [30, 20, -40, 10, 25, -15];
  client.write(JSON.stringify({ command: "movej", joint: target.map((d) => d * 1000), v: 50, r: 0, trajectory_connect: 0 }) + "\r\n");
  await until("the drawn arm to reach the movej target", async () => {
    const a = await page.evaluate(() => window.armhilLive.renderedDeg());
    return a.length === 6 && a.every((v, i) => Math.abs(v - target[i]) < 1.0);
  }, 20000);
  const clients = await page.evaluate(() => window.armhilLive.state.clients);
  assert.equal(clients.length, 1, `one TCP client: ${clients}`);
  await page.selectOption("#fault-kind", "joint_error");
  await page.fill("#fault-arg-joint", "3");
  await page.fill("#fault-arg-code", "8");
  await page.click("#fault-inject");
  await until("the controller to report the joint error", () => page.evaluate(() => window.armhilLive.state.errors.length > 0
    && window.armhilLive.state.faults.includes("joint_error")), 5000);
  await until("the panel to show it", async () => /0x/.test(await page.textContent("#status")), 2000);
  await page.screenshot({ path: path.join(SHOTS, "live_realman.png") });
});

test("a robot's report replays the whole humanoid at its base pose as it falls", async (t) => {
  const out = fs.mkdtempSync(path.join(os.tmpdir(), "armhil-report-"));
  // Stands, then every actuator is stopped and it falls (its joints keep answering).
  const scenario = path.join(ROOT, "scenarios", "robot", "humanoid_estop.yaml");
  const r = spawnSync(BIN, ["run", "--out", out, scenario], { encoding: "utf8" });
  assert.equal(r.status, 0, "the scenario passes: " + r.stdout + r.stderr);
  const { context, profile } = await browser();
  t.after(async () => {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
    fs.rmSync(out, { recursive: true, force: true });
  });
  const page = await context.newPage();
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  await page.goto("file://" + path.join(out, "humanoid_estop", "report.html"));
  await page.waitForFunction(() => document.getElementById("arm-view") && document.getElementById("arm-view").dataset.root);
  // The whole URDF is drawn: every one of the 20 actuated joints.
  assert.equal(await page.evaluate(() => window.ArmHil.armJoints(window.armhilReport.data.model).length), 20);
  const root = async () => (await page.getAttribute("#arm-view", "data-root")).split(",").map(Number);
  // Standing at power-on: the pelvis 0.81 m up, where the trace's base columns say.
  await page.fill("#time-slider", "0");
  await until("the replay at 0 s", async () => Math.abs((await root())[2] - 0.81) < 0.002, 3000);
  // At the end it lies where the emulator left it: the drawn root is the traced base pose.
  const end = await page.evaluate(() => window.armhilReport.data.duration);
  await page.fill("#time-slider", String(end));
  const traced = await page.evaluate((t) => {
    const d = window.armhilReport.data;
    const i = window.ArmHil.nearestIndex(d.trace.t, t);
    const value = (n) => { const c = d.trace.columns.find((x) => x.name === n); return c.values[i] * c.quantum; };
    return ["base_x_m", "base_y_m", "base_height_m"].map(value);
  }, end);
  assert.ok(traced[2] < 0.5, `fallen: ${traced}`);
  await until("the replay at the end", async () => (await root()).every((v, k) => Math.abs(v - traced[k]) < 0.002), 3000);
  assert.deepEqual(errors, []);
  await page.screenshot({ path: path.join(SHOTS, "report_robot.png"), fullPage: false });
});

test("a meshed robot's report draws its links' visual geometry and says which link it could not", async (t) => {
  const out = fs.mkdtempSync(path.join(os.tmpdir(), "armhil-report-"));
  // fixtures/meshed/: STL, OBJ and COLLADA meshes, primitives, and a tool whose mesh is missing.
  const r = spawnSync(BIN, ["run", "--out", out, path.join(FIXTURES, "meshed_move.yaml")], { encoding: "utf8" });
  assert.equal(r.status, 0, "the scenario passes: " + r.stdout + r.stderr);
  const { context, profile } = await browser();
  t.after(async () => {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
    fs.rmSync(out, { recursive: true, force: true });
  });
  const page = await context.newPage();
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  await page.goto("file://" + path.join(out, "meshed_move", "report.html"));
  await page.waitForFunction(() => document.getElementById("arm-view") && document.getElementById("arm-view").dataset.frames);
  const model = await page.evaluate(() => window.armhilReport.data.model);
  assert.deepEqual(model.meshes.map((m) => m.file), ["package://meshed_fixture/meshes/base.stl", "meshes/upper.obj", "meshes/wrist.dae"]);
  assert.deepEqual(model.fallbacks.map((f) => f.link), ["tool"]);
  // At the end the arm is drawn where the trace has it: shoulder near 0.8 rad, elbow 0.7.
  const end = await page.evaluate(() => window.armhilReport.data.duration);
  await page.fill("#time-slider", String(end));
  const traced = await page.evaluate((t) => {
    const d = window.armhilReport.data;
    const i = window.ArmHil.nearestIndex(d.trace.t, t);
    const deg = (n) => { const c = d.trace.columns.find((x) => x.name === n); return (c.values[i] * c.quantum * 180) / Math.PI; };
    return [deg("shoulder_rad"), deg("elbow_rad")];
  }, end);
  assert.ok(Math.abs(traced[0] - 45.8) < 4 && Math.abs(traced[1] - 40.1) < 4, `traced ${traced}`);
  await until("the replay at the end", async () => {
    const a = (await page.getAttribute("#arm-view", "data-angles")).split(",").map(Number);
    return a.every((v, k) => Math.abs(v - traced[k]) < 0.5);
  }, 3000);
  // Filled triangles are drawn (back faces left out), and the missing mesh is said.
  const triangles = Number(await page.getAttribute("#arm-view", "data-triangles"));
  assert.ok(triangles > 30 && triangles < 400, `${triangles} triangles drawn`);
  assert.equal(await page.getAttribute("#arm-view", "data-fallbacks"), "1");
  assert.match(await page.getAttribute("#arm-view", "title"), /tool: `meshes\/gripper_missing\.stl` is not found/);
  // The base's steel box is drawn, shaded, where the canvas shows the arm's foot.
  const lit = await page.evaluate(() => {
    const c = document.getElementById("arm-view");
    const px = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let orange = 0;
    for (let i = 0; i < px.length; i += 4) if (px[i] > 150 && px[i + 1] > 60 && px[i + 1] < 140 && px[i + 2] < 60) orange++;
    return orange;
  });
  assert.ok(lit > 200, `the orange upper arm covers ${lit} pixels`);
  assert.deepEqual(errors, []);
  await page.screenshot({ path: path.join(SHOTS, "report_meshed.png"), fullPage: false });
});

test("a failing scenario's report.html shows the failure and replays with the slider", async (t) => {
  const out = fs.mkdtempSync(path.join(os.tmpdir(), "armhil-report-"));
  const r = spawnSync(BIN, ["run", "--out", out, path.join(FIXTURES, "report_failing.yaml")], { encoding: "utf8" });
  assert.equal(r.status, 1, "the scenario fails: " + r.stdout + r.stderr);
  const report = path.join(out, "report_failing", "report.html");
  assert.ok(fs.existsSync(path.join(out, "index.html")), "index.html per suite");

  const { context, profile } = await browser();
  t.after(async () => {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
  });
  const page = await context.newPage();
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  await page.goto("file://" + report);
  const failure = await page.textContent("#first-failure");
  assert.match(failure, /Step 3 `wait_until` \(line \d+\) timed out/);
  assert.match(failure, /expected:/);
  await page.waitForFunction(() => document.querySelectorAll("canvas.plot").length >= 4 && document.getElementById("arm-view").dataset.frames);
  // The cursor starts at the failure; move the slider to the start, then to the middle.
  const duration = await page.evaluate(() => window.armhilReport.data.duration);
  await page.fill("#time-slider", "0");
  await until("the replay at 0 s", async () => (await page.getAttribute("#arm-view", "data-angles")).split(",").every((a) => Math.abs(Number(a)) < 0.5), 3000);
  const mid = (duration / 2).toFixed(3);
  await page.fill("#time-slider", mid);
  assert.equal(await page.evaluate(() => window.armhilReport.cursor()), Number(mid));
  const angles = await until("the replay to move", async () => {
    const a = (await page.getAttribute("#arm-view", "data-angles")).split(",").map(Number);
    return a.some((v) => Math.abs(v) > 5) ? a : null;
  }, 3000);
  // The drawn pose is the traced one at the cursor.
  const traced = await page.evaluate((t) => {
    const d = window.armhilReport.data;
    const i = window.ArmHil.nearestIndex(d.trace.t, t);
    const c = d.trace.columns.find((x) => x.name === "j1_deg");
    return c.values[i] * c.quantum;
  }, Number(mid));
  assert.ok(Math.abs(angles[0] - traced) < 0.01, `J1 ${angles[0]} vs traced ${traced}`);
  assert.equal(await page.locator("#frames tbody tr").count() > 100, true, "decoded frames listed");
  assert.match(await page.textContent("#frames"), /JointFeedback12/);
  assert.deepEqual(errors, []);
  await page.screenshot({ path: path.join(SHOTS, "report.png"), fullPage: false });
  await page.locator("#plots").screenshot({ path: path.join(SHOTS, "report_plots.png") });
});
