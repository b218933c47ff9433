// A document as the core knows it, for the document controller (document.js)
// and its parts: the tool's defaults (the core's `Default` impls, the only
// copy), the check of a document that comes from outside the page's own
// edits (an autosave, a project file, a link: migrated here first by the
// panel's `migrate`, then made what the tool's module reads by its `toCore`
// (Pixel: its images as PNG), then checked field by field by the core,
// `check-state`), and the core's "none" made the documents' null.
//
//   await coreDefaults(pool, tool)            → the tool's default request(s), a fresh copy
//   await checkState(pool, tool, raw, version) → the normalised state, or a plain Error
//   nulls(value)                              → value with every undefined made null (in place)

/**
 * Plain data from the core with every `undefined` made `null` (the core's
 * "none" arrives as `undefined`; documents use `null`). In place.
 */
export function nulls(v) {
  if (Array.isArray(v)) {
    for (let i = 0; i < v.length; i++) if (v[i] === undefined || (v[i] && typeof v[i] === 'object')) v[i] = nulls(v[i]);
    return v;
  }
  if (v && typeof v === 'object' && !ArrayBuffer.isView(v)) {
    for (const k of Object.keys(v)) v[k] = nulls(v[k]);
    return v;
  }
  return v === undefined ? null : v;
}

const defaultsCache = new Map();
/** The tool's default request(s), from the core (`defaults` request kind). */
export function coreDefaults(pool, tool) {
  if (!defaultsCache.has(tool)) {
    // The core answers {tool, request, budgets?}: the tool's default request.
    // The core's `Default` impls are the only copy of the defaults.
    const p = pool.run('defaults', { tool }).then((d) => d?.request ?? d).catch((err) => {
      defaultsCache.delete(tool);
      throw err;
    });
    defaultsCache.set(tool, p);
  }
  return defaultsCache.get(tool).then((d) => structuredClone(d));
}

/**
 * Migrate `raw` (schema `version`) for `tool` here, convert it for the
 * tool's module (`state.toCore`, if the tool has one), then have the core
 * check it (`check-state`): resolves with the normalised state, rejects
 * with an Error (a JobError naming the field at fault) in plain words.
 * Every document from outside the page's own edits comes through here
 * (autosave and its history, the other tab's save, links, project files).
 */
export async function checkState(pool, tool, raw, version) {
  const spec = tool.state;
  if (!Number.isInteger(version) || version < 1) throw new Error('the state has no schema version');
  let s = raw;
  if (version < spec.version) {
    if (!spec.migrate) throw new Error(`${tool.title} state version ${version} can no longer be read`);
    s = spec.migrate(s, version);
    version = spec.version;
  }
  if (spec.toCore) s = await spec.toCore(s);
  // Copied, not transferred: `raw` may be a live document.
  return nulls(await pool.run('check-state', { tool: tool.id, version, state: s }, { transfer: [] }));
}
