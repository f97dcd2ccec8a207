"""A lab running in the browser (``ejsgen build --web``): the Python side of the page.

- :mod:`ejsrl.web.lab`: ``WebLab`` (the served app's ``App`` and ``ViserView`` behind one page),
  what the page's worker calls once per display frame, and ``headless_csv``;
- :mod:`ejsrl.web._server`: viser's own ``ViserServer`` whose websocket is the page;
- :mod:`ejsrl.web._msgpack`: the MessagePack codec standing in for msgspec's;
- :mod:`ejsrl.web._absent`: what the WebAssembly Python lacks (sockets, threads, OpenCV),
  importable and refusing plainly when used.

Nothing here is imported by a served or headless app.
"""
