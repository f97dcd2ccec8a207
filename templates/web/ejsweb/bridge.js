// The in-page channel of a lab built with `ejsgen build --web` (a classic script, run before
// viser's client). viser's client opens its websocket from an inline Worker; this script
// gives it, in that Worker's place, an object speaking the same protocol (WsWorkerIncoming /
// WsWorkerOutgoing of viser's WebsocketClientWorker.ts) whose other end is the lab's Python,
// running in worker.js. Every other Worker the client makes is a real one.
//
// It also shows the lab's loading view in place of viser's stock panel, registers sw.js (the
// lab's Python from Cache Storage on later visits) and, on software WebGL, turns viser's
// environment map off (see softwareWebGL).
//
// window.ejsWeb: {ready (a Promise), call(what, args) -> Promise, timing, marks (the start's
// phases, ms from navigation), software, bytes}: what the tests and bench/web.py use (a headless
// run's CSV, the model's time, the step cost, where the start's time goes).
(() => {
  "use strict";
  const RealWorker = window.Worker;
  const base = new URL("ejsweb/", document.baseURI);
  const started = performance.now();
  let python = null;
  let socket = null; // the viser client's side, once it made its websocket worker
  let ready = false;
  let wanted = false; // the client asked to connect (set_server / retry)
  let connected = false;
  let calls = 0;
  const pending = new Map();
  let resolveReady, rejectReady;
  const api = {
    ready: new Promise((res, rej) => { resolveReady = res; rejectReady = rej; }),
    timing: {},
    marks: {}, // the start's phases: ms since the page's navigation began (see mark)
    failed: null,
    call(what, args) {
      return api.ready.then(() => new Promise((res, rej) => {
        const id = ++calls;
        pending.set(id, { res, rej });
        python.postMessage({ type: "call", id, what, args });
      }));
    },
  };
  window.ejsWeb = api;
  /** Note the moment ``name`` of the start (the first time only), at ``at`` ms since the epoch
   * (a worker's clock) or now; also a performance.mark for DevTools. */
  function mark(name, at) {
    if (name in api.marks) return;
    api.marks[name] = at === undefined ? performance.now() : at - performance.timeOrigin;
    performance.mark(`ejsweb:${name}`);
  }
  mark("bridge");

  // -- what the page shows while the lab loads -------------------------------------------------
  // viser's client is hidden (its stock panel: a server field, "Connected", the scene tree)
  // until the lab's own panel is drawn; the lab's title and what the start does now show
  // instead. Text only: nothing here is read as HTML.
  const hiding = document.createElement("style");
  hiding.textContent = "#root{visibility:hidden}";
  (document.head || document.documentElement).appendChild(hiding);
  let overlay = null;
  let phase = null;
  const progress = {};
  let stage = "";
  function show(text, failed) {
    if (overlay === null) {
      overlay = document.createElement("div");
      overlay.id = "ejsweb-loading";
      overlay.setAttribute("role", "status");
      overlay.style.cssText = "position:fixed;inset:0;z-index:10000;display:flex;flex-direction:column;" +
        "align-items:center;justify-content:center;gap:12px;background:#fff;color:#222;" +
        "font:15px system-ui,sans-serif;text-align:center;padding:24px";
      const title = document.createElement("div");
      title.style.cssText = "font-size:22px;font-weight:600";
      title.textContent = document.title || "";
      phase = document.createElement("div");
      phase.style.cssText = "white-space:pre-wrap;max-width:80vw;color:#555";
      overlay.append(title, phase);
      (document.body || document.documentElement).appendChild(overlay);
      if (!title.textContent) document.addEventListener("DOMContentLoaded", () => { title.textContent = document.title; });
    }
    phase.textContent = text;
    if (failed) phase.style.color = "#a00";
  }
  /** The lab's panel is drawn: viser's client shows, the loading view goes. */
  function reveal() {
    if (api.failed || "panelDrawn" in api.marks) return;
    mark("panelDrawn");
    hiding.remove();
    if (overlay !== null) overlay.remove();
    overlay = null;
  }
  show("Starting…");
  const mb = (n) => (n / 1e6).toFixed(1);

  // The client is told it is connected as soon as it asks (a websocket that opened), so what
  // it sends first (its camera, which makes the lab build its panel) is kept here until the
  // lab's Python is ready, then handed over in order.
  const early = [];
  function connect() {
    if (!wanted || socket === null) return;
    if (!connected) {
      connected = true;
      socket.emit({ type: "connected" });
    }
    if (ready && early !== null) {
      for (const message of early.splice(0)) python.postMessage({ type: "send", message });
      python.postMessage({ type: "connect" });
    }
  }

  // Whether this browser renders WebGL in software (no GPU), by viser's own test of the
  // renderer's name. There the lab's first batch turns viser's environment map off
  // (window.ejsWebSoftware, made by the build from viser's message class): prefiltering it takes
  // seconds of CPU there, most of what a start costs. With a GPU the page looks as served.
  function softwareWebGL() {
    try {
      const gl = document.createElement("canvas").getContext("webgl2");
      if (!gl) return false;
      const info = gl.getExtension("WEBGL_debug_renderer_info");
      const renderer = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER)).toLowerCase();
      const lose = gl.getExtension("WEBGL_lose_context");
      if (lose) lose.loseContext();
      return /swiftshader|llvmpipe|softpipe|software/.test(renderer);
    } catch (e) {
      return false;
    }
  }

  function startPython(served) {
    python = new RealWorker(new URL(served ? "worker.js?sw=1" : "worker.js", base), { type: "module" });
    const t0 = performance.now();
    python.onmessage = (e) => {
      const msg = e.data;
      if (msg.type === "batch") {
        if (!api.timing.firstBatch) api.timing.firstBatch = performance.now() - t0;
        mark("firstBatch");
        if (!api.timing.panel && msg.messages.some((m) => m.type === "GuiButtonMessage")) {
          api.timing.panel = performance.now() - t0; // the panel's controls reach the client
        }
        if (api.software === undefined) {
          api.software = softwareWebGL();
          const off = window.ejsWebSoftware;
          if (api.software && Array.isArray(off)) msg.messages.unshift(...off);
        }
        if (socket !== null) socket.emit({ type: "message_batch", messages: msg.messages });
        if (waitingFor === undefined) { // the first batch: watch for the lab's panel (once)
          waitingFor = labelOf(msg.messages);
          drawn();
          setTimeout(reveal, 3000); // a label the client shows otherwise (a closed tab): shown anyway
        }
      } else if (msg.type === "mark") {
        mark(msg.name, msg.at);
      } else if (msg.type === "progress") {
        progress[msg.what] = msg;
        let got = 0, size = 0;
        for (const p of Object.values(progress)) { got += p.got; size += p.size; }
        api.bytes = got;
        show(`Loading the lab… ${mb(got)} of ${mb(Math.max(size, got))} MB` + (stage ? "\n" + stage : ""));
      } else if (msg.type === "stage") {
        stage = msg.text; // what the lab's Python does now, once the bytes are in
        show(stage);
      } else if (msg.type === "ready") {
        ready = true;
        api.sim = { fps: msg.fps, steps: msg.steps, realtime: msg.realtime };
        Object.assign(api.timing, msg.timing, { ready: performance.now() - t0 });
        show("Drawing the lab…");
        resolveReady();
        connect();
      } else if (msg.type === "reply") {
        const p = pending.get(msg.id);
        pending.delete(msg.id);
        if (p) (msg.ok ? p.res : p.rej)(msg.ok ? msg.value : new Error(msg.value));
      } else if (msg.type === "log") {
        (msg.level === "warn" ? console.warn : console.log)("[lab]", msg.text);
      } else if (msg.type === "failed") {
        api.failed = msg.text;
        console.error("[lab]", msg.text);
        show("The lab stopped: " + msg.text.split("\n").filter(Boolean).slice(-1)[0], true);
        rejectReady(new Error(msg.text));
      }
    };
    python.onerror = (e) => {
      if (location.protocol === "file:") return; // said already
      api.failed = String(e.message || e);
      show("The lab could not start: " + api.failed + "\n(this page needs a recent Chrome, Edge or Firefox)", true);
      rejectReady(new Error(api.failed));
    };
  }

  // The panel is drawn once the first labelled control of the lab's first batch is in the page
  // (viser's client renders a batch on its next frames).
  let waitingFor;
  function labelOf(messages) {
    for (const m of messages) {
      const label = m.props && m.props.label;
      if (typeof label === "string" && label.trim()) return label.trim();
    }
    return null;
  }
  function drawn() {
    if ("panelDrawn" in api.marks) return;
    const root = document.getElementById("root");
    if (waitingFor === null || (root !== null && root.textContent.includes(waitingFor))) reveal();
    else requestAnimationFrame(drawn);
  }

  /** Stands in for viser's websocket worker. */
  class PageSocket {
    constructor() {
      this.onmessage = null;
      this.onerror = null;
      socket = this;
    }
    emit(data) {
      if (typeof this.onmessage === "function") this.onmessage({ data });
    }
    postMessage(data) {
      if (data.type === "send") {
        if (ready) python.postMessage({ type: "send", message: data.message });
        else if (early.length < 1000) early.push(data.message);
      } else if (data.type === "set_server" || data.type === "retry") {
        if (!api.timing.clientAsked) api.timing.clientAsked = performance.now() - started;
        mark("clientAsked");
        wanted = true;
        connect();
      }
      // "zstd_wasm": nothing is compressed on this channel; "close": the page is going away
    }
    addEventListener(type, fn) {
      if (type === "message") this.onmessage = fn;
    }
    removeEventListener() {}
    terminate() {}
  }

  function isSocketWorker(url) {
    // viser's inline websocket worker: a blob: URL whose code opens the websocket
    try {
      const request = new XMLHttpRequest();
      request.open("GET", String(url), false);
      request.send();
      const code = request.responseText || "";
      return code.includes("set_server") && code.includes("WebSocket");
    } catch (e) {
      return false;
    }
  }

  window.Worker = function Worker(url, options) {
    if (socket === null && String(url).startsWith("blob:") && isSocketWorker(url)) return new PageSocket();
    return new RealWorker(url, options);
  };
  window.Worker.prototype = RealWorker.prototype;

  // sw.js serves the lab's Python from the page's Cache Storage (see sw.js): the worker starts
  // once it controls the page (at once from the second visit on; a first visit waits for it to
  // install, which viser's client takes longer to start anyway), or without it where a browser
  // has none (a page that is not a secure context) or it does not come within 3 s.
  (async () => {
    let served = false;
    try {
      const sw = navigator.serviceWorker;
      if (sw && window.isSecureContext) {
        sw.register(new URL("sw.js", document.baseURI)).catch((e) => console.warn("[lab] no service worker:", e));
        served = sw.controller !== null || await new Promise((resolve) => {
          sw.addEventListener("controllerchange", () => resolve(true), { once: true });
          setTimeout(() => resolve(false), 3000);
        });
      }
    } catch (e) {
      served = false;
    }
    mark(served ? "serviceWorker" : "noServiceWorker");
    startPython(served);
  })();
  if (location.protocol === "file:") { // a browser runs no module worker from a file: say what to do instead
    api.failed = "opened as a file";
    show("This lab runs from a web server, not as a file (a browser does not start its Python from a file:// page).\n" +
      "In its folder run   python3 -m http.server 8000\nthen open   http://localhost:8000/", true);
    rejectReady(new Error(api.failed));
  }
  document.addEventListener("DOMContentLoaded", () => mark("domContentLoaded"));
})();
