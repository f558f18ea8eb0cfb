// Page-building helpers shared by the live page and report.html.
(function (root, factory) {
  const api = factory();
  if (typeof module === "object" && module.exports) module.exports = api;
  else root.ArmHil = Object.assign(root.ArmHil || {}, api);
})(typeof self !== "undefined" ? self : this, function () {
  "use strict";

  // An element with attributes (`text` sets its text) and children (strings become text nodes).
  function el(tag, attrs, children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "text") e.textContent = v; else e.setAttribute(k, v);
    }
    for (const c of children || []) e.appendChild(typeof c === "string" ? document.createTextNode(c) : c);
    return e;
  }

  // Sizes a canvas's drawing buffer to its laid-out size (at least 200 × 100 pixels).
  function fitCanvas(c) {
    const r = c.getBoundingClientRect();
    c.width = Math.max(200, Math.round(r.width));
    c.height = Math.max(100, Math.round(r.height));
  }

  return { el, fitCanvas };
});
