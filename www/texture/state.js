// Texture's document and what a mounted panel derives from it. The
// document is {source, predicted, scales, sameModel, retrieved}; its schema
// is src/texture/state.rs. History, autosave, project files and links come
// from the document controller (app/document.js).
//
// The scales are computational estimates, not human ratings (see
// src/texture/scales.rs; `filigree build-index --ratings` replaces them):
// an example's scales are measured on it (its four corner windows), and
// only an index built on ratings predicts them with its classifiers.
import { IndexError, models, withIndex } from './index-loader.js';
import { grayPng } from './pictures.js';
import { greyPixels, paethFilter, greyFromLink } from './link.js';

export const SIDE = 256; // rendered textures, pixels a side (the index's size)
export const SCALES = ['contrast', 'repetition', 'granularity', 'randomness', 'roughness', 'feature_density',
  'directionality', 'structural_complexity', 'coarseness', 'regularity', 'local_orientation', 'uniformity'];
export const label = (name) => name.replace(/_/g, ' ').replace(/^./, (c) => c.toUpperCase());
export const DEFAULT_MODEL = 'texton-regular';

export const same = (a, b) => a === b || (Array.isArray(a) && Array.isArray(b) && a.length === b.length && a.every((v, i) => v === b[i]));
export const keyOf = (r) => (r ? `${r.model}|${r.params.join(',')}|${r.seed}` : '');
export const sourceKey = (s) => (!s ? '' : s.kind === 'model' ? `m|${s.model}|${s.params.join(',')}|${s.seed}` : `i|${s.name}|${s.png.length}|${s.png.slice(0, 64).join(',')}|${s.png.slice(-64).join(',')}`);

/** The predicted part of a document from a `texture-analyse` answer: the model, the scale
 * estimates, the three likeliest models with their probabilities, and whether any is close. */
export const predictedOf = (a) => {
  // The shape the core's document check gives back (state.rs): `top` left
  // out when empty and `close` when true, so a link or a project opens equal.
  const p = { model: a.model, scales: [...a.scales] };
  const top = (a.top || []).map((c) => ({ model: c.model, probability: c.probability }));
  if (top.length) p.top = top;
  if (a.close === false) p.close = false;
  return p;
};

/** The retrieved part of a document from a `texture-retrieve` answer. */
export const retrievedOf = (r) => ({ model: r.model, params: r.params, seed: r.seed, sample: r.sample, scales: [...r.scales], cosine: r.cosine, edited: false });

export const textureState = {
  version: 1,
  async defaults(ctx) {
    // The default example: a model rendered and analysed, its nearest texture retrieved.
    const list = await models(ctx.run);
    const m = list.find((x) => x.id === DEFAULT_MODEL) || list[0];
    const doc = { source: { kind: 'model', model: m.id, params: m.params.map((p) => p.default), seed: 1 }, predicted: null, scales: Array(12).fill(5), sameModel: false, retrieved: null };
    try {
      const img = await ctx.run('texture-render', { model: m.id, params: doc.source.params, seed: 1, size: SIDE });
      const a = await withIndex(ctx.run, 'texture-analyse', { bytes: await grayPng(img.gray, SIDE) }, { transfer: [] });
      doc.predicted = predictedOf(a);
      doc.scales = [...a.scales];
      const r = await withIndex(ctx.run, 'texture-retrieve', { scales: doc.scales, model: '', size: 0 });
      doc.retrieved = retrievedOf(r);
    } catch (err) {
      if (err?.kind === 'cancelled') throw err;
      ctx.error(err, { prefix: err instanceof IndexError ? 'Texture index' : 'Texture', source: 'index' });
    }
    return doc;
  },
  migrate: (raw) => raw,
  fileName: (s) => `texture-${s.retrieved?.model || s.source?.model || 'example'}`,
  // A link carries the example: its grey pixels (see greyPixels above), or
  // a colour PNG's bytes; one too big for a link leaves it out, and the page
  // says so before copying (document.js).
  async toShare(s) {
    if (s.source?.kind !== 'image') return s;
    const px = await greyPixels(s.source.png);
    if (!px) return s;
    const grey = { width: px.width, height: px.height, filtered: paethFilter(px.grey, px.width, px.height, false) };
    return { ...s, source: { kind: 'image', name: s.source.name, grey } };
  },
  async fromShare(x) {
    if (x?.source?.kind !== 'image' || !x.source.grey) return x;
    const { grey, ...source } = x.source;
    return { ...x, source: { ...source, png: await greyFromLink(grey) } };
  },
  shareLean: (s) => (s.source?.kind === 'image' ? { state: { ...s, source: null }, omits: 'the example' } : null),
};

/**
 * What a mounted panel derives from the document (not saved), shared by its
 * parts: the model list, the retrieved texture drawn, whether the index loaded.
 */
export const createLive = () => ({
  list: [], // the models
  shown: null, // {key, image: ImageData} of the retrieved texture drawn
  indexOk: false,
});
