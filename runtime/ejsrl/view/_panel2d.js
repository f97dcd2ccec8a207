/* ejsrl 2D panel engine (window.__ejs2d): draws drawing panels and plots on a canvas.
 *
 * Installed once per page by the first panel's HTML (see _panel2d.py); every panel's
 * HTML calls __ejs2d.mount(img) and every frame's HTML queues itself in window.__ejs2dq.
 * The server decides everything (ranges, ticks, colours, text); this only draws what a
 * frame says, in CSS pixels scaled by devicePixelRatio (crisp at any zoom), and reports
 * pointer and keyboard events through the panel's hidden text input. Text is drawn with
 * fillText: nothing in a frame can become markup.
 */
(function () {
  if (window.__ejs2d) { window.__ejs2d.drain(); return; }
  var KEYS = /^([a-zA-Z0-9]|ArrowUp|ArrowDown|ArrowLeft|ArrowRight| |Enter|Escape|\+|-)$/;
  var SEND_MS = 60;      // at most one message per 60 ms (viser's sender keeps one per 50 ms)
  var MAX_QUEUE = 24;    // events a message carries at most
  var HIT_PX = 10;       // how near (CSS px) a pointer must be to grab a point
  var E = { panels: {}, draws: 0 };
  window.__ejs2d = E;

  function panel(id) {
    var p = E.panels[id];
    if (!p) {
      p = E.panels[id] = { id: id, canvas: null, frame: null, queue: [], seq: 0, lastSend: 0,
        timer: null, drag: null, map: null, pending: false, drawn: 0, hits: [] };
    }
    return p;
  }

  // -- frames from the server ----------------------------------------------------------------
  E.drain = function () {
    var q = window.__ejs2dq || [];
    window.__ejs2dq = [];
    for (var i = 0; i < q.length; i++) {
      try { E.frame(q[i]); } catch (err) { console.error("ejs2d frame", err); }
    }
  };
  E.frame = function (img) {
    var s = img.previousElementSibling;
    if (!s || !s.isConnected) return;
    var p = panel(s.getAttribute("data-ejs2d-frame"));
    var text = s.textContent;
    if (text === p.text) return;
    p.text = text;
    p.frame = JSON.parse(text);
    p.decoded = null;
    request(p);
  };
  function request(p) {
    if (p.pending) return;
    p.pending = true;
    requestAnimationFrame(function () { p.pending = false; draw(p); });
  }

  // -- the canvas ------------------------------------------------------------------------------
  E.mount = function (img) {
    var root = img.previousElementSibling;
    if (!root) return;
    var p = panel(root.getAttribute("data-ejs2d"));
    var c = root.querySelector("canvas");
    p.root = root;
    p.input = root.getAttribute("data-ev");
    p.only = root.getAttribute("data-keys") ? JSON.parse(root.getAttribute("data-keys")) : null;
    p.auto = root.getAttribute("data-auto-height") ? root.getAttribute("data-auto-height").split(",").map(Number) : null;
    if (p.auto && !p.autoResize) {   // the window's height bounds the panel's: follow it
      p.autoResize = true;
      window.addEventListener("resize", function () { p.autoFrozen = false; p.autoSets = []; request(p); });
    }
    if (p.canvas === c) return;
    p.canvas = c;
    c.addEventListener("pointerdown", function (e) { down(p, e); });
    c.addEventListener("pointermove", function (e) { move(p, e); });
    c.addEventListener("pointerup", function (e) { up(p, e, false); });
    c.addEventListener("pointercancel", function (e) { up(p, e, true); });
    c.addEventListener("keydown", function (e) { key(p, e, "down"); });
    c.addEventListener("keyup", function (e) { key(p, e, "up"); });
    c.addEventListener("blur", function () { p.held = {}; });
    p.size = null;
    // the canvas's CSS size, kept from the observer: reading it in every draw forced a layout
    if (window.ResizeObserver) new ResizeObserver(function (es) {
      var r = es[es.length - 1].contentRect;
      p.size = [r.width, r.height];
      request(p);
    }).observe(c);
    if (root.getAttribute("data-scene-keys")) sceneKeys(p);
    request(p);
  };

  // keys of the 3D view: reported while the 3D view has the focus (it was clicked last)
  function scene3d(t) { return !!(t && t.tagName === "CANVAS" && !t.classList.contains("ejs2d-c") && !t.classList.contains("ejs2d-k")); }
  function sceneKeys(p) {
    if (p.sceneKeys) return;
    p.sceneKeys = true;
    window.addEventListener("pointerdown", function (e) { p.sceneFocus = scene3d(e.target); }, true);
    var on = function (phase) {
      return function (e) {
        var t = e.target;
        if (p.sceneFocus && (!t || t === document.body || t === document.documentElement || scene3d(t))) key(p, e, phase);
      };
    };
    window.addEventListener("keydown", on("down"), true);
    window.addEventListener("keyup", on("up"), true);
  }

  function b64(s) {
    var bin = atob(s), n = bin.length, u = new Uint8Array(n);
    for (var i = 0; i < n; i++) u[i] = bin.charCodeAt(i);
    return new Float32Array(u.buffer, 0, n >> 2);
  }
  function xyOf(p, item, k) {
    if (!p.decoded) p.decoded = [];
    var d = p.decoded[k];
    if (!d) d = p.decoded[k] = item.xy ? b64(item.xy) : new Float32Array(0);
    return d;
  }

  function fin(v) { return typeof v === "number" && isFinite(v); }

  // world -> CSS px: the plot area, the (grown) bounds and the axis kinds
  function layout(p, f, w, h, ctx) {
    var ax = f.axes, m = { l: 0, r: 0, t: 0, b: 0 };
    if (f.title) m.t = 22;
    if (ax) {
      ctx.font = "11px sans-serif";
      var wmax = 0, yt = (ax.y && ax.y.ticks) || [];
      for (var i = 0; i < yt.length; i++) wmax = Math.max(wmax, ctx.measureText(String(yt[i][1])).width);
      m.l = Math.ceil(wmax) + 10 + (ax.y && ax.y.title ? 18 : 0);
      m.b = 20 + (ax.x && ax.x.title ? 18 : 0);
      m.r = 12; m.t = Math.max(m.t, 10);
    }
    var lx = !!(ax && ax.x && ax.x.log), ly = !!(ax && ax.y && ax.y.log);
    var bd = f.bounds || [0, 1, 0, 1];
    var x0 = +bd[0], x1 = +bd[1], y0 = +bd[2], y1 = +bd[3];
    if (lx) { x0 = Math.log10(x0); x1 = Math.log10(x1); }
    if (ly) { y0 = Math.log10(y0); y1 = Math.log10(y1); }
    if (!(fin(x0) && fin(x1) && x1 > x0)) { x0 = 0; x1 = 1; }
    if (!(fin(y0) && fin(y1) && y1 > y0)) { y0 = 0; y1 = 1; }
    var pw = Math.max(1, w - m.l - m.r), ph = Math.max(1, h - m.t - m.b);
    var sx = pw / (x1 - x0), sy = ph / (y1 - y0);
    if (f.aspect !== "free") {   // equal: the same px per unit on x and y, the window grown and centred
      var s = Math.min(sx, sy), cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
      sx = sy = s;
      x0 = cx - pw / s / 2; x1 = cx + pw / s / 2; y0 = cy - ph / s / 2; y1 = cy + ph / s / 2;
    }
    return { l: m.l, t: m.t, w: pw, h: ph, x0: x0, x1: x1, y0: y0, y1: y1, sx: sx, sy: sy, lx: lx, ly: ly };
  }
  // a panel of automatic height (equal aspect): as high as the requested window needs at this
  // width (its plot area's height / width = the ranges' ratio), within [min, window height - reserve]
  function autoHeight(p, f, h, M) {
    var bd = f.bounds || [], sx = +bd[1] - +bd[0], sy = +bd[3] - +bd[2];
    if (!(fin(sx) && fin(sy) && sx > 0 && sy > 0) || p.autoFrozen || !p.root) return false;
    var lo = p.auto[0], hi = Math.max(lo, window.innerHeight - p.auto[1]);
    var want = Math.min(Math.max(Math.round(M.w * sy / sx + (h - M.h)), lo), hi);
    if (Math.abs(want - h) < 2) return false;
    var now = Date.now();
    p.autoSets = (p.autoSets || []).filter(function (t) { return now - t < 2000; });
    if (p.autoSets.length >= 6) { p.autoFrozen = true; return false; }   // flip-flopping (a scrollbar coming and going): keep this height
    p.autoSets.push(now);
    p.root.style.height = want + "px";
    return true;
  }
  function X(M, x) { return M.l + ((M.lx ? Math.log10(x) : x) - M.x0) * M.sx; }
  function Y(M, y) { return M.t + (M.y1 - (M.ly ? Math.log10(y) : y)) * M.sy; }
  E.toPx = function (id, x, y) { var M = (E.panels[id] || {}).map; return M ? [X(M, x), Y(M, y)] : null; };
  function toWorld(M, px, py) {
    var x = M.x0 + (px - M.l) / M.sx, y = M.y1 - (py - M.t) / M.sy;
    return [M.lx ? Math.pow(10, x) : x, M.ly ? Math.pow(10, y) : y];
  }

  function draw(p) {
    var c = p.canvas, f = p.frame;
    if (!c || !c.isConnected) return;
    var dpr = window.devicePixelRatio || 1;
    if (!p.size) { var rect = c.getBoundingClientRect(); p.size = [rect.width, rect.height]; }
    var w = p.size[0], h = p.size[1];   // fractional CSS px
    if (w <= 0 || h <= 0) return;
    var W = Math.round(w * dpr), H = Math.round(h * dpr);
    if (c.width !== W || c.height !== H) { c.width = W; c.height = H; }
    var ctx = c.getContext("2d");
    ctx.setTransform(W / w, 0, 0, H / h, 0, 0);   // one canvas pixel per device pixel
    ctx.clearRect(0, 0, w, h);
    if (!f) return;
    if (f.background) { ctx.fillStyle = f.background; ctx.fillRect(0, 0, w, h); }
    var M = p.map = layout(p, f, w, h, ctx);
    if (p.auto && f.aspect !== "free") autoHeight(p, f, h, M);   // a new height: the observer draws again
    if (f.axes) axes(ctx, M, f.axes, true);
    ctx.save();
    ctx.beginPath(); ctx.rect(M.l, M.t, M.w, M.h); ctx.clip();
    var items = f.items || [];
    p.hits = [];
    for (var k = 0; k < items.length; k++) {
      try { item(p, ctx, M, items[k], k); } catch (err) { console.error("ejs2d item", err); }
    }
    ctx.restore();
    if (f.axes) axes(ctx, M, f.axes, false);
    if (f.title) text(ctx, f.title, M.l + M.w / 2, 11, 13, "#222", "center", "bold ");
    if (f.legend && f.legend.length) legend(ctx, M, f.legend);
    if (f.error) note(ctx, M, String(f.error));
    p.drawn++; E.draws++;
    c.setAttribute("data-drawn", String(p.drawn));
  }

  function text(ctx, s, x, y, size, color, align, weight) {
    ctx.font = (weight || "") + size + "px sans-serif";
    ctx.fillStyle = color || "#222";
    ctx.textAlign = align || "left";
    ctx.textBaseline = "middle";
    ctx.fillText(String(s), x, y);
  }

  function axes(ctx, M, ax, under) {
    var xt = (ax.x && ax.x.ticks) || [], yt = (ax.y && ax.y.ticks) || [], i, v, q;
    var inX = function (v) { q = X(M, v); return fin(q) && q >= M.l - 0.5 && q <= M.l + M.w + 0.5; };
    var inY = function (v) { q = Y(M, v); return fin(q) && q >= M.t - 0.5 && q <= M.t + M.h + 0.5; };
    if (under) {
      if (!ax.grid) return;
      ctx.strokeStyle = "rgba(0,0,0,0.12)"; ctx.lineWidth = 1; ctx.beginPath();
      for (i = 0; i < xt.length; i++) if (inX(xt[i][0])) { v = Math.round(q) + 0.5; ctx.moveTo(v, M.t); ctx.lineTo(v, M.t + M.h); }
      for (i = 0; i < yt.length; i++) if (inY(yt[i][0])) { v = Math.round(q) + 0.5; ctx.moveTo(M.l, v); ctx.lineTo(M.l + M.w, v); }
      ctx.stroke();
      return;
    }
    ctx.strokeStyle = "#555"; ctx.lineWidth = 1;
    ctx.strokeRect(Math.round(M.l) + 0.5, Math.round(M.t) + 0.5, Math.round(M.w) - 1, Math.round(M.h) - 1);
    ctx.beginPath();
    for (i = 0; i < xt.length; i++) if (inX(xt[i][0])) { v = Math.round(q) + 0.5; ctx.moveTo(v, M.t + M.h); ctx.lineTo(v, M.t + M.h + 4); }
    for (i = 0; i < yt.length; i++) if (inY(yt[i][0])) { v = Math.round(q) + 0.5; ctx.moveTo(M.l - 4, v); ctx.lineTo(M.l, v); }
    ctx.stroke();
    for (i = 0; i < xt.length; i++) if (inX(xt[i][0])) text(ctx, xt[i][1], q, M.t + M.h + 12, 11, "#333", "center");
    for (i = 0; i < yt.length; i++) if (inY(yt[i][0])) text(ctx, yt[i][1], M.l - 6, q, 11, "#333", "right");
    if (ax.x && ax.x.title) text(ctx, ax.x.title, M.l + M.w / 2, M.t + M.h + 29, 12, "#222", "center");
    if (ax.y && ax.y.title) {
      ctx.save(); ctx.translate(9, M.t + M.h / 2); ctx.rotate(-Math.PI / 2);
      text(ctx, ax.y.title, 0, 0, 12, "#222", "center"); ctx.restore();
    }
  }

  // the lab's error, written over the top of the plot area (as text: never markup), at most 3 lines
  function note(ctx, M, msg) {
    ctx.font = "12px sans-serif";
    var words = msg.split(/\s+/), lines = [], line = "", room = Math.max(40, M.w - 16);
    for (var i = 0; i < words.length && lines.length < 3; i++) {
      var next = line ? line + " " + words[i] : words[i];
      if (line && ctx.measureText(next).width > room) { lines.push(line); line = words[i]; } else line = next;
    }
    if (line && lines.length < 3) lines.push(line);
    var bh = lines.length * 16 + 8;
    ctx.fillStyle = "rgba(253,232,232,0.92)"; ctx.fillRect(M.l + 1, M.t + 1, M.w - 2, bh);
    ctx.strokeStyle = "#e03131"; ctx.lineWidth = 1; ctx.strokeRect(M.l + 1.5, M.t + 1.5, M.w - 3, bh - 1);
    for (var j = 0; j < lines.length; j++) text(ctx, lines[j], M.l + 8, M.t + 12 + j * 16, 12, "#c92a2a", "left");
  }

  function legend(ctx, M, entries) {
    ctx.font = "11px sans-serif";
    var wmax = 0, i;
    for (i = 0; i < entries.length; i++) wmax = Math.max(wmax, ctx.measureText(String(entries[i].label)).width);
    var bw = wmax + 34, bh = entries.length * 16 + 6, bx = M.l + M.w - bw - 6, by = M.t + 6;
    ctx.fillStyle = "rgba(255,255,255,0.85)"; ctx.fillRect(bx, by, bw, bh);
    ctx.strokeStyle = "#bbb"; ctx.lineWidth = 1; ctx.strokeRect(bx + 0.5, by + 0.5, bw - 1, bh - 1);
    for (i = 0; i < entries.length; i++) {
      var e = entries[i], y = by + 11 + i * 16;
      ctx.fillStyle = ctx.strokeStyle = e.color || "#333";
      if (e.kind === "marker") { ctx.beginPath(); ctx.arc(bx + 15, y, 3.5, 0, 7); ctx.fill(); }
      else if (e.kind === "bar") ctx.fillRect(bx + 9, y - 5, 12, 10);
      else { ctx.lineWidth = 2; ctx.beginPath(); ctx.moveTo(bx + 6, y); ctx.lineTo(bx + 24, y); ctx.stroke(); }
      text(ctx, e.label, bx + 28, y, 11, "#222", "left");
    }
  }

  // a path of thousands of shapes costs the canvas more than its parts (5,000 circles in one path:
  // 18 ms, 11x the time of 1,000): shapes are filled and stroked in chunks
  var CHUNK = 200;
  function endMarkers(ctx, it, sh) {
    if (sh === "cross") { ctx.strokeStyle = it.stroke || it.fill || "#333"; ctx.lineWidth = fin(it.width) ? it.width : 1.5; ctx.stroke(); }
    else paint(ctx, it, true);
  }
  function endLines(ctx, it, t) {
    if (t === "rects") paint(ctx, it, true);
    else { ctx.strokeStyle = it.stroke || "#333"; ctx.lineWidth = fin(it.width) ? it.width : 1; ctx.stroke(); }
  }

  function paint(ctx, it, closedFill) {
    if (it.fill && closedFill) { ctx.fillStyle = it.fill; ctx.fill(); }
    if (it.stroke) { ctx.strokeStyle = it.stroke; ctx.lineWidth = fin(it.width) ? it.width : 1; ctx.stroke(); }
  }

  function item(p, ctx, M, it, k) {
    var t = it.t, d, n, i, x, y, a, b;
    ctx.setLineDash(it.dash && it.dash.length ? it.dash : []);
    ctx.lineJoin = "round"; ctx.lineCap = "round";
    if (t === "polyline") {
      d = xyOf(p, it, k); n = d.length >> 1;
      ctx.beginPath();
      var pen = false;
      for (i = 0; i < n; i++) {
        x = d[2 * i]; y = d[2 * i + 1];
        if (!(isFinite(x) && isFinite(y))) { pen = false; continue; }
        if (pen) ctx.lineTo(X(M, x), Y(M, y)); else { ctx.moveTo(X(M, x), Y(M, y)); pen = true; }
      }
      if (it.closed) ctx.closePath();
      if (it.fill) { ctx.fillStyle = it.fill; ctx.fill(); }
      if (it.stroke) { ctx.strokeStyle = it.stroke; ctx.lineWidth = fin(it.width) ? it.width : 1; ctx.stroke(); }
      hitRows(p, it, d, 2, 0);
    } else if (t === "markers") {
      d = xyOf(p, it, k); n = d.length >> 1;
      var s = fin(it.size) ? it.size : 6, r = s / 2, sh = it.shape || "circle";
      ctx.beginPath();
      for (i = 0; i < n; i++) {
        x = X(M, d[2 * i]); y = Y(M, d[2 * i + 1]);
        if (!(isFinite(x) && isFinite(y))) continue;
        if (sh === "square") ctx.rect(x - r, y - r, s, s);
        else if (sh === "cross") { ctx.moveTo(x - r, y - r); ctx.lineTo(x + r, y + r); ctx.moveTo(x - r, y + r); ctx.lineTo(x + r, y - r); }
        else if (sh === "triangle") { ctx.moveTo(x, y - r); ctx.lineTo(x + r, y + r * 0.8); ctx.lineTo(x - r, y + r * 0.8); ctx.closePath(); }
        else { ctx.moveTo(x + r, y); ctx.arc(x, y, r, 0, 2 * Math.PI); }
        if (i % CHUNK === CHUNK - 1) { endMarkers(ctx, it, sh); ctx.beginPath(); }
      }
      endMarkers(ctx, it, sh);
      hitRows(p, it, d, 2, r);
    } else if (t === "circles") {
      d = xyOf(p, it, k); n = d.length >> 1;
      var rx = Math.abs(+it.r * M.sx), ry = Math.abs(+it.r * M.sy);
      ctx.beginPath();
      for (i = 0; i < n; i++) {
        x = X(M, d[2 * i]); y = Y(M, d[2 * i + 1]);
        if (!(isFinite(x) && isFinite(y))) continue;
        ctx.moveTo(x + rx, y);
        if (rx === ry) ctx.arc(x, y, rx, 0, 2 * Math.PI); else ctx.ellipse(x, y, rx, ry, 0, 0, 2 * Math.PI);
        if (i % CHUNK === CHUNK - 1) { paint(ctx, it, true); ctx.beginPath(); }
      }
      paint(ctx, it, true);
      hitRows(p, it, d, 2, Math.min(rx, ry));
    } else if (t === "segments" || t === "arrows" || t === "rects") {
      d = xyOf(p, it, k); n = d.length >> 2;
      ctx.beginPath();
      var heads = [], hd = fin(it.head) ? it.head : 8;
      for (i = 0; i < n; i++) {
        a = d[4 * i]; b = d[4 * i + 1];
        var c2 = d[4 * i + 2], d2 = d[4 * i + 3];
        if (t === "arrows") { c2 = a + c2; d2 = b + d2; }
        x = X(M, a); y = Y(M, b);
        var x2 = X(M, c2), y2 = Y(M, d2);
        if (!(isFinite(x) && isFinite(y) && isFinite(x2) && isFinite(y2))) continue;
        if (i % CHUNK === CHUNK - 1) { endLines(ctx, it, t); ctx.beginPath(); }
        if (t === "rects") { ctx.rect(Math.min(x, x2), Math.min(y, y2), Math.abs(x2 - x), Math.abs(y2 - y)); continue; }
        var L = Math.hypot(x2 - x, y2 - y);
        if (t === "arrows" && L > 0) {
          var hl = Math.min(hd, L * 0.6), ux = (x2 - x) / L, uy = (y2 - y) / L, hw = hl * 0.45;
          ctx.moveTo(x, y); ctx.lineTo(x2 - ux * hl * 0.8, y2 - uy * hl * 0.8);
          heads.push(x2, y2, x2 - ux * hl - uy * hw, y2 - uy * hl + ux * hw, x2 - ux * hl + uy * hw, y2 - uy * hl - ux * hw);
        } else { ctx.moveTo(x, y); ctx.lineTo(x2, y2); }
      }
      endLines(ctx, it, t);
      if (heads.length) {
        ctx.setLineDash([]); ctx.beginPath();
        ctx.fillStyle = it.stroke || "#333";
        for (i = 0; i < heads.length; i += 6) {
          ctx.moveTo(heads[i], heads[i + 1]); ctx.lineTo(heads[i + 2], heads[i + 3]); ctx.lineTo(heads[i + 4], heads[i + 5]); ctx.closePath();
          if ((i / 6) % CHUNK === CHUNK - 1) { ctx.fill(); ctx.beginPath(); }
        }
        ctx.fill();
      }
      hitRows(p, it, d, 4, 0);
    } else if (t === "text") {
      if (!(fin(it.x) && fin(it.y))) return;
      text(ctx, it.text, X(M, it.x), Y(M, it.y), fin(it.size) ? it.size : 12, it.color, it.align || "center");
      hitPoint(p, it, it.x, it.y, 0, 0);
    } else if (t === "image") {
      // one picture per item of the panel, replaced when its source changes (no cache that grows)
      if (!p.images) p.images = {};
      var im = p.images[k];
      if (!im || im.ejsSrc !== it.src) {
        var old = im;
        im = p.images[k] = new Image();
        im.prev = old && old.complete && old.naturalWidth ? old : old && old.prev;   // shown until this one loads
        if (im.prev) im.prev.prev = null;
        im.ejsSrc = it.src;
        im.onload = function () { request(p); };
        im.src = String(it.src).indexOf("data:image/") === 0 ? it.src : "data:,";   // data URLs only: nothing fetched
      }
      x = X(M, it.x0); y = Y(M, it.y1);
      var x3 = X(M, it.x1), y3 = Y(M, it.y0);
      var shown = im.complete && im.naturalWidth ? im : im.prev;
      if (shown && isFinite(x) && isFinite(y)) {
        ctx.imageSmoothingEnabled = !!it.smooth;
        ctx.drawImage(shown, Math.min(x, x3), Math.min(y, y3), Math.abs(x3 - x), Math.abs(y3 - y));
      }
      hitPoint(p, it, (it.x0 + it.x1) / 2, (it.y0 + it.y1) / 2, 0, 0);
    }
  }

  // -- dragging -------------------------------------------------------------------------------
  // a draggable item's handle points: each row of markers and circles (a set: the row is
  // sent as "i"); segments and arrows at their start, or with "handle": "end" at their end
  // (an arrow's tip); a polyline at its first point (its last with "handle": "end")
  function hitRows(p, it, d, stride, r) {
    if (!it.drag || !it.id) return;
    var n = d.length / stride, end = it.handle === "end";
    if (it.t === "polyline") {   // a spring, a path: dragged by its first point (its last with handle end)
      if (n) hitPoint(p, it, d[end ? 2 * n - 2 : 0], d[end ? 2 * n - 1 : 1], 0, 0);
      return;
    }
    for (var i = 0; i < n; i++) {
      var x = d[stride * i], y = d[stride * i + 1];
      if (stride === 4 && end) {
        x = it.t === "arrows" ? x + d[stride * i + 2] : d[stride * i + 2];
        y = it.t === "arrows" ? y + d[stride * i + 3] : d[stride * i + 3];
      }
      hitPoint(p, it, x, y, r, i);
    }
  }
  function hitPoint(p, it, x, y, r, i) {
    if (!it.drag || !it.id || !(isFinite(x) && isFinite(y))) return;
    p.hits.push({ id: String(it.id), i: i, x: x, y: y, r: r, drag: it.drag });
  }
  function local(p, e) {
    var rect = p.canvas.getBoundingClientRect();
    return [e.clientX - rect.left, e.clientY - rect.top];
  }
  function down(p, e) {
    var M = p.map;
    if (!M || e.button !== 0) return;
    p.canvas.focus({ preventScroll: true });
    var q = local(p, e), best = null, bestD = Infinity;
    for (var j = p.hits.length - 1; j >= 0; j--) {
      var h = p.hits[j], dx = X(M, h.x) - q[0], dy = Y(M, h.y) - q[1];
      var dist = Math.hypot(dx, dy) - h.r;
      if (dist <= HIT_PX && dist < bestD) { best = h; bestD = dist; }
    }
    p.down = q;
    if (!best) { p.drag = null; return; }
    var w = toWorld(M, q[0], q[1]);
    p.drag = { id: best.id, i: best.i, ox: best.x - w[0], oy: best.y - w[1], x: best.x, y: best.y, mode: best.drag };
    p.canvas.setPointerCapture(e.pointerId);
    e.preventDefault();
    e.stopPropagation();
    send(p, dragEvent(p, "start", best.x, best.y));
  }
  function dragEvent(p, phase, x, y) {
    var g = p.drag, ev = { k: "drag", id: g.id, phase: phase, x: x, y: y };
    if (g.i) ev.i = g.i;
    return ev;
  }
  function move(p, e) {
    var g = p.drag, M = p.map;
    if (!g || !M) return;
    var q = local(p, e), w = toWorld(M, q[0], q[1]);
    var x = g.mode === "y" ? g.x : w[0] + g.ox, y = g.mode === "x" ? g.y : w[1] + g.oy;
    if (!(isFinite(x) && isFinite(y))) return;
    e.preventDefault();
    send(p, dragEvent(p, "move", x, y));
  }
  function up(p, e, cancelled) {
    var g = p.drag, M = p.map;
    if (g) {
      var last = p.queue.length ? p.queue[p.queue.length - 1] : null;
      var x = last && last.k === "drag" ? last.x : g.x, y = last && last.k === "drag" ? last.y : g.y;
      if (M && !cancelled) {
        var q = local(p, e), w = toWorld(M, q[0], q[1]);
        x = g.mode === "y" ? g.x : w[0] + g.ox; y = g.mode === "x" ? g.y : w[1] + g.oy;
      }
      send(p, dragEvent(p, "release", x, y), true);
      p.drag = null;
      return;
    }
    if (M && p.down && !cancelled) {
      var q2 = local(p, e);
      if (Math.hypot(q2[0] - p.down[0], q2[1] - p.down[1]) < 4) {
        var w2 = toWorld(M, q2[0], q2[1]);
        if (isFinite(w2[0]) && isFinite(w2[1])) send(p, { k: "click", x: w2[0], y: w2[1] }, true);
      }
    }
    p.down = null;
  }

  // -- keys -----------------------------------------------------------------------------------
  function key(p, e, phase) {
    if (e.ctrlKey || e.metaKey || e.altKey || !KEYS.test(e.key)) return;
    if (p.only && p.only.indexOf(e.key) < 0) return;   // not one of its keys: left to the page
    e.preventDefault();       // no page scroll, no 3D camera move
    e.stopPropagation();
    if (phase === "down" && e.repeat && p.queue.length > MAX_QUEUE / 2) return;
    send(p, { k: "key", key: e.key, phase: phase }, true);
  }

  // -- to the server: the panel's hidden text input --------------------------------------------
  function send(p, ev, keep) {
    var q = p.queue, last = q.length ? q[q.length - 1] : null;
    if (!keep && last && last.k === ev.k && last.phase === "move" && ev.phase === "move" && last.id === ev.id) q[q.length - 1] = ev;
    else if (q.length < MAX_QUEUE) q.push(ev);
    flushSoon(p);
  }
  function flushSoon(p) {
    if (p.timer) return;
    var wait = Math.max(0, SEND_MS - (Date.now() - p.lastSend));
    p.timer = setTimeout(function () { p.timer = null; flush(p); }, wait);
  }
  function inputOf(p) {
    var label = document.querySelector('label[for="' + p.input + '"]');
    var wrap = label;
    for (var i = 0; wrap && i < 6 && !(wrap.querySelector && wrap.querySelector("input")); i++) wrap = wrap.parentElement;
    return wrap ? wrap.querySelector("input") : null;
  }
  function flush(p) {
    if (!p.queue.length) return;
    var el = inputOf(p);
    if (!el) { flushSoon(p); return; }
    var msg = JSON.stringify({ s: ++p.seq, e: p.queue });
    p.queue = [];
    p.lastSend = Date.now();
    var setter = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, "value").set;
    setter.call(el, msg);
    el.dispatchEvent(new Event("input", { bubbles: true }));
  }
  E.drain();
})();
