// Browser tests in headless Chromium (playwright-core, the system's /usr/bin/chromium):
// the live view of `armhil sim piper --ui` follows a MOVE J and injects/clears a fault, and a
// failing scenario's report.html opened from disk shows the failure and replays with the
// slider, and a meshed robot's report draws its links' visuals. Screenshots go to
// $ARMHIL_SCREENSHOTS (default out/web).
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
