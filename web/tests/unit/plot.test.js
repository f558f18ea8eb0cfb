// Plot scaling: ticks, bounds, nearest sample and zoom.
const test = require("node:test");
const assert = require("node:assert/strict");
const P = require("../../common/plot.js");

test("ticks are round numbers covering the range", () => {
  assert.deepEqual(P.niceTicks(0, 10, 5), [0, 2, 4, 6, 8, 10]);
  assert.deepEqual(P.niceTicks(-0.33, 0.71, 10), [-0.3, -0.2, -0.1, 0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]);
  assert.deepEqual(P.niceTicks(-0.33, 0.71, 5), [-0.2, 0, 0.2, 0.4, 0.6]);
  const t = P.niceTicks(123.4, 5678.9, 4);
  assert.deepEqual(t, [2000, 4000], "2.8 intervals of 2000 are nearer to 4 than 5.6 of 1000");
  assert.ok(t.every((v) => v >= 123.4 && v <= 5678.9));
  assert.deepEqual(P.niceTicks(1, 1, 5), [1], "empty range");
});

test("bounds skip gaps, add a margin and never collapse", () => {
  assert.deepEqual(P.valueBounds([[0, null, 10]], 0, 2), [-0.5, 10.5]);
  assert.deepEqual(P.valueBounds([[3, 3]], 0, 1), [2, 4]);
  assert.deepEqual(P.valueBounds([[null]], 0, 0), [-1, 1]);
  // Only the visible samples count.
  assert.deepEqual(P.valueBounds([[100, 0, 10, 100]], 1, 2), [-0.5, 10.5]);
});

test("the nearest sample is found by bisection", () => {
  const ts = [0, 0.01, 0.02, 0.05, 0.1];
  assert.equal(P.nearestIndex(ts, -1), 0);
  assert.equal(P.nearestIndex(ts, 0.014), 1);
  assert.equal(P.nearestIndex(ts, 0.016), 2);
  assert.equal(P.nearestIndex(ts, 0.08), 4);
  assert.equal(P.nearestIndex([], 1), -1);
});

test("zoom keeps the point under the mouse and stays inside the data", () => {
  assert.deepEqual(P.zoomRange(0, 10, 5, 0.5, 0, 10), [2.5, 7.5]);
  const [a, b] = P.zoomRange(0, 10, 0, 0.5, 0, 10);
  assert.deepEqual([a, b], [0, 5]);
  assert.deepEqual(P.zoomRange(2, 4, 3, 10, 0, 10), [0, 10], "zooming out past the data shows it all");
  assert.deepEqual(P.zoomRange(8, 12, 0, 1, 0, 10), [6, 10], "a pan past the end is pushed back");
});
