// Share links (MISSION S8): a tool's state in the URL fragment, versioned
// and compressed, so a link opened in a fresh browser restores exactly that
// state. Embedding (www/embed.js, `?embed=1#<fragment>`) reuses the same
// fragment.
//
//   const fragment = await encodeShare('pixel', shareState, {version: 2});
//   location.hash = fragment;               // 'tool=pixel&share=<base64url>'
//   const {tool, version, state} = await decodeShare(location.hash);
//
// The payload is `[u32 LE json length][json][blob bytes…]`, deflated with
// CompressionStream('deflate-raw') and written as base64url. Byte inputs
// (Uint8Array) travel as blobs after the JSON, not as base64 inside it, so
// they compress well; the JSON names them `{"$blob": index}`.
//
// A link is untrusted input: decoding is bounded (fragment length, size
// after decompression, nesting depth, blob bounds) and every failure is an
// Error with a plain message. Decoding never touches storage; the caller
// validates the state with the tool's own `validate()` before using it.

/** Version of the link envelope itself (the tool's state has its own `version`). */
export const SHARE_FORMAT = 1;
/**
 * Longest fragment a link may have (96 KB, what the app says links hold);
 * past this `encodeShare` throws a ShareTooBig. Big inputs (a Texture
 * example, a Pixel source) travel in the link, deflated, up to this size;
 * a tool whose state is bigger names what its link leaves out
 * (`state.shareLean`, document.js) or is shared as a project file. Browsers
 * take far longer URLs (Chromium 2 MB); the bound keeps a link something a
 * chat or a mail can carry.
 */
export const MAX_FRAGMENT = 96 * 1024;
/** The size a link holds, in words. */
export const LINK_LIMIT_TEXT = `${MAX_FRAGMENT / 1024} KB`;
/** Decoding stops past this many decompressed bytes (a zip bomb stays small). */
export const MAX_DECOMPRESSED = 1 << 20;
/** A link longer than this is refused before it is even decoded. */
const MAX_INPUT = 256 * 1024;
const MAX_DEPTH = 64;
const TOOL_ID = /^[a-z][a-z0-9-]{0,31}$/;

/** The state does not fit in a link; `size` is the fragment length it would need. */
export class ShareTooBig extends Error {
  constructor(size) {
    super(`This state is too big for a link (${kb(size)} > the ${LINK_LIMIT_TEXT} a link holds). Use Save project to share it as a file.`);
    this.name = 'ShareTooBig';
    this.size = size;
  }
}

/** `bytes` in whole KB, rounded up, as words ('70 KB'). */
export const kb = (bytes) => `${Math.ceil(bytes / 1024)} KB`;

/** A link that cannot be read; the message says why, for people. */
export class LinkError extends Error {
  constructor(message) {
    super(message);
    this.name = 'LinkError';
  }
}

const bad = (why) => new LinkError(`This link is damaged or not a Filigree link: ${why}.`);

// ---- base64url ---------------------------------------------------------------

function toBase64Url(bytes) {
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(s).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
}

function fromBase64Url(text) {
  if (!/^[A-Za-z0-9_-]*$/.test(text)) throw bad('it contains characters a link never has');
  const b64 = text.replace(/-/g, '+').replace(/_/g, '/') + '==='.slice((text.length + 3) % 4);
  let bin;
  try {
    bin = atob(b64);
  } catch {
    throw bad('its data is cut short');
  }
  const out = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
  return out;
}

// ---- compression ---------------------------------------------------------------

async function deflate(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new CompressionStream('deflate-raw'));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}

/** Inflate, stopping with an error once the output passes `limit` bytes. */
async function inflate(bytes, limit) {
  const reader = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate-raw')).getReader();
  const chunks = [];
  let total = 0;
  try {
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      total += value.length;
      if (total > limit) {
        reader.cancel().catch(() => {});
        throw bad(`it unpacks to more than ${limit / (1024 * 1024)} MB`);
      }
      chunks.push(value);
    }
  } catch (err) {
    if (err instanceof LinkError) throw err;
    throw bad('its compressed data is corrupt');
  }
  const out = new Uint8Array(total);
  let at = 0;
  for (const c of chunks) { out.set(c, at); at += c.length; }
  return out;
}

// ---- state ↔ bytes ---------------------------------------------------------------

function pack(value, blobs, depth = 0) {
  if (depth > MAX_DEPTH) throw new Error('the state is nested too deeply to share');
  if (value instanceof Uint8Array) { blobs.push(value); return { $blob: blobs.length - 1 }; }
  if (ArrayBuffer.isView(value)) throw new Error('only byte arrays (Uint8Array) can be shared');
  if (Array.isArray(value)) return value.map((v) => pack(v, blobs, depth + 1));
  if (value && typeof value === 'object') {
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, pack(v, blobs, depth + 1)]));
  }
  if (typeof value === 'number' && !Number.isFinite(value)) throw new Error('the state holds a number that is not finite');
  return value;
}

function unpack(value, blobs, depth = 0) {
  if (depth > MAX_DEPTH) throw bad('its state is nested too deeply');
  if (Array.isArray(value)) return value.map((v) => unpack(v, blobs, depth + 1));
  if (value && typeof value === 'object') {
    const keys = Object.keys(value);
    if (keys.length === 1 && keys[0] === '$blob') {
      const b = blobs[value.$blob];
      if (!Number.isInteger(value.$blob) || !b) throw bad('it refers to data it does not hold');
      return b.slice();
    }
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, unpack(v, blobs, depth + 1)]));
  }
  return value;
}

/**
 * The URL fragment (without '#') that carries `shareState` of tool `toolId`.
 * `version` is the tool's state version (see document.js). Throws a
 * ShareTooBig when the fragment would pass MAX_FRAGMENT characters.
 * @returns {Promise<string>}
 */
export async function encodeShare(toolId, shareState, { version = 1, limit = MAX_FRAGMENT } = {}) {
  if (!TOOL_ID.test(toolId)) throw new Error(`'${toolId}' is not a tool name`);
  const blobs = [];
  const s = pack(shareState, blobs);
  const json = new TextEncoder().encode(JSON.stringify({
    format: SHARE_FORMAT, tool: toolId, version, state: s, blobs: blobs.map((b) => b.length),
  }));
  const total = 4 + json.length + blobs.reduce((a, b) => a + b.length, 0);
  const raw = new Uint8Array(total);
  new DataView(raw.buffer).setUint32(0, json.length, true);
  raw.set(json, 4);
  let at = 4 + json.length;
  for (const b of blobs) { raw.set(b, at); at += b.length; }
  if (raw.length > MAX_DECOMPRESSED) throw new ShareTooBig(Math.ceil(raw.length * 4 / 3));
  const fragment = `tool=${toolId}&share=${toBase64Url(await deflate(raw))}`;
  if (fragment.length > limit) throw new ShareTooBig(fragment.length);
  return fragment;
}

/** Whether a fragment (with or without '#') carries a shared state. */
export function hasShare(fragment) {
  return new URLSearchParams(String(fragment ?? '').replace(/^#/, '')).has('share');
}

/**
 * The state a fragment carries. Throws an Error with a plain message when
 * the link is damaged, hostile or from a newer Filigree.
 * @returns {Promise<{tool: string, version: number, state: any}>}
 */
export async function decodeShare(fragment) {
  const text = String(fragment ?? '').replace(/^#/, '');
  if (text.length > MAX_INPUT) throw bad(`it is longer than ${MAX_INPUT / 1024} KB`);
  const params = new URLSearchParams(text);
  const data = params.get('share');
  if (!data) throw bad('it carries no shared state');
  const raw = await inflate(fromBase64Url(data), MAX_DECOMPRESSED);
  if (raw.length < 4) throw bad('its data is cut short');
  const jsonLen = new DataView(raw.buffer, raw.byteOffset).getUint32(0, true);
  if (jsonLen > raw.length - 4) throw bad('its data is cut short');
  let doc;
  try {
    doc = JSON.parse(new TextDecoder('utf-8', { fatal: true }).decode(raw.subarray(4, 4 + jsonLen)));
  } catch {
    throw bad('its contents are not readable');
  }
  if (!doc || typeof doc !== 'object' || Array.isArray(doc)) throw bad('its contents are not a shared state');
  if (doc.format !== SHARE_FORMAT) {
    if (Number.isInteger(doc.format) && doc.format > SHARE_FORMAT) {
      throw new LinkError('This link was made by a newer Filigree; update Filigree (reload the page) to open it.');
    }
    throw bad('it has no known format');
  }
  if (typeof doc.tool !== 'string' || !TOOL_ID.test(doc.tool)) throw bad('it names no tool');
  const outer = params.get('tool');
  if (outer && outer !== doc.tool) throw bad(`it says both '${outer}' and '${doc.tool}'`);
  if (!Number.isInteger(doc.version) || doc.version < 1) throw bad('its state has no version');
  const lengths = doc.blobs ?? [];
  if (!Array.isArray(lengths) || !lengths.every((n) => Number.isInteger(n) && n >= 0)) throw bad('its data table is wrong');
  const blobs = [];
  let at = 4 + jsonLen;
  for (const n of lengths) {
    if (at + n > raw.length) throw bad('its data is cut short');
    blobs.push(raw.subarray(at, at + n));
    at += n;
  }
  if (at !== raw.length) throw bad('it holds data it does not use');
  return { tool: doc.tool, version: doc.version, state: unpack(doc.state, blobs) };
}
