// Facts of a pattern program, shared by the document (state.js) and the
// view: its parameters and colours (`pattern-info`), values by name as the
// core's requests want them.

/** `#rrggbb` → [r, g, b]. */
export const rgbOf = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));

/** The values of `values` by name (only the integer ones with `integersOnly`), as pattern-info and fit want them. */
export function named(info, values, { integersOnly = false } = {}) {
  return Object.fromEntries(info.params
    .map((p, i) => [p.name, values[i], p.integer])
    .filter(([, , integer]) => !integersOnly || integer)
    .map(([n, v]) => [n, v]));
}

/** pattern-info of `program` with the integer parameters among `values` (when they belong to it). */
export function programInfo(run, program, ints = {}) {
  return run('pattern-info', { program, params: ints });
}

/** The key of a document's program facts: the program and its integer values. */
export const keyOf = (d, info) => `${d.program}\u0000${info ? JSON.stringify(named(info, d.values, { integersOnly: true })) : ''}`;

/**
 * The facts of document `d`'s program (integer parameters shape it: how
 * many shapes it draws), each program and integer values asked once a
 * mount (`pattern-info`).
 */
export function createProgramFacts(run) {
  const cache = new Map();
  const infoFor = (program, ints) => {
    const key = `${program}\u0000${JSON.stringify(ints)}`;
    if (!cache.has(key)) {
      const p = programInfo(run, program, ints);
      cache.set(key, p);
      p.catch(() => cache.delete(key));
    }
    return cache.get(key);
  };
  return async (d) => {
    const base = await infoFor(d.program, {});
    return base.params.some((p) => p.integer) ? infoFor(d.program, named(base, d.values, { integersOnly: true })) : base;
  };
}
