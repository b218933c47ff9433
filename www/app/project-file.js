// Project files (MISSION S8): a tool's document saved as one JSON file,
// byte inputs (images) encoded as {"$bytes": base64}. Reading one back
// (envelope, bytes, the tool's state) is the core's `open-project`
// (src/api/project.rs), which knows the same format.

export const PROJECT_FORMAT = 'filigree-project';
// File format 2 adds `stateVersion` (the tool's state schema version);
// format-1 files carry tool states of version 1.
export const PROJECT_VERSION = 2;

function toBase64(bytes) {
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(s);
}

function encode(v) {
  if (v instanceof Uint8Array) return { $bytes: toBase64(v) };
  if (Array.isArray(v)) return v.map(encode);
  if (v && typeof v === 'object') return Object.fromEntries(Object.entries(v).map(([k, x]) => [k, encode(x)]));
  return v;
}

/** The text of a project file for `tool` whose state (schema `stateVersion`) is `state`. */
export function projectText(tool, stateVersion, state) {
  return JSON.stringify({ format: PROJECT_FORMAT, version: PROJECT_VERSION, tool, stateVersion, state: encode(state) });
}
