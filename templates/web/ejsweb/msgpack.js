// MessagePack for the lab's in-page channel (ejsgen build --web): the subset viser's messages
// use, with the types viser's client gets from @msgpack/msgpack: maps are plain objects,
// `bin` is a Uint8Array, integers are numbers. Both directions throw on malformed data.

const te = new TextEncoder();
const td = new TextDecoder("utf-8", { fatal: true });

/** The one value in `bytes` (a Uint8Array). */
export function decode(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let pos = 0;
  const need = (n) => {
    if (pos + n > bytes.length) throw new Error("msgpack: truncated data");
  };
  const u8 = () => { need(1); return bytes[pos++]; };
  const u16 = () => { need(2); const v = view.getUint16(pos); pos += 2; return v; };
  const u32 = () => { need(4); const v = view.getUint32(pos); pos += 4; return v; };
  const str = (n) => { need(n); const s = td.decode(bytes.subarray(pos, pos + n)); pos += n; return s; };
  const bin = (n) => { need(n); const b = bytes.slice(pos, pos + n); pos += n; return b; };
  const arr = (n, depth) => { const out = new Array(n); for (let i = 0; i < n; i++) out[i] = read(depth + 1); return out; };
  const map = (n, depth) => {
    const out = {};
    for (let i = 0; i < n; i++) { const k = read(depth + 1); out[k] = read(depth + 1); }
    return out;
  };
  function read(depth) {
    if (depth > 64) throw new Error("msgpack: nested too deeply");
    const b = u8();
    if (b < 0x80) return b;
    if (b >= 0xe0) return b - 0x100;
    if (b >= 0xa0 && b <= 0xbf) return str(b & 0x1f);
    if (b >= 0x90 && b <= 0x9f) return arr(b & 0x0f, depth);
    if (b >= 0x80 && b <= 0x8f) return map(b & 0x0f, depth);
    switch (b) {
      case 0xc0: return null;
      case 0xc2: return false;
      case 0xc3: return true;
      case 0xc4: return bin(u8());
      case 0xc5: return bin(u16());
      case 0xc6: return bin(u32());
      case 0xca: { need(4); const v = view.getFloat32(pos); pos += 4; return v; }
      case 0xcb: { need(8); const v = view.getFloat64(pos); pos += 8; return v; }
      case 0xcc: return u8();
      case 0xcd: return u16();
      case 0xce: return u32();
      case 0xcf: { need(8); const v = Number(view.getBigUint64(pos)); pos += 8; return v; }
      case 0xd0: { need(1); const v = view.getInt8(pos); pos += 1; return v; }
      case 0xd1: { need(2); const v = view.getInt16(pos); pos += 2; return v; }
      case 0xd2: { need(4); const v = view.getInt32(pos); pos += 4; return v; }
      case 0xd3: { need(8); const v = Number(view.getBigInt64(pos)); pos += 8; return v; }
      case 0xd9: return str(u8());
      case 0xda: return str(u16());
      case 0xdb: return str(u32());
      case 0xdc: return arr(u16(), depth);
      case 0xdd: return arr(u32(), depth);
      case 0xde: return map(u16(), depth);
      case 0xdf: return map(u32(), depth);
      default: throw new Error("msgpack: unsupported type byte 0x" + b.toString(16));
    }
  }
  const value = read(0);
  if (pos !== bytes.length) throw new Error("msgpack: bytes left after the value");
  return value;
}

/** `value` as MessagePack bytes (a Uint8Array), as @msgpack/msgpack writes it. */
export function encode(value) {
  let buf = new Uint8Array(256);
  let view = new DataView(buf.buffer);
  let pos = 0;
  const room = (n) => {
    if (pos + n <= buf.length) return;
    const bigger = new Uint8Array(Math.max(buf.length * 2, pos + n));
    bigger.set(buf);
    buf = bigger;
    view = new DataView(buf.buffer);
  };
  const put = (...bytes) => { room(bytes.length); for (const b of bytes) buf[pos++] = b; };
  const head = (n, fix, fixMax, w16, w32) => {
    if (n <= fixMax) put(fix | n);
    else if (n < 0x10000) { put(w16); room(2); view.setUint16(pos, n); pos += 2; }
    else { put(w32); room(4); view.setUint32(pos, n); pos += 4; }
  };
  function write(v, depth) {
    if (depth > 64) throw new Error("msgpack: nested too deeply");
    if (v === null || v === undefined) put(0xc0);
    else if (v === true) put(0xc3);
    else if (v === false) put(0xc2);
    else if (typeof v === "number") {
      if (Number.isSafeInteger(v)) {
        if (v >= 0 && v < 0x80) put(v);
        else if (v < 0 && v >= -32) put(v & 0xff);
        else if (v >= 0) {
          if (v < 0x100) put(0xcc, v);
          else if (v < 0x10000) { put(0xcd); room(2); view.setUint16(pos, v); pos += 2; }
          else if (v < 0x100000000) { put(0xce); room(4); view.setUint32(pos, v); pos += 4; }
          else { put(0xcf); room(8); view.setBigUint64(pos, BigInt(v)); pos += 8; }
        } else {
          if (v >= -0x80) { put(0xd0); room(1); view.setInt8(pos, v); pos += 1; }
          else if (v >= -0x8000) { put(0xd1); room(2); view.setInt16(pos, v); pos += 2; }
          else if (v >= -0x80000000) { put(0xd2); room(4); view.setInt32(pos, v); pos += 4; }
          else { put(0xd3); room(8); view.setBigInt64(pos, BigInt(v)); pos += 8; }
        }
      } else { put(0xcb); room(8); view.setFloat64(pos, v); pos += 8; }
    } else if (typeof v === "string") {
      const b = te.encode(v);
      if (b.length < 32) put(0xa0 | b.length);
      else if (b.length < 0x100) put(0xd9, b.length);
      else if (b.length < 0x10000) { put(0xda); room(2); view.setUint16(pos, b.length); pos += 2; }
      else { put(0xdb); room(4); view.setUint32(pos, b.length); pos += 4; }
      room(b.length); buf.set(b, pos); pos += b.length;
    } else if (ArrayBuffer.isView(v) || v instanceof ArrayBuffer) {
      const b = v instanceof ArrayBuffer ? new Uint8Array(v) : new Uint8Array(v.buffer, v.byteOffset, v.byteLength);
      if (b.length < 0x100) put(0xc4, b.length);
      else if (b.length < 0x10000) { put(0xc5); room(2); view.setUint16(pos, b.length); pos += 2; }
      else { put(0xc6); room(4); view.setUint32(pos, b.length); pos += 4; }
      room(b.length); buf.set(b, pos); pos += b.length;
    } else if (Array.isArray(v)) {
      head(v.length, 0x90, 15, 0xdc, 0xdd);
      for (const item of v) write(item, depth + 1);
    } else if (typeof v === "object") {
      const keys = Object.keys(v);
      head(keys.length, 0x80, 15, 0xde, 0xdf);
      for (const k of keys) { write(k, depth + 1); write(v[k], depth + 1); }
    } else throw new Error("msgpack: cannot encode a " + typeof v);
  }
  write(value, 0);
  return buf.slice(0, pos);
}
