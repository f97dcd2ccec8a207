// The lab's Python, in a module worker (ejsgen build --web). It loads CPython for WebAssembly
// (python.wasm) with the WASI shim, mounts the standard library zip at /usr/local/lib and the
// lab's files at /lab, makes the lab (ejsrl.web.lab.open_lab) and then runs one display frame
// per tick: the page's messages go in through /io/inbox, viser's batch comes out of /io/outbox
// (see runtime/ejsrl/web/lab.py). One interpreter lives as long as the page: each call is a
// "turn" of the reactor's `turn` export. The downloaded files are kept inflated in the page's
// Cache Storage (see load); `worker.js?sw=1` (bridge.js) says sw.js serves this worker.
//
// Messages from the page (bridge.js): {type: "connect"}, {type: "send", message},
// {type: "call", id, what, args} (headless CSV, state). To the page: {type: "progress", ...},
// {type: "stage", text} (what the loader does now), {type: "ready", fps}, {type: "batch", messages}, {type: "reply", id, ok, value},
// {type: "failed", text}, {type: "log", level, text}, {type: "mark", name, at} (a phase of the start).

import { WASI, File, OpenFile, ConsoleStdout, PreopenDirectory, Directory } from "./vendor/browser_wasi_shim/index.js";
import { decode, encode } from "./msgpack.js";

const site = new URL("../", import.meta.url); // the site's folder: index.html's
const at = (path) => new URL(path, site).href;
const log = (level, text) => postMessage({ type: "log", level, text });
const stage = (text) => postMessage({ type: "stage", text });
/** A named moment of the start (ms since the epoch, as performance.timeOrigin + now: the page
 * turns it into its own clock), also a performance.mark for DevTools. */
const mark = (name) => {
  performance.mark(`ejsweb:${name}`);
  postMessage({ type: "mark", name, at: performance.timeOrigin + performance.now() });
};
mark("workerStarted");
let exports = null;
let stdout = [];
let fps = 30;
let connected = false;
let inbox = [];
let batches = 0; // batches sent to the page
let cameraAt = 0; // when the client's first camera message came (it makes the lab build its panel)
const io = { inbox: new File([]), outbox: new File([]), "run.csv": new File([]) };

/** Fetch `url` (gzip-compressed: `url` ends in .gz) into a Uint8Array, reporting progress. */
async function fetchBytes(url, what, size) {
  const response = await fetch(at(url));
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  let got = 0;
  const counted = response.body.pipeThrough(new TransformStream({
    transform(chunk, controller) {
      got += chunk.byteLength;
      postMessage({ type: "progress", what, got, size });
      controller.enqueue(chunk);
    },
  }));
  const body = url.endsWith(".gz") ? counted.pipeThrough(new DecompressionStream("gzip")) : counted;
  return new Uint8Array(await new Response(body).arrayBuffer());
}

/** The lab's files (bundle.bin: a 4-byte little-endian JSON index length, the index
 * [[path, size], ...], then the files' bytes) as a tree of the shim's Directory/File. */
function unpack(bundle) {
  const n = new DataView(bundle.buffer, bundle.byteOffset).getUint32(0, true);
  const index = JSON.parse(new TextDecoder().decode(bundle.subarray(4, 4 + n)));
  const root = new Map();
  let pos = 4 + n;
  for (const [path, size] of index) {
    const parts = path.split("/");
    let dir = root;
    for (const part of parts.slice(0, -1)) {
      if (!dir.has(part)) dir.set(part, new Directory(new Map()));
      dir = dir.get(part).contents;
    }
    dir.set(parts[parts.length - 1], new File(bundle.subarray(pos, pos + size), { readonly: true }));
    pos += size;
  }
  return root;
}

/** Run `code` in the interpreter; its standard output as text. */
function turn(code) {
  const bytes = new TextEncoder().encode(code);
  const p = exports.host_alloc(bytes.length) >>> 0;
  if (p === 0) throw new Error("the lab's Python is out of memory");
  new Uint8Array(exports.memory.buffer, p, bytes.length).set(bytes);
  stdout = [];
  exports.turn(p, bytes.length);
  return stdout.join("\n");
}

/** A turn whose last line prints a JSON value: that value (errors are raised as Error). */
function ask(code) {
  const out = turn(
    "import json as _j, traceback as _tb\ntry:\n" +
    code.split("\n").map((l) => "    " + l).join("\n") +
    "\n    print('\\x1e' + _j.dumps({'ok': True, 'value': _v}))\n" +
    "except BaseException as _e:\n    print('\\x1e' + _j.dumps({'ok': False, 'value': _tb.format_exc()}))\n");
  const line = out.split("\n").reverse().find((l) => l.startsWith("\x1e"));
  if (line === undefined) throw new Error("the lab's Python gave no answer: " + out.slice(-500));
  const answer = JSON.parse(line.slice(1));
  if (!answer.ok) throw new Error(answer.value);
  return answer.value;
}

/** The URL to fetch for a manifest entry: the plain file when the host compresses it on the
 * wire itself (Content-Encoding br or gzip), else the .gz file, inflated here. */
async function pick(entry) {
  try {
    const head = await fetch(at(entry.plain), { method: "HEAD" });
    const encoding = head.ok ? head.headers.get("content-encoding") || "" : "";
    if (/\b(br|gzip)\b/.test(encoding)) return entry.plain;
  } catch (e) {
    // no HEAD: the .gz file
  }
  return entry.url;
}

/** The page's Cache Storage (null where the browser gives none: a page that is not a secure
 * context, a private window out of room). It keeps each file inflated under its plain URL and
 * the build's digest (`python/python.wasm?v=...`), so a later visit neither downloads nor
 * inflates it, and Chromium keeps the compiled WebAssembly beside the entry it was compiled
 * from by streaming (its code cache), so a later visit does not compile it either. */
async function openStore() {
  try {
    return self.caches ? await caches.open("ejsweb") : null;
  } catch (e) {
    return null;
  }
}

const TYPES = { wasm: "application/wasm" };

/** Whether sw.js serves this worker's requests (bridge.js says so in the worker's URL). */
const served = new URL(self.location.href).searchParams.get("sw") === "1";

/** A manifest entry's file as a Response: from the store, else downloaded (and stored). The
 * WebAssembly comes through sw.js when it serves this worker: a response it took from the
 * store is one whose compiled code Chromium caches. */
async function load(store, entry, what) {
  const key = `${at(entry.plain)}?v=${entry.sha}`;
  const headers = { "Content-Type": TYPES[what] || "application/octet-stream" };
  let hit;
  if (store !== null) {
    try {
      hit = await store.match(key);
    } catch (e) {
      hit = undefined; // a store that fails to read: download
    }
  }
  if (hit) {
    postMessage({ type: "progress", what, got: entry.size, size: entry.size, cached: true });
  } else {
    const bytes = await fetchBytes(await pick(entry), what, entry.size);
    mark(`${what}Fetched`);
    if (store !== null) hit = await keep(store, key, new Response(bytes, { headers }));
    if (!hit) return new Response(bytes, { headers });
  }
  if (served && what === "wasm") {
    try {
      const response = await fetch(key);
      if (response.ok) return response;
    } catch (e) {
      // sw.js gone: the store's response
    }
  }
  return hit;
}

/** Put `response` in `store` under `key` (dropping this file of earlier builds); the stored
 * response, or undefined when the browser keeps nothing (out of room). */
async function keep(store, key, response) {
  try {
    const path = new URL(key).pathname;
    for (const old of await store.keys()) {
      if (new URL(old.url).pathname === path && old.url !== key) await store.delete(old);
    }
    await store.put(key, response);
    return await store.match(key);
  } catch (e) {
    log("warn", `the browser did not keep ${new URL(key).pathname} (${e}); the next visit downloads it again`);
    return undefined;
  }
}

/** The manifest: asked of the host each visit (a rebuilt site is seen at once), else, offline,
 * the browser's copy. */
async function manifestOf() {
  const url = at("python/manifest.json");
  let response;
  try {
    response = await fetch(url, { cache: "no-cache" });
  } catch (e) {
    response = await fetch(url, { cache: "force-cache" });
  }
  if (!response.ok) throw new Error(`python/manifest.json: HTTP ${response.status}`);
  return response.json();
}

async function boot() {
  const t0 = performance.now();
  const [manifest, store] = await Promise.all([manifestOf(), openStore()]);
  mark("manifest");
  const [module, stdlib, lab] = await Promise.all([
    load(store, manifest.wasm, "wasm").then((r) => {
      mark("wasmLoaded");
      stage("Compiling Python (WebAssembly)…");
      return WebAssembly.compileStreaming(r);
    }).then((m) => { mark("wasmCompiled"); return m; }),
    load(store, manifest.stdlib, "stdlib").then((r) => r.arrayBuffer())
      .then((b) => { mark("stdlibLoaded"); return new Uint8Array(b); }),
    load(store, manifest.lab, "lab").then((r) => r.arrayBuffer())
      .then((b) => { mark("labLoaded"); return new Uint8Array(b); }),
  ]);
  const fetched = performance.now() - t0;
  stage("Starting Python…");
  const fds = [
    new OpenFile(new File([])),
    ConsoleStdout.lineBuffered((line) => stdout.push(line)),
    ConsoleStdout.lineBuffered((line) => log("warn", line)),
    new PreopenDirectory("/usr/local/lib", [[manifest.stdlib.name, new File(stdlib, { readonly: true })]]),
    new PreopenDirectory("/lab", unpack(lab)),
    new PreopenDirectory("/io", Object.entries(io)),
    new PreopenDirectory("/tmp", []),
  ];
  const wasi = new WASI(["python.wasm"], ["TMPDIR=/tmp", "HOME=/tmp", "PYTHONTZPATH=", "PYTHONDONTWRITEBYTECODE=1"],
    fds, { debug: false });
  const instance = await WebAssembly.instantiate(module, {
    wasi_snapshot_preview1: wasi.wasiImport,
    host: { call: () => -1 }, // no host functions: the lab asks the page nothing synchronously
  });
  mark("instantiated");
  exports = instance.exports;
  wasi.initialize(instance);
  mark("pythonStarted");
  const started = performance.now() - t0;
  stage("Starting Python: importing the lab (NumPy, SciPy, the runtime, viser)…");
  // the methods viser's ~250 dataclasses write, compiled by the build (ejsrl.web._codecache)
  const codes = ask("import sys\nsys.path.insert(0, '/lab')\nfrom ejsrl.web._codecache import FILE, install\n" +
    "_v = install('/lab/' + FILE)");
  ask("import numpy\n_v = 0");
  mark("numpyImported");
  ask("from ejsrl.web.lab import open_lab\n_v = 0");
  mark("runtimeImported");
  ask("import app\n_v = 0");
  mark("appImported");
  const info = ask("lab = open_lab('app')\n" +
    "_v = {'fps': lab.fps, 'steps': lab.sim.steps_per_display, 'realtime': bool(lab.sim.realtime), " +
    "'title': lab.app.meta.title}");
  mark("labOpened");
  fps = info.fps;
  const timing = { fetched, started, lab: performance.now() - t0, dataclassCodes: codes };
  postMessage({ type: "ready", fps, steps: info.steps, realtime: info.realtime, title: info.title, timing });
}

/** Replace viser's binary placeholders ({__binary_index, dtype}) with typed arrays over `buffer`. */
const DTYPES = {
  "<f2": [Uint16Array, 2], "<f4": [Float32Array, 4], "<f8": [Float64Array, 8], "|u1": [Uint8Array, 1],
  "<u2": [Uint16Array, 2], "<u4": [Uint32Array, 4], "|i1": [Int8Array, 1], "<i2": [Int16Array, 2], "<i4": [Int32Array, 4],
};
function placeBinaries(obj, buffer, offsets, lengths) {
  if (obj === null || typeof obj !== "object" || ArrayBuffer.isView(obj)) return obj;
  if (Array.isArray(obj)) {
    for (let i = 0; i < obj.length; i++) obj[i] = placeBinaries(obj[i], buffer, offsets, lengths);
    return obj;
  }
  if ("__binary_index" in obj && "dtype" in obj) {
    const i = obj.__binary_index;
    const [ctor, bytes] = DTYPES[obj.dtype] || [Uint8Array, 1];
    return new ctor(buffer, offsets[i], lengths[i] / bytes);
  }
  for (const k of Object.keys(obj)) obj[k] = placeBinaries(obj[k], buffer, offsets, lengths);
  return obj;
}

function decodeBatch(data) {
  const buffer = data.slice().buffer; // starts at 0: the 8-byte alignment of the arrays holds
  const bytes = new Uint8Array(buffer);
  const n = Number(new DataView(buffer).getBigUint64(0, true));
  const batch = decode(bytes.subarray(8, 8 + n));
  const lengths = batch.binaryBufferLengths || [];
  const offsets = [];
  let pos = 8 + n;
  for (const len of lengths) {
    pos += (8 - (pos % 8)) % 8;
    offsets.push(pos);
    pos += len;
  }
  if (lengths.length) placeBinaries(batch.messages, buffer, offsets, lengths);
  return { messages: batch.messages, buffer };
}

function frame(step) {
  if (inbox.length) {
    let size = 0;
    for (const m of inbox) size += 4 + m.length;
    const data = new Uint8Array(size);
    const view = new DataView(data.buffer);
    let pos = 0;
    for (const m of inbox) { view.setUint32(pos, m.length, true); data.set(m, pos + 4); pos += 4 + m.length; }
    io.inbox.data = data;
    inbox = [];
  }
  const out = turn(step ? "_ = lab.frame()" : "_ = lab.frame(step=False)");
  if (out) log("info", out);
  const data = io.outbox.data;
  if (data.length) {
    if (!batches++) mark("firstBatchOut");
    const { messages, buffer } = decodeBatch(data);
    postMessage({ type: "batch", messages }, [buffer]);
  }
}

let next = 0;
let frameMs = 0;
function loop() {
  const t = performance.now();
  try {
    frame(true);
  } catch (e) {
    postMessage({ type: "failed", text: String(e && e.stack || e) });
    return;
  }
  frameMs = performance.now() - t;
  const period = 1000 / fps;
  next += period;
  let delay = next - performance.now();
  // a late frame is made up by the next ones (the lab's rate holds on a busy machine); after
  // more than a few periods behind (the tab was in the background) the schedule starts again
  if (delay < -4 * period) { next = performance.now(); delay = 0; }
  setTimeout(loop, Math.max(0, delay));
}

function call(what, args) {
  if (what === "state") {
    const names = (args.vars || []).map(String);
    if (!names.every((v) => /^[A-Za-z_][A-Za-z0-9_]*$/.test(v))) throw new Error("state: bad variable name");
    return { ...ask(`_v = lab.state(${JSON.stringify(names)})`), frameMs, cameraAt };
  }
  if (what === "headless") {
    const duration = Number(args.duration);
    if (!Number.isFinite(duration) || duration <= 0) throw new Error("headless: duration must be a positive number");
    const names = (args.vars || []).map(String);
    if (!names.every((v) => /^[A-Za-z_][A-Za-z0-9_]*(\[[0-9]+\])?$/.test(v))) throw new Error("headless: bad variable name");
    const every = Math.max(1, Math.floor(Number(args.every) || 1));
    const t = performance.now();
    const status = ask("from ejsrl.web.lab import headless_csv\n" +
      `_v = headless_csv(lab.module, ${duration}, variables=${names.length ? JSON.stringify(names) : "None"}, every=${every})`);
    return { status, csv: new TextDecoder().decode(io["run.csv"].data), ms: performance.now() - t };
  }
  if (what === "steps") { // seconds of n model steps in this browser (bench/web.py): the shim has no CPU clock
    const n = Math.max(1, Math.min(1000000, Math.floor(Number(args.n) || 1)));
    return ask(`import time\n_m = lab.app.model\n_t = time.perf_counter()\nfor _ in range(${n}):\n    _m._ejs_step()\n` +
      "_v = time.perf_counter() - _t");
  }
  throw new Error("unknown call " + what);
}

onmessage = (e) => {
  const msg = e.data;
  if (msg.type === "send") {
    if (msg.message && msg.message.type === "ViewerCameraMessage" && !cameraAt) cameraAt = performance.now();
    try { inbox.push(encode(msg.message)); } catch (err) { log("warn", "dropped a client message: " + err); }
  } else if (msg.type === "connect") {
    if (!connected) {
      connected = true;
      next = performance.now();
      loop();
    }
  } else if (msg.type === "call") {
    let reply;
    try { reply = { ok: true, value: call(msg.what, msg.args || {}) }; } catch (err) { reply = { ok: false, value: String(err && err.message || err) }; }
    postMessage({ type: "reply", id: msg.id, ...reply });
  }
};

boot().catch((e) => postMessage({ type: "failed", text: String(e && e.stack || e) }));
