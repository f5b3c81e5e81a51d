"""The report's style sheet and script, inlined into every report.html (no file is fetched).

The script draws the error-against-run-time chart as inline SVG from the JSON the page carries
(``<script id="rr-data" type="application/json">``): one path per trained node over Δn = 1..50,
the Pareto front, the original's time and the four selections. Hovering a point shows its node,
Δn, predicted error and time; clicking it (or a marked source line) shows the node's details.
"""

CSS = r"""
:root { --fg: #1d2330; --muted: #5d6678; --line: #d9dde6; --accent: #b3122e; --bg: #fbfbfd; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: var(--fg);
       background: var(--bg); margin: 0; }
header { background: #1d2330; color: #fff; padding: 16px 28px; }
header h1 { margin: 0; font-size: 20px; }
header p { margin: 4px 0 0; color: #c9cfdb; }
main { padding: 8px 28px 40px; max-width: 1280px; }
h2 { font-size: 17px; border-bottom: 1px solid var(--line); padding-bottom: 4px; margin-top: 28px; }
table { border-collapse: collapse; font-size: 13px; }
td, th { border-bottom: 1px solid var(--line); padding: 3px 10px 3px 0; text-align: left; vertical-align: top; }
th { color: var(--muted); font-weight: 600; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
.summary { display: grid; grid-template-columns: repeat(auto-fill, minmax(190px, 1fr)); gap: 8px; }
.summary div { background: #fff; border: 1px solid var(--line); border-radius: 6px; padding: 8px 10px; }
.summary b { display: block; font-size: 18px; }
.summary span { color: var(--muted); font-size: 12px; }
.chartrow { display: flex; gap: 18px; align-items: flex-start; flex-wrap: wrap; }
#chart { background: #fff; border: 1px solid var(--line); border-radius: 6px; }
#chart .pt { cursor: pointer; }
#chart .pt:hover, #chart .pt.sel { stroke: #000; stroke-width: 1.5; }
#chart text { font-size: 11px; fill: var(--muted); }
#yscale { margin: 0 0 6px; }
#yscale button { font-size: 12px; }
#chart .sellabel { fill: var(--accent); font-weight: 600; }
#tooltip { position: fixed; pointer-events: none; background: rgba(20, 24, 33, .92); color: #fff;
           padding: 5px 8px; border-radius: 4px; font-size: 12px; display: none; z-index: 10; white-space: nowrap; }
#details { flex: 1; min-width: 320px; background: #fff; border: 1px solid var(--line); border-radius: 6px;
           padding: 10px 14px; }
#details h3 { margin: 0 0 6px; font-size: 15px; }
#details code, .src code { font: 12px/1.35 ui-monospace, "DejaVu Sans Mono", Menlo, monospace; }
.muted { color: var(--muted); }
.warn { color: #b3261e; font-weight: 600; }
.src { background: #fff; border: 1px solid var(--line); border-radius: 6px; padding: 6px 0; overflow-x: auto;
       max-height: 520px; overflow-y: auto; }
.src div { white-space: pre; padding: 0 10px 0 0; }
.src .ln { display: inline-block; width: 44px; text-align: right; color: #9aa1b0; padding-right: 10px;
           user-select: none; }
.src .mk { display: inline-block; width: 64px; font-size: 11px; color: #333; text-align: right; padding-right: 8px; }
.src div.has { cursor: pointer; }
.src div.focus { outline: 2px solid var(--accent); outline-offset: -2px; }
.legend span { display: inline-block; padding: 0 8px; margin-right: 4px; border-radius: 3px; font-size: 12px; }
.sel { background: #fff; border: 1px solid var(--line); border-radius: 6px; padding: 10px 14px; margin: 12px 0; }
.sel h3 { margin: 0 0 6px; font-size: 15px; }
.shots { display: flex; gap: 10px; flex-wrap: wrap; margin-top: 8px; }
.shots figure { margin: 0; }
.shots img { display: block; image-rendering: pixelated; border: 1px solid var(--line); }
.shots figcaption { font-size: 11px; color: var(--muted); max-width: 240px; }
.plots img { max-width: 100%; border: 1px solid var(--line); background: #fff; margin: 6px 12px 6px 0; }
/* a level's "Use it" (rrcache.report.next_steps) and the summary's notices */
.next { border-top: 1px solid var(--line); margin-top: 10px; }
.next h4 { margin: 8px 0 4px; font-size: 14px; }
.next table.files td:first-child, .next table.cmds td:first-child { white-space: nowrap; }
.snippet { background: #f4f5f8; border: 1px solid var(--line); border-radius: 4px; padding: 8px 10px;
           overflow-x: auto; font-size: 12px; line-height: 1.35; }
.notices { margin: 8px 0 0; padding-left: 20px; }
"""

JS = r"""
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("rr-data").textContent);
  var NS = "http://www.w3.org/2000/svg";
  var W = 720, H = 440, M = {l: 64, r: 18, t: 14, b: 44};
  var svg = document.getElementById("chart");
  var tip = document.getElementById("tooltip");
  var details = document.getElementById("details");

  function el(name, attrs, parent) {
    var e = document.createElementNS(NS, name);
    for (var k in attrs) { e.setAttribute(k, attrs[k]); }
    if (parent) { parent.appendChild(e); }
    return e;
  }
  function fmt(v, digits) {
    if (v === null || v === undefined) { return "–"; }
    if (v !== 0 && (Math.abs(v) < 1e-3 || Math.abs(v) >= 1e5)) { return v.toExponential(digits || 3); }
    var t = v.toPrecision(digits || 4);
    return t.indexOf(".") >= 0 ? t.replace(/0+$/, "").replace(/\.$/, "") : t;
  }
  function esc(s) {
    return String(s).replace(/[&<>"]/g, function (c) { return {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"}[c]; });
  }
  function ticks(lo, hi, n) {
    var step = Math.pow(10, Math.floor(Math.log10((hi - lo) / n)));
    var err = (hi - lo) / n / step;
    step *= err >= 7.5 ? 10 : err >= 3.5 ? 5 : err >= 1.5 ? 2 : 1;
    var out = [];
    for (var v = Math.ceil(lo / step) * step; v <= hi + 1e-12; v += step) { out.push(v); }
    return out;
  }

  // ---- scales
  var xs = [data.original_ms], ys = [0];
  data.nodes.forEach(function (n) { n.points.forEach(function (p) { xs.push(p[1]); ys.push(p[2]); }); });
  (data.amortized || []).forEach(function (p) { xs.push(p[0]); ys.push(p[1]); });
  var x0 = Math.min.apply(null, xs), x1 = Math.max.apply(null, xs);
  var pad = (x1 - x0) * 0.04 || x0 * 0.1 || 1;
  x0 = Math.max(0, x0 - pad); x1 += pad;
  var y1 = Math.max.apply(null, ys) * 1.06 || 1e-3;
  var pos = ys.filter(function (v) { return v > 0; });
  var ylo = Math.max(pos.length ? Math.min.apply(null, pos) / 1.5 : 0, y1 / 1e4);
  var logY = true;
  function X(v) { return M.l + (v - x0) / (x1 - x0) * (W - M.l - M.r); }
  function Y(v) {
    if (!logY) { return H - M.b - v / y1 * (H - M.t - M.b); }
    var f = (Math.log(Math.max(v, ylo)) - Math.log(ylo)) / (Math.log(y1) - Math.log(ylo));
    return H - M.b - f * (H - M.t - M.b);
  }
  function logTicks() {
    var out = [];
    for (var e = Math.floor(Math.log10(ylo)); e <= Math.ceil(Math.log10(y1)); e++) {
      [1, 2, 5].forEach(function (m) { var v = m * Math.pow(10, e); if (v >= ylo && v <= y1) { out.push(v); } });
    }
    return out;
  }
  var layer;
  function draw() {
    while (svg.firstChild) { svg.removeChild(svg.firstChild); }

    // ---- axes
    var axes = el("g", {}, svg);
    ticks(x0, x1, 6).forEach(function (v) {
      el("line", {x1: X(v), x2: X(v), y1: M.t, y2: H - M.b, stroke: "#eceef3"}, axes);
      el("text", {x: X(v), y: H - M.b + 16, "text-anchor": "middle"}, axes).textContent = fmt(v, 3);
    });
    (logY ? logTicks() : ticks(0, y1, 6)).forEach(function (v) {
      el("line", {x1: M.l, x2: W - M.r, y1: Y(v), y2: Y(v), stroke: "#eceef3"}, axes);
      el("text", {x: M.l - 6, y: Y(v) + 4, "text-anchor": "end"}, axes).textContent =
          v !== 0 && v < 1e-3 ? v.toExponential(0) : fmt(v, 2);
    });
    el("rect", {x: M.l, y: M.t, width: W - M.l - M.r, height: H - M.t - M.b, fill: "none", stroke: "#b8bfcc"}, axes);
    el("text", {x: (M.l + W - M.r) / 2, y: H - 8, "text-anchor": "middle"}, axes).textContent =
        "ms per frame (predicted)";
    var yl = el("text", {x: 14, y: (M.t + H - M.b) / 2, "text-anchor": "middle",
                         transform: "rotate(-90 14 " + (M.t + H - M.b) / 2 + ")"}, axes);
    yl.textContent = "mean RGB L2 error (predicted" + (logY ? ", log scale)" : ")");

    // ---- original, nodes, front, selections
    el("line", {x1: X(data.original_ms), x2: X(data.original_ms), y1: M.t, y2: H - M.b, stroke: "#777",
                "stroke-dasharray": "5 4"}, svg);
    el("text", {x: X(data.original_ms) + 4, y: M.t + 12}, svg).textContent =
        "original " + fmt(data.original_ms, 3) + " ms";
    layer = el("g", {id: "points"}, svg);
    data.nodes.forEach(function (n, i) {
      var hue = Math.round(260 - 220 * i / Math.max(1, data.nodes.length - 1));
      n.color = "hsl(" + hue + ",65%,45%)";
      el("polyline", {points: n.points.filter(function (p) { return !logY || p[2] > 0; }).map(function (p) { return X(p[1]) + "," + Y(p[2]); }).join(" "),
                      fill: "none", stroke: n.color, "stroke-width": 1, "stroke-opacity": 0.6}, layer);
      n.points.forEach(function (p, j) {
      if (logY && p[2] <= 0) { return; }
        var trained = data.details[n.id] && data.details[n.id].runs.some(function (r) { return r.period === p[0]; });
        el("circle", {cx: X(p[1]), cy: Y(p[2]), r: trained ? 3.6 : 2.2, fill: n.color, "class": "pt",
                      "data-node": i, "data-point": j}, layer);
      });
    });
    // amortized estimators' options (m of N terms per frame, blend λ): orange crosses
    (data.amortized || []).forEach(function (p) {
      if (logY && p[1] <= 0) { return; }
      var x = X(p[0]), y = Y(p[1]);
      var mark = el("path", {d: "M" + (x - 3) + "," + (y - 3) + "L" + (x + 3) + "," + (y + 3) + "M" + (x - 3) + "," +
                             (y + 3) + "L" + (x + 3) + "," + (y - 3), stroke: "#e07b00", "stroke-width": 1.4,
                             "class": "amort"}, layer);
      el("title", {}, mark).textContent = p[2] + ": error " + fmt(p[1], 3) + ", " + fmt(p[0], 3) + " ms";
    });
    el("polyline", {points: data.front.map(function (p) { return X(p[0]) + "," + Y(p[1]); }).join(" "),
                    fill: "none", stroke: "#000", "stroke-width": 2.2, "stroke-opacity": 0.45,
                    "pointer-events": "none", id: "front"}, svg);
    var seen = {};
    data.selections.forEach(function (s) { s.labelEl = null; });
    data.selections.forEach(function (s) {
      if (s.ms === null || s.error === null) { return; }
      var key = s.node + ":" + s.period;
      var k = seen[key] = (seen[key] || []);
      k.push(s.label);
      if (k.length > 1) { return; }
      el("rect", {x: X(s.ms) - 5, y: Y(s.error) - 5, width: 10, height: 10, fill: "none", stroke: "#b3122e",
                  "stroke-width": 1.8, "pointer-events": "none", "class": "selmark"}, svg);
      s.labelEl = el("text", {x: X(s.ms) + 8, y: Y(s.error) - 6, "class": "sellabel"}, svg);
    });
    data.selections.forEach(function (s) {
      if (s.labelEl) {
        var sel = seen[s.node + ":" + s.period];
        s.labelEl.textContent = sel.join(",") + (s.node ? "" : " (original)");
      }
    });
  }
  draw();
  document.querySelectorAll('#yscale button').forEach(function (b) {
    b.addEventListener('click', function () { logY = b.getAttribute('data-scale') === 'log'; draw(); });
  });

  // ---- hover and click
  function pointOf(target) {
    var n = data.nodes[+target.getAttribute("data-node")];
    return {node: n, p: n.points[+target.getAttribute("data-point")]};
  }
  svg.addEventListener("mousemove", function (ev) {
    if (!ev.target.classList.contains("pt")) { tip.style.display = "none"; return; }
    var q = pointOf(ev.target);
    tip.innerHTML = "<b>" + esc(q.node.id) + "</b> Δn = " + q.p[0] + "<br>error " + fmt(q.p[2]) +
                    " · " + fmt(q.p[1]) + " ms · " + fmt(data.original_ms / q.p[1], 3) + "×";
    tip.style.display = "block";
    var left = ev.clientX + 14;
    if (left + tip.offsetWidth > window.innerWidth - 8) { left = ev.clientX - tip.offsetWidth - 14; }
    tip.style.left = left + "px";
    tip.style.top = (ev.clientY + 12) + "px";
  });
  svg.addEventListener("mouseleave", function () { tip.style.display = "none"; });
  svg.addEventListener("click", function (ev) {
    if (!ev.target.classList.contains("pt")) { return; }
    var prev = svg.querySelector(".pt.sel");
    if (prev) { prev.classList.remove("sel"); }
    ev.target.classList.add("sel");
    var q = pointOf(ev.target);
    show(q.node.id, q.p[0]);
  });

  function show(id, period) {
    var d = data.details[id];
    if (!d) { return; }
    var line = data.source[d.line - 1];
    var src = line === undefined ? "" : esc(line.slice(0, d.column - 1)) + "<mark>" + esc(line.slice(d.column - 1)) + "</mark>";
    var rows = d.runs.map(function (r) {
      return "<tr><td class=num>" + r.period + "</td><td class=num>" + fmt(r.error) + "</td><td class=num>" +
             fmt(r.predicted_error) + "</td><td class=num>" + fmt(r.hit_rate, 3) + "</td><td class=num>" +
             fmt(r.psnr, 3) + "</td><td class=num>" + fmt(r.predicted_ms) + "</td></tr>";
    }).join("");
    details.innerHTML =
      "<h3>" + esc(d.id) + " <span class=muted>" + esc(d.type) + " at line " + d.line + ", column " + d.column +
      (period ? " · Δn = " + period : "") + "</span></h3>" +
      (d.note ? "<p class=muted>" + esc(d.note) + "</p>" : "") +
      "<div class=muted>source</div><code class=srcline>" + src + "</code>" +
      "<div class=muted>value (after inlining)</div><code>" + esc(d.text) + "</code>" +
      "<div class=muted>call chain</div><code>" + esc(d.call_chain.join(" › ") || "main") + "</code>" +
      "<table style='margin-top:6px'><tr><th>α</th><td class=num>" + fmt(d.alpha) + "</td><th>λ</th><td class=num>" +
      fmt(d.lam) + "</td><th>fit</th><td>" + esc(d.error_quality || "–") + ", R² " + fmt(d.error_r2, 3) + "</td></tr>" +
      "<tr><th>t_hit</th><td class=num>" + fmt(d.t_hit) + "</td><th>t_miss</th><td class=num>" + fmt(d.t_miss) +
      "</td><th>time fit</th><td>" + esc(d.perf_quality || "–") + "</td></tr>" +
      "<tr><th>cost</th><td class=num>" + d.cost + "</td><th>best</th><td class=num>" + fmt(d.benefit, 3) +
      "×</td><th></th><td></td></tr></table>" +
      "<div class=muted style='margin-top:6px'>measured error runs</div>" +
      "<table class=runs><tr><th class=num>Δn</th><th class=num>error</th><th class=num>model</th>" +
      "<th class=num>hit rate</th><th class=num>PSNR</th><th class=num>ms (model)</th></tr>" + rows + "</table>";
    details.setAttribute("data-node", d.id);
    var prev = document.querySelector(".src div.focus");
    if (prev) { prev.classList.remove("focus"); }
    var target = document.getElementById("L" + d.line);
    if (target) { target.classList.add("focus"); }
  }
  document.querySelectorAll(".src div.has").forEach(function (row) {
    row.addEventListener("click", function () { show(row.getAttribute("data-node")); });
  });
  window.rrShowNode = show;
})();
"""
