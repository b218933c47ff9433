// Fit's document and what a mounted panel derives from it. The document is
// {generator, program, values, target: {width, height, rgba}, truth,
// result, settings: {budget, loss, seed}} (version 1); its schema is the
// core's, src/pattern/state.rs, applied by the document controller
// (`check-state`). History, autosave, project files and links come from
// the document controller (app/document.js).
import { named, programInfo, rgbOf } from './program.js';

// The target's longer side (a drawn target is square; an upload keeps its
// aspect, and the fit's canvas follows it: src/pattern/state.rs).
export const TARGET_SIZE = 256;
// A target made from known values is drawn anti-aliased, as a user's image
// of the design would be: the target's fields read the outline from the
// edge pixels' coverage, to a fraction of a pixel.
export const TARGET_SUPERSAMPLE = 4;
const BUDGETS = ['quick', 'paper'];
const LOSSES = ['sdf', 'l1', 'pyramid', 'image'];

/** What a mounted panel derives from the document (not saved). */
export function createLive() {
  return {
    info: null, // pattern-info of the shown document's program
    infoKey: null, // its key (program.js keyOf)
    generators: [], // pattern-generators
    job: null, // the fit this panel shows (running or the last one; app/document.js DocJob)
  };
}

/** The `render-pattern` request of `values` drawn as the target `t` would be (make-target, a link's truth). */
export const targetRequest = (program, params) => ({ program, params, size: TARGET_SIZE, supersample: TARGET_SUPERSAMPLE });

/** The `render-pattern` size fields of a picture `k` times the target's, on the target's canvas. */
export const sizeOf = (t, k = 1) => (t ? { size: k * t.width, height: k * t.height } : { size: k * TARGET_SIZE });

export function backgroundTarget(info) {
  const [r, g, b] = rgbOf(info.colours[0]);
  const rgba = new Uint8Array(TARGET_SIZE * TARGET_SIZE * 4);
  for (let i = 0; i < rgba.length; i += 4) { rgba[i] = r; rgba[i + 1] = g; rgba[i + 2] = b; rgba[i + 3] = 255; }
  return { width: TARGET_SIZE, height: TARGET_SIZE, rgba };
}

/** Whether target `t` is blank: one colour everywhere (nothing to fit to). */
const blankTargets = new WeakMap();
export function isBlank(t) {
  if (!t?.rgba) return true;
  if (!blankTargets.has(t)) {
    const px = new Uint32Array(t.rgba.buffer, t.rgba.byteOffset, t.rgba.length >> 2);
    let blank = true;
    for (let i = 1; i < px.length && blank; i++) blank = px[i] === px[0];
    blankTargets.set(t, blank);
  }
  return blankTargets.get(t);
}

/** A fresh document for generator `g` (values at its defaults, an empty target). */
export async function generatorDoc(run, g, base) {
  const info = await programInfo(run, g.source);
  return {
    ...base, generator: g.name, program: g.source, values: info.params.map((p) => p.default),
    target: backgroundTarget(info), truth: null, result: null,
  };
}

function invalid(field, why) {
  const e = new Error(`${field} ${why}`);
  e.field = field;
  return e;
}

const finiteList = (v, field, max = 1000) => {
  if (!Array.isArray(v) || v.length > max || !v.every(Number.isFinite)) throw invalid(field, `must be a list of at most ${max} finite numbers`);
  return [...v];
};

/** A target as palette indices (a hand-drawn one has a few colours, so a link stays small). */
function indexTarget(t) {
  const px = new Uint32Array(t.rgba.buffer, t.rgba.byteOffset, t.rgba.length / 4);
  const palette = [];
  const index = new Map();
  const out = new Uint8Array(px.length);
  for (let i = 0; i < px.length; i++) {
    let k = index.get(px[i]);
    if (k === undefined) {
      if (palette.length === 256) return null;
      k = palette.length;
      index.set(px[i], k);
      palette.push(px[i]);
    }
    out[i] = k;
  }
  return { palette: new Uint8Array(new Uint32Array(palette).buffer), indices: out, width: t.width, height: t.height };
}

// (A link from before uploads kept their aspect has no width and height: square.)
function unindexTarget(x) {
  const width = x?.width ?? TARGET_SIZE;
  const height = x?.height ?? TARGET_SIZE;
  if (!(x?.palette instanceof Uint8Array) || x.palette.length % 4 || !(x.indices instanceof Uint8Array)
    || !Number.isInteger(width) || !Number.isInteger(height) || x.indices.length !== width * height) {
    throw invalid('target', 'is damaged');
  }
  const rgba = new Uint8Array(width * height * 4);
  const n = x.palette.length / 4;
  for (let i = 0; i < x.indices.length; i++) {
    const k = x.indices[i];
    if (k >= n) throw invalid('target', 'is damaged');
    rgba.set(x.palette.subarray(4 * k, 4 * k + 4), 4 * i);
  }
  return { width, height, rgba };
}

export const fitState = {
  version: 1,
  async defaults(ctx) {
    const [generators, d] = await Promise.all([ctx.run('pattern-generators', {}), ctx.coreDefaults()]);
    const g = generators.find((x) => x.name === 'circles-grid') || generators[0];
    const settings = {
      budget: BUDGETS.includes(d.budget) ? d.budget : 'quick',
      loss: LOSSES.includes(d.loss) ? d.loss : 'sdf',
      seed: Number.isInteger(d.seed) ? d.seed : 1,
    };
    return generatorDoc(ctx.run, g, { settings });
  },
  migrate: (raw) => raw,
  fileName: (s) => s.generator || 'pattern',
  // A target made from known values travels as those values (re-rendered on
  // arrival, pixel for pixel); a drawn one as palette indices.
  toShare(s) {
    const { target, ...rest } = s;
    if (!target) return { ...rest, target: null };
    if (s.truth) return { ...rest, target: 'truth' };
    const indexed = indexTarget(target);
    return { ...rest, target: indexed ? { indexed } : target };
  },
  async fromShare(x, ctx) {
    if (!x || typeof x !== 'object' || Array.isArray(x)) throw invalid('state', 'is not a Fit document');
    let target = x.target ?? null;
    if (target === 'truth') {
      const truth = finiteList(x.truth, 'truth');
      if (typeof x.program !== 'string') throw invalid('program', 'is missing');
      const info = await programInfo(ctx.run, x.program);
      const full = await programInfo(ctx.run, x.program, named(info, truth, { integersOnly: true }));
      const r = await ctx.run('render-pattern', targetRequest(x.program, named(full, truth)));
      target = { width: r.width, height: r.height, rgba: r.rgba };
    } else if (target?.indexed) target = unindexTarget(target.indexed);
    return { ...x, target };
  },
};
