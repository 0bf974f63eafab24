// ballpass report: zoom, pan and read values off the figures marked
// interactive. Self-contained: reads the data embedded in the page
// (script.bp-data), fetches nothing. Without scripts the static SVG stays.
(function () {
  "use strict";
  var NS = "http://www.w3.org/2000/svg";
  var SUP = "⁰¹²³⁴⁵⁶⁷⁸⁹";

  function el(name, attrs, parent) {
    var e = document.createElementNS(NS, name);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }

  function pow10(n) {
    var s = String(Math.abs(n)), out = "10" + (n < 0 ? "⁻" : "");
    for (var i = 0; i < s.length; i++) out += SUP[+s[i]];
    return out;
  }

  function niceStep(span, target) {
    var raw = span / Math.max(target, 1);
    var mag = Math.pow(10, Math.floor(Math.log10(raw)));
    var m = raw / mag;
    return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 2.5 ? 2.5 : m <= 5 ? 5 : 10) * mag;
  }

  function fmtNum(v, step) {
    if (v === 0) return "0";
    var a = Math.abs(v);
    if (a >= 1e5 || a < 1e-3) return v.toExponential(Math.max(0, Math.min(6,
      Math.ceil(Math.log10(a) - Math.log10(step))))).replace("-", "−");
    var d = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    if (Math.abs(step / Math.pow(10, Math.floor(Math.log10(step))) - 2.5) < 1e-9) d += 1;
    return v.toFixed(d).replace("-", "−");
  }

  // A value for the readout: 4 significant digits.
  function fmtValue(v) {
    if (!isFinite(v)) return "–";
    if (v === 0) return "0";
    var a = Math.abs(v);
    var s = (a >= 1e5 || a < 1e-3) ? v.toExponential(3) : v.toPrecision(4);
    return s.replace("-", "−");
  }

  // Ticks in axis space (log10 of the value on a log axis): [pos, label].
  function ticks(lo, hi, log, target) {
    var out = [], k, v;
    if (log && hi - lo >= 2) {
      var every = Math.max(1, Math.ceil((Math.floor(hi) - Math.ceil(lo) + 1) / target));
      for (k = Math.ceil(lo); k <= Math.floor(hi); k++)
        if (k % every === 0) out.push([k, pow10(k)]);
      return out;
    }
    if (log) {
      var mults = [[1, 2, 5], [1, 2, 3, 4, 5, 6, 7, 8, 9]];
      for (var m = 0; m < mults.length; m++) {
        out = [];
        for (k = Math.floor(lo); k <= Math.ceil(hi); k++)
          for (var j = 0; j < mults[m].length; j++) {
            v = k + Math.log10(mults[m][j]);
            if (v >= lo - 1e-12 && v <= hi + 1e-12)
              out.push([v, fmtNum(mults[m][j] * Math.pow(10, k), Math.pow(10, Math.min(k, 0)))]);
          }
        if (out.length >= 3) return out;
      }
      var a = Math.pow(10, lo), b = Math.pow(10, hi), st = niceStep(b - a, target);
      for (k = Math.ceil(a / st - 1e-9); k <= Math.floor(b / st + 1e-9); k++)
        if (k * st > 0) out.push([Math.log10(k * st), fmtNum(k * st, st)]);
      return out;
    }
    var step = niceStep(hi - lo, target);
    for (k = Math.ceil(lo / step - 1e-9); k <= Math.floor(hi / step + 1e-9); k++) {
      v = k * step;
      if (Math.abs(v) < step * 1e-9) v = 0;
      out.push([v, fmtNum(v, step)]);
    }
    return out;
  }

  function Panel(fig, svg, spec, index) {
    this.fig = fig;
    this.svg = svg;
    this.s = spec;
    this.index = index;
    this.lo = spec.x.lo;
    this.hi = spec.x.hi;
    var p = spec.plot;
    this.l = p[0]; this.t = p[1]; this.r = p[2]; this.b = p[3];
    this.g = el("g", { "class": "bp-live", "data-panel": index }, svg);
    this.view = el("g", {}, this.g);
    this.hover = el("g", { "pointer-events": "none" }, this.g);
    var clipId = fig.id + "-clip-" + index;
    var defs = el("defs", {}, this.g);
    var cp = el("clipPath", { id: clipId }, defs);
    el("rect", { x: this.l, y: this.t, width: this.r - this.l, height: this.b - this.t }, cp);
    this.clip = "url(#" + clipId + ")";
    this.capture = el("rect", {
      x: this.l, y: this.t, width: this.r - this.l, height: this.b - this.t,
      fill: "transparent", "class": "bp-capture"
    }, this.g);
    this.setView();
  }

  Panel.prototype.setView = function () {
    var x = this.s.x;
    var a = x.log ? Math.pow(10, this.lo) : this.lo, b = x.log ? Math.pow(10, this.hi) : this.hi;
    this.g.setAttribute("data-x", a + " " + b);
  };

  Panel.prototype.px = function (v) { return this.l + (v - this.lo) / (this.hi - this.lo) * (this.r - this.l); };
  Panel.prototype.xAt = function (px) { return this.lo + (px - this.l) / (this.r - this.l) * (this.hi - this.lo); };

  // The y range over the visible x range (the initial one when fixed).
  Panel.prototype.yRange = function () {
    var y = this.s.y;
    if (y.fixed || this.zoomed === false) return [y.lo, y.hi];
    var lo = Infinity, hi = -Infinity, self = this;
    this.s.series.forEach(function (se) {
      se.segs.forEach(function (sg) {
        for (var i = 0; i < sg[0].length; i++) {
          var xv = sg[0][i];
          if (xv < self.lo || xv > self.hi) continue;
          if (sg[1][i] < lo) lo = sg[1][i];
          if (sg[1][i] > hi) hi = sg[1][i];
        }
      });
    });
    if (!(hi > lo)) return [y.lo, y.hi];
    var d = (hi - lo) * 0.05;
    return [Math.max(y.lo, lo - d), Math.min(y.hi, hi + d)];
  };

  Panel.prototype.draw = function () {
    var v = this.view;
    while (v.firstChild) v.removeChild(v.firstChild);
    this.zoomed = !(this.lo <= this.s.x.lo && this.hi >= this.s.x.hi);
    this.setView();
    if (!this.zoomed) return; // the static drawing shows the initial view
    var yr = this.yRange(), ylo = yr[0], yhi = yr[1], self = this;
    var py = function (val) { return self.b - (val - ylo) / (yhi - ylo) * (self.b - self.t); };
    var bandX = this.fig.bands[0], bandY = this.fig.bands[1];
    el("rect", { x: this.l - bandY, y: this.t - 8, width: bandY, height: this.b - this.t + 16, fill: "#fff" }, v);
    el("rect", { x: this.l - 30, y: this.b, width: this.r - this.l + 60, height: bandX, fill: "#fff" }, v);
    el("rect", { x: this.l, y: this.t, width: this.r - this.l, height: this.b - this.t, fill: "#fff" }, v);
    var font = this.fig.font;
    ticks(this.lo, this.hi, this.s.x.log, 8).forEach(function (t) {
      var x = self.px(t[0]);
      el("line", { x1: x, x2: x, y1: self.t, y2: self.b, stroke: "#d7d7d7" }, v);
      el("line", { x1: x, x2: x, y1: self.b, y2: self.b + 5, stroke: "#000" }, v);
      var tx = el("text", { x: x, y: self.b + 8, dy: "0.76em", "text-anchor": "middle", "font-size": font, "font-family": "DejaVu Sans, Verdana, sans-serif" }, v);
      tx.textContent = t[1];
    });
    ticks(ylo, yhi, this.s.y.log, 6).forEach(function (t) {
      var y = py(t[0]);
      el("line", { x1: self.l, x2: self.r, y1: y, y2: y, stroke: "#d7d7d7" }, v);
      el("line", { x1: self.l - 5, x2: self.l, y1: y, y2: y, stroke: "#000" }, v);
      var tx = el("text", { x: self.l - 8, y: y, dy: "0.5ex", "text-anchor": "end", "font-size": font, "font-family": "DejaVu Sans, Verdana, sans-serif" }, v);
      tx.textContent = t[1];
    });
    var data = el("g", { "clip-path": this.clip }, v);
    this.s.series.forEach(function (se) {
      se.segs.forEach(function (sg) {
        var pts = [];
        for (var i = 0; i < sg[0].length; i++) {
          var xv = sg[0][i];
          if (xv < self.lo - (self.hi - self.lo) || xv > self.hi + (self.hi - self.lo)) continue;
          pts.push(self.px(xv).toFixed(1) + "," + py(sg[1][i]).toFixed(1));
        }
        if (!pts.length) return;
        if (se.kind === "points") {
          pts.forEach(function (p) {
            var c = p.split(",");
            el("circle", { cx: c[0], cy: c[1], r: 3, fill: se.color }, data);
          });
        } else {
          el("polyline", {
            points: pts.join(" "), fill: "none", stroke: se.color, "stroke-width": se.w,
            "stroke-dasharray": se.dash ? "7 4" : "none"
          }, data);
        }
      });
    });
    var markerColor = { red: "#d62728", black: "#000", grey: "#969696" };
    var lastRight = -Infinity;
    (this.s.v || []).slice().sort(function (a, b) { return a[0] - b[0]; }).forEach(function (m) {
      if (m[0] < self.lo || m[0] > self.hi) return;
      var x = self.px(m[0]);
      el("line", { x1: x, x2: x, y1: self.t, y2: self.b, stroke: markerColor[m[2]], "stroke-width": 1.5, "stroke-dasharray": m[2] === "grey" ? "none" : "8 5" }, v);
      var w = m[1] ? m[1].length * (font - 2) * 0.6 + 8 : 0;
      if (m[1] && x >= lastRight && x + w <= self.r) {
        lastRight = x + w;
        var tx = el("text", { x: x + 4, y: self.t + 3, dy: "0.76em", fill: markerColor[m[2]], "font-size": font - 2, "font-family": "DejaVu Sans, Verdana, sans-serif" }, v);
        tx.textContent = m[1];
      }
    });
    (this.s.h || []).forEach(function (m) {
      if (m[0] < ylo || m[0] > yhi) return;
      var y = py(m[0]);
      el("line", { x1: self.l, x2: self.r, y1: y, y2: y, stroke: markerColor[m[2]], "stroke-width": 1.5, "stroke-dasharray": m[2] === "grey" ? "none" : "8 5" }, v);
    });
    el("rect", { x: this.l, y: this.t, width: this.r - this.l, height: this.b - this.t, fill: "none", stroke: "#000" }, v);
    this.yNow = [ylo, yhi];
  };

  // Values of every series at the data x nearest to the cursor.
  Panel.prototype.readout = function (px) {
    var h = this.hover;
    while (h.firstChild) h.removeChild(h.firstChild);
    if (px === null || px < this.l || px > this.r) return;
    var x = this.xAt(px), self = this, lines = [];
    var val = function (v, log) { return fmtValue(log ? Math.pow(10, v) : v); };
    lines.push(this.s.x.title + " " + val(x, this.s.x.log));
    this.s.series.forEach(function (se) {
      var best = null, bd = Infinity;
      se.segs.forEach(function (sg) {
        var xs = sg[0], lo = 0, hi = xs.length - 1;
        if (hi < 0) return;
        while (hi - lo > 1) { var mid = (lo + hi) >> 1; if (xs[mid] < x) lo = mid; else hi = mid; }
        [lo, hi].forEach(function (i) {
          var d = Math.abs(xs[i] - x);
          if (d < bd) { bd = d; best = sg[1][i]; }
        });
      });
      if (best !== null && bd <= (self.hi - self.lo) * 0.02)
        lines.push((se.name || self.s.y.title) + ": " + val(best, self.s.y.log));
    });
    el("line", { x1: px, x2: px, y1: this.t, y2: this.b, stroke: "#555", "stroke-width": 1, "stroke-dasharray": "2 3" }, h);
    var fs = this.fig.font - 2, w = 0;
    lines.forEach(function (l) { w = Math.max(w, l.length * fs * 0.6); });
    var bx = px + 10 + w + 12 > this.r ? px - 10 - w - 12 : px + 10;
    el("rect", { x: bx, y: this.t + 6, width: w + 12, height: lines.length * (fs + 4) + 8, fill: "#fff", "fill-opacity": 0.92, stroke: "#888" }, h);
    lines.forEach(function (l, i) {
      var tx = el("text", { x: bx + 6, y: self.t + 10 + i * (fs + 4), dy: "0.76em", "font-size": fs, "font-family": "DejaVu Sans, Verdana, sans-serif", "class": "bp-readout" }, h);
      tx.textContent = l;
    });
  };

  function Figure(node, spec) {
    this.node = node;
    this.id = node.id;
    this.font = spec.font;
    this.bands = spec.bands;
    var svg = node.querySelector("svg");
    var self = this;
    this.svg = svg;
    this.panels = spec.panels.map(function (p, i) { return new Panel(self, svg, p, i); });
    this.linked = spec.linked;
    this.active = false;
    this.drag = null;
    svg.addEventListener("mousedown", function (e) { self.down(e); });
    svg.addEventListener("mousemove", function (e) { self.move(e); });
    svg.addEventListener("mouseleave", function () { self.panels.forEach(function (p) { p.readout(null); }); });
    window.addEventListener("mouseup", function (e) { self.up(e); });
    svg.addEventListener("dblclick", function (e) { self.reset(); e.preventDefault(); });
    svg.addEventListener("wheel", function (e) { self.wheel(e); }, { passive: false });
    var bar = document.createElement("div");
    bar.className = "bp-tools";
    [["−", "zoom out", function () { self.zoomAll(1.6); }],
     ["+", "zoom in", function () { self.zoomAll(1 / 1.6); }],
     ["◀", "pan left", function () { self.panAll(-0.25); }],
     ["▶", "pan right", function () { self.panAll(0.25); }],
     ["reset", "show everything", function () { self.reset(); }]].forEach(function (b) {
      var btn = document.createElement("button");
      btn.type = "button";
      btn.textContent = b[0];
      btn.title = b[1];
      btn.addEventListener("click", b[2]);
      bar.appendChild(btn);
    });
    var hint = document.createElement("span");
    hint.className = "bp-hint";
    hint.textContent = "Drag across a plot to zoom, shift-drag to pan; click it, then scroll to zoom; double-click to reset. Values under the cursor.";
    bar.appendChild(hint);
    svg.parentNode.insertBefore(bar, svg.nextSibling);
  }

  // The panel under a mouse event, and the cursor in SVG user units.
  Figure.prototype.locate = function (e) {
    var pt = this.svg.createSVGPoint();
    pt.x = e.clientX; pt.y = e.clientY;
    var m = this.svg.getScreenCTM();
    if (!m) return null;
    var u = pt.matrixTransform(m.inverse());
    for (var i = 0; i < this.panels.length; i++) {
      var p = this.panels[i];
      if (u.x >= p.l && u.x <= p.r && u.y >= p.t && u.y <= p.b) return { panel: p, x: u.x, y: u.y };
    }
    return { panel: null, x: u.x, y: u.y };
  };

  Figure.prototype.targets = function (p) { return this.linked ? this.panels : [p]; };

  Figure.prototype.setRange = function (p, lo, hi) {
    var x0 = p.s.x.lo, x1 = p.s.x.hi, w = hi - lo, full = x1 - x0;
    if (w >= full || !(w > 0)) { lo = x0; hi = x1; }
    else {
      w = Math.max(w, full * 1e-5);
      if (lo < x0) { lo = x0; hi = x0 + w; }
      if (hi > x1) { hi = x1; lo = x1 - w; }
    }
    this.targets(p).forEach(function (q) { q.lo = lo; q.hi = hi; q.draw(); });
  };

  Figure.prototype.zoomAt = function (p, c, f) { this.setRange(p, c - (c - p.lo) * f, c + (p.hi - c) * f); };
  Figure.prototype.zoomAll = function (f) {
    var self = this;
    (this.linked ? [this.panels[0]] : this.panels).forEach(function (p) { self.zoomAt(p, (p.lo + p.hi) / 2, f); });
  };
  Figure.prototype.panAll = function (frac) {
    var self = this;
    (this.linked ? [this.panels[0]] : this.panels).forEach(function (p) {
      var d = (p.hi - p.lo) * frac;
      self.setRange(p, p.lo + d, p.hi + d);
    });
  };
  Figure.prototype.reset = function () {
    var self = this;
    this.panels.forEach(function (p) { self.setRange(p, p.s.x.lo, p.s.x.hi); });
  };

  Figure.prototype.wheel = function (e) {
    if (!this.active) return; // scrolling the page stays scrolling
    var at = this.locate(e);
    if (!at || !at.panel) return;
    e.preventDefault();
    this.zoomAt(at.panel, at.panel.xAt(at.x), Math.exp(Math.max(-3, Math.min(3, e.deltaY * 0.002))));
  };

  Figure.prototype.down = function (e) {
    var at = this.locate(e);
    activate(this);
    if (!at || !at.panel || e.button !== 0) return;
    e.preventDefault();
    this.drag = { panel: at.panel, x: at.x, pan: e.shiftKey, lo: at.panel.lo, hi: at.panel.hi, box: null };
  };

  Figure.prototype.move = function (e) {
    var at = this.locate(e), d = this.drag;
    if (d) {
      var p = d.panel;
      if (d.pan) {
        var dx = (at.x - d.x) / (p.r - p.l) * (d.hi - d.lo);
        this.setRange(p, d.lo - dx, d.hi - dx);
      } else {
        if (d.box) d.box.parentNode.removeChild(d.box);
        var a = Math.max(p.l, Math.min(d.x, at.x)), b = Math.min(p.r, Math.max(d.x, at.x));
        d.box = el("rect", { x: a, y: p.t, width: b - a, height: p.b - p.t, fill: "#1f77b4", "fill-opacity": 0.15, "pointer-events": "none" }, p.hover);
      }
      return;
    }
    this.panels.forEach(function (p) { p.readout(at && at.panel === p ? at.x : null); });
  };

  Figure.prototype.up = function (e) {
    var d = this.drag;
    if (!d) return;
    this.drag = null;
    if (d.box && d.box.parentNode) d.box.parentNode.removeChild(d.box);
    if (d.pan) return;
    var at = this.locate(e), p = d.panel;
    if (!at || Math.abs(at.x - d.x) < 4) return;
    var a = p.xAt(Math.max(p.l, Math.min(d.x, at.x))), b = p.xAt(Math.min(p.r, Math.max(d.x, at.x)));
    this.setRange(p, a, b);
  };

  var figures = [];
  function activate(f) {
    figures.forEach(function (g) {
      g.active = g === f;
      g.node.classList.toggle("bp-active", g.active);
    });
  }
  document.addEventListener("mousedown", function (e) {
    if (!e.target.closest || !e.target.closest("figure.bp-interactive")) activate(null);
  });

  function start() {
    var blocks = document.querySelectorAll("script.bp-data");
    for (var i = 0; i < blocks.length; i++) {
      var spec = JSON.parse(blocks[i].textContent);
      var node = document.getElementById(spec.figure);
      if (node && node.querySelector("svg")) {
        node.classList.add("bp-interactive");
        figures.push(new Figure(node, spec));
      }
    }
    document.documentElement.setAttribute("data-live-figures", String(figures.length));
  }
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();
