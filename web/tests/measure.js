// Closing figures of the live view: page weight, frames drawn per second in headless
// Chromium, and the emulator's extra CPU with one page open (from /proc, Linux only).
//
//   ARMHIL_BIN=target/debug/armhil node web/tests/measure.js [seconds]
const fs = require("node:fs");
const os = require("node:os");
const path = require("node:path");
const net = require("node:net");
const { spawn } = require("node:child_process");
const { chromium } = require("playwright-core");

const BIN = process.env.ARMHIL_BIN || "target/debug/armhil";
const SECONDS = Number(process.argv[2] || 10);
const TICK = 100; // USER_HZ on Linux

function freePort() {
  return new Promise((resolve) => {
    const s = net.createServer().listen(0, "127.0.0.1", () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

// utime + stime of a process, seconds.
function cpu(pid) {
  const f = fs.readFileSync(`/proc/${pid}/stat`, "utf8");
  const fields = f.slice(f.lastIndexOf(")") + 2).split(" ");
  return (Number(fields[11]) + Number(fields[12])) / TICK;
}

async function cpuOver(pid, seconds) {
  const c0 = cpu(pid), t0 = Date.now();
  await new Promise((r) => setTimeout(r, seconds * 1000));
  return (100 * (cpu(pid) - c0)) / ((Date.now() - t0) / 1000);
}

(async () => {
  const can = await freePort(), ui = await freePort();
  const sim = spawn(BIN, ["sim", "piper", "--socketcand", `127.0.0.1:${can}`, "--ui", `127.0.0.1:${ui}`], { stdio: ["ignore", "ignore", "pipe"] });
  let err = "";
  sim.stderr.on("data", (d) => { err += d; });
  while (!err.includes("web view on")) await new Promise((r) => setTimeout(r, 100));
  const page0 = await fetch(`http://127.0.0.1:${ui}/`).then((r) => r.text());
  console.log(`page weight: ${(Buffer.byteLength(page0) / 1024).toFixed(1)} KB (one request, no other assets)`);
  await new Promise((r) => setTimeout(r, 2000));
  const idle = await cpuOver(sim.pid, SECONDS);
  console.log(`emulator CPU, no page: ${idle.toFixed(1)} % of one core`);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "armhil-measure-"));
  const ctx = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM || "/usr/bin/chromium", headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync"],
    viewport: { width: 1280, height: 900 },
  });
  const page = await ctx.newPage();
  await page.goto(`http://127.0.0.1:${ui}/`);
  await page.waitForFunction(() => window.armhilLive && window.armhilLive.state);
  await new Promise((r) => setTimeout(r, 2000));
  const f0 = await page.evaluate(() => [window.armhilLive.framesDrawn(), window.armhilLive.states, performance.now()]);
  const open = await cpuOver(sim.pid, SECONDS);
  const f1 = await page.evaluate(() => [window.armhilLive.framesDrawn(), window.armhilLive.states, performance.now()]);
  const secs = (f1[2] - f0[2]) / 1000;
  console.log(`emulator CPU, one page open: ${open.toFixed(1)} % (extra ${(open - idle).toFixed(1)} %)`);
  console.log(`live view: ${((f1[0] - f0[0]) / secs).toFixed(1)} frames/s drawn, ${((f1[1] - f0[1]) / secs).toFixed(1)} state messages/s (emulator feedback at 200 Hz)`);
  await ctx.close();
  sim.kill("SIGINT");
})().catch((e) => { console.error(e); process.exit(1); });
