// The live page's WebSocket URL: on a server that requires a token (`armhil sim --ui` bound to
// a non-loopback address), the page must pass the token of its own URL on, or the server
// refuses the socket with 403. live.js runs here against a stand-in DOM that accepts anything.
const test = require("node:test");
const assert = require("node:assert/strict");
const fs = require("node:fs");
const path = require("node:path");
const vm = require("node:vm");

const SOURCE = fs.readFileSync(path.join(__dirname, "../../live/live.js"), "utf8");

// Any property, call or assignment works and yields another stand-in.
function standIn() {
  return new Proxy(function () {}, {
    get: (target, key) => (key === Symbol.toPrimitive ? () => "" : standIn()),
    set: () => true,
    apply: () => standIn(),
  });
}

function socketUrl(search) {
  const opened = [];
  const context = {
    window: { ArmHil: { el: () => standIn(), fitCanvas: () => {} } },
    document: standIn(),
    location: { protocol: "http:", host: "192.168.1.5:8000", search },
    URLSearchParams,
    WebSocket: class { constructor(url) { opened.push(url); } },
    setInterval: () => 0,
    setTimeout: () => 0,
    performance: { now: () => 0 },
  };
  vm.runInNewContext(SOURCE, context);
  assert.equal(opened.length, 1, "the page opens one WebSocket at start");
  return opened[0];
}

test("the page's token goes on to its WebSocket", () => {
  assert.equal(socketUrl("?token=3f9c0a"), "ws://192.168.1.5:8000/ws?token=3f9c0a");
  assert.equal(socketUrl("?x=1&token=a%2Bb"), "ws://192.168.1.5:8000/ws?token=a%2Bb");
});

test("without a token the WebSocket URL is bare", () => {
  assert.equal(socketUrl(""), "ws://192.168.1.5:8000/ws");
});
