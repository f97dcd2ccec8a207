// The service worker of a lab built with `ejsgen build --web` (registered by ejsweb/bridge.js).
// It answers one kind of request only: a file of the lab's Python asked with its build digest
// (`python/python.wasm?v=<sha>`), from the page's Cache Storage ("ejsweb"), where the lab's
// worker (ejsweb/worker.js) keeps it inflated after downloading it once. Chromium keeps the
// compiled WebAssembly beside a Cache Storage entry that a service worker served (its code
// cache), so a later visit neither downloads, inflates nor compiles python.wasm. Every other
// request goes to the host as if there were no service worker.
"use strict";

self.addEventListener("install", () => self.skipWaiting());
self.addEventListener("activate", (event) => event.waitUntil(self.clients.claim()));

self.addEventListener("fetch", (event) => {
  const url = new URL(event.request.url);
  if (event.request.method !== "GET" || !url.searchParams.has("v") || !url.pathname.includes("/python/")) return;
  event.respondWith(
    caches.open("ejsweb")
      .then((store) => store.match(event.request))
      .catch(() => undefined)
      .then((hit) => hit || fetch(event.request)),
  );
});
