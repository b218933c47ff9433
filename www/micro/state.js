// Micro's document and what a mounted panel derives from it. The document
// is {example, scene, camera, steps, view, z, shading, roughness, specular,
// absorption, spp, max_depth} (version 2; version 1 documents get the
// request's defaults); its schema is src/micro/state.rs. History, autosave,
// project files and links come from the document controller
// (app/document.js).
import { shippedExamples, shareByExample } from '../ui/examples.js';

export const DEFAULT_CAMERA = { yaw: 35, pitch: 28, distance: 3.6, target: [0, 0, 0] };
const SHADING_DEFAULTS = { shading: 'lambert', roughness: 0.35, specular: 0.04, absorption: 0, spp: 0, max_depth: 4 };

// Shipped scenes: fetched once per page, their JSON pretty-printed (two
// spaces, a key a line) so the editor shows one field a line; the numbers
// read back as the same numbers.
const shipped = shippedExamples('micro-examples');
let prettyOf = null; // {list: the core's list, pretty: the same, pretty-printed}
export const prettyScene = (text) => {
  try { return JSON.stringify(JSON.parse(text), null, 2); } catch { return text; }
};
export const examples = (run) => shipped(run).then((list) => {
  if (prettyOf?.list !== list) prettyOf = { list, pretty: list.map((ex) => ({ ...ex, scene: prettyScene(ex.scene) })) };
  return prettyOf.pretty;
});

export const microState = {
  version: 2,
  async defaults(ctx) {
    const list = await examples(ctx.run);
    const ex = list.find((e) => e.name === 'gyroid') || list[0];
    return { example: ex.name, scene: ex.scene, camera: { ...DEFAULT_CAMERA, target: [...DEFAULT_CAMERA.target] }, steps: 'fixed', view: 'render', z: 0, ...SHADING_DEFAULTS };
  },
  // Version 1 had no shading fields: the request's defaults (what it drew).
  migrate: (raw, version) => (version < 2 && raw && typeof raw === 'object' && !Array.isArray(raw) ? { ...SHADING_DEFAULTS, ...raw } : raw),
  fileName: (s) => s.example || 'micro',
  // A shipped scene travels by name.
  ...shareByExample(examples, 'scene', { tool: 'Micro', what: 'scene' }),
};

export const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
export const sameCamera = (a, b) => a === b || (a.yaw === b.yaw && a.pitch === b.pitch && a.distance === b.distance
  && a.target.every((v, i) => v === b.target[i]));
/** Whether documents a and b draw the same picture. */
export const sameShading = (a, b) => a.shading === b.shading && a.roughness === b.roughness && a.specular === b.specular
  && a.absorption === b.absorption && a.spp === b.spp && a.max_depth === b.max_depth;
export const samePicture = (a, b) => a.scene === b.scene && a.steps === b.steps && a.view === b.view
  && (a.view === 'render' ? sameCamera(a.camera, b.camera) && sameShading(a, b) : a.z === b.z && sameCamera(a.camera, b.camera));
/** The shading fields of a `micro-render` request. */
export const shadingOf = (doc) => ({
  shading: doc.shading ?? 'lambert', roughness: doc.roughness ?? 0.35, specular: doc.specular ?? 0.04, absorption: doc.absorption ?? 0,
});

/** The request [kind, payload] of document `doc`'s picture, `side` pixels a side. */
export function requestOf(doc, side) {
  if (doc.view === 'slice') {
    // The slice looks at the camera's target; its half width follows the zoom.
    const half = doc.camera.distance / DEFAULT_CAMERA.distance;
    return ['micro-slice', { scene: doc.scene, z: doc.z, center: [doc.camera.target[0], doc.camera.target[1]], half, width: side, height: side }];
  }
  return ['micro-render', {
    scene: doc.scene, width: side, height: side, steps: doc.steps,
    camera: { yaw: doc.camera.yaw, pitch: doc.camera.pitch, distance: doc.camera.distance, target: doc.camera.target },
    ...shadingOf(doc), spp: doc.spp ?? 0, max_depth: doc.max_depth ?? 4,
  }];
}

/**
 * What a mounted panel derives from the document (not saved), shared by its
 * parts: the picture shown and the drag under way.
 */
export const createLive = () => ({
  last: null, // what the canvas shows: {width, height, kind, preview, stats, gpu, tiles?, passes?, frame?}
  bitmap: null, // the CPU picture drawn (an ImageBitmap, or the tiles' canvas)
  gesture: null, // a drag in progress: {x, y, id, pan, moved}
});
