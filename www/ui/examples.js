// A tool's shipped examples (grammars, scenes, ...): fetched once per page
// from the core's `<tool>-examples` request kind, and the share-link rule
// that a shipped example travels by name, its text filled in again on
// arrival.

const cache = new Map(); // request kind → promise of the list

/** `(run) → Promise<[{name, ...}]>` for request `kind`; a failed fetch is retried next time. */
export function shippedExamples(kind) {
  return (run) => {
    if (!cache.has(kind)) cache.set(kind, run(kind, {}).catch((e) => { cache.delete(kind); throw e; }));
    return cache.get(kind);
  };
}

/** An error about document field `field`, as the document controller shows it. */
export function invalid(field, why) {
  const e = new Error(`${field} ${why}`);
  e.field = field;
  return e;
}

/**
 * `toShare`/`fromShare` for a document whose `text` field (e.g. `grammar`)
 * holds the text of the shipped example named by its `example` field:
 * the link carries the name only. `tool` and `what` name things in errors.
 */
export function shareByExample(examples, text, { tool, what }) {
  return {
    toShare: (s) => ({ ...s, [text]: s.example ? null : s[text] }),
    async fromShare(x, ctx) {
      if (!x || typeof x !== 'object' || Array.isArray(x)) throw invalid('state', `is not a ${tool} document`);
      if (x[text] == null && x.example != null) {
        const ex = (await examples(ctx.run)).find((e) => e.name === x.example);
        if (!ex) throw invalid('example', `is not a shipped ${what}`);
        return { ...x, [text]: ex[text] };
      }
      return x;
    },
  };
}
