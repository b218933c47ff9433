// The numbers of a scene for Micro's "Reconstruct" section (fit.js): where
// each is (an RFC 6901 JSON pointer), how to set one, a default range.

const MAX_ROWS = 24; // numbers of the scene offered for fitting

/** Every number in a JSON value: [{pointer, value, integer}], document order. */
export function numbersOf(value, pointer = '', out = []) {
  if (out.length >= MAX_ROWS) return out;
  if (typeof value === 'number') out.push({ pointer, value, integer: Number.isInteger(value) });
  else if (Array.isArray(value)) value.forEach((v, i) => numbersOf(v, `${pointer}/${i}`, out));
  else if (value && typeof value === 'object') {
    for (const [k, v] of Object.entries(value)) numbersOf(v, `${pointer}/${k.replace(/~/g, '~0').replace(/\//g, '~1')}`, out);
  }
  return out;
}

/** The JSON value with `pointer` (RFC 6901) set to `v`. */
export function setPointer(root, pointer, v) {
  const keys = pointer.split('/').slice(1).map((k) => k.replace(/~1/g, '/').replace(/~0/g, '~'));
  let o = root;
  for (const k of keys.slice(0, -1)) o = o[k];
  o[keys[keys.length - 1]] = v;
  return root;
}

/** A default range around a value. */
export function rangeOf(v) {
  if (v === 0) return [-1, 1];
  const a = Math.abs(v);
  return [v - a, v + a].sort((x, y) => x - y).map((x) => Number(x.toPrecision(6)));
}
