// Make the geopattern designs (gp-*.svg) of this set from the npm package
// `geopattern` (MIT, Jason Long and Brandon Mills), unmodified geometry.
//
// What is chosen here, per design:
//  * the generator and the 40-hex-digit `hash` option (geopattern reads its
//    sizes and each cell's shade from the hash; a regular hash, e.g. digits
//    alternating by column, gives a regular design instead of a random 6×6
//    mosaic of shades);
//  * a scale and an offset (like CSS background-size / background-position)
//    for tiling geopattern's tile over a 256×256 square.
// What is changed from geopattern's SVG (and only this):
//  * its translucent #ddd / #222 overlays are flattened to opaque colours
//    (composited over the background colour with their own opacity), so the
//    targets have 2–3 flat colours; where shapes overlap, the later one now
//    hides the earlier one (painter's order) instead of darkening it;
//  * its hairline strokes (#000 at 2 % opacity) are dropped;
//  * the tile is repeated at its exact size (geopattern floors the SVG's
//    width and height to whole px, which would leave sub-px seams).
//
// Usage:
//   mkdir -p /tmp/gp && cd /tmp/gp && npm init -y && npm install geopattern
//   DESIGNS_DEPS=/tmp/gp node /path/to/bench/designs/make-geopattern.mjs [name ...]
import { createRequire } from "node:module";
import { writeFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = process.env.DESIGNS_DIR || dirname(fileURLToPath(import.meta.url));
const deps = process.env.DESIGNS_DEPS || "/tmp/gp";
const require = createRequire(join(deps, "package.json"));
const GeoPattern = require("geopattern");
// geopattern floors the tile's width and height to whole px, which leaves a
// sub-px seam (gap or overlap) at every tile edge; tile at the exact size.
const SVG = require("geopattern/lib/svg");
SVG.prototype.setWidth = function (w) { this.svg.setAttribute("width", w); };
SVG.prototype.setHeight = function (h) { this.svg.setAttribute("height", h); };

const SIZE = 256;

// hash from a function of the cell index i (cell (i % 6, floor(i / 6)) for
// the 6×6 generators); digits past 35 only matter where noted.
function hash(f) {
  let s = "";
  for (let i = 0; i < 40; i++) s += f(i, i % 6, Math.floor(i / 6)).toString(16);
  return s;
}

export const DESIGNS = [
  // name, generator, hash, background colour, scale, offset (px)
  { name: "gp-octogons", generator: "octogons", hash: hash(() => 12),
    color: "#3b6e8f", scale: 0.83, offset: [-9, -40] },
  { name: "gp-hexagons", generator: "hexagons",
    // three shades by (q - r) mod 3 in axial hex coordinates: a 3-colouring
    hash: hash((i, x, y) => [14, 15, 4][(((x - (y - (x - (x & 1)) / 2)) % 3) + 3) % 3]),
    color: "#7a4f8c", scale: 0.34, offset: [-5, -12] },
  { name: "gp-sine-waves", generator: "sineWaves",
    hash: hash((i) => (i % 2 === 0 ? 14 : 11)),
    color: "#2d7d6f", scale: 0.45, offset: [-30, 6] },
  { name: "gp-triangles", generator: "triangles",
    hash: hash((i, x, y) => ((x + y) % 2 === 0 ? 12 : 15)),
    color: "#b5653a", scale: 0.74, offset: [-14, -10] },
  { name: "gp-diamonds", generator: "diamonds",
    hash: hash((i, x, y) => (y % 2 === 0 ? 11 : 10)),
    color: "#94405b", scale: 1.18, offset: [-17, -9] },
  { name: "gp-nested-squares", generator: "nestedSquares", hash: hash(() => 14),
    color: "#4d5e91", scale: 0.78, offset: [-23, -14] },
  { name: "gp-concentric-circles", generator: "concentricCircles",
    hash: hash(() => 13), color: "#8f6a2e", scale: 0.71, offset: [-6, -31] },
  { name: "gp-tessellation", generator: "tessellation", hash: hash(() => 15),
    color: "#3f7f4c", scale: 0.5, offset: [-37, -18] },
  { name: "gp-squares", generator: "squares",
    hash: hash((i, x, y) => ((x + y) % 2 === 0 ? 8 : 15)),
    color: "#6c3f8a", scale: 0.93, offset: [-12, -25] },
  { name: "gp-chevrons", generator: "chevrons",
    hash: hash((i, x, y) => (y % 2 === 0 ? 10 : 15)),
    color: "#2f6f8f", scale: 0.61, offset: [-11, -4] },
];

const hex2 = (v) => Math.round(v).toString(16).padStart(2, "0");
function parseColour(c) {
  let m = c.match(/^rgb\((\d+),\s*(\d+),\s*(\d+)\)$/);
  if (m) return [+m[1], +m[2], +m[3]];
  m = c.match(/^#([0-9a-f])([0-9a-f])([0-9a-f])$/i);
  if (m) return [1, 2, 3].map((k) => parseInt(m[k] + m[k], 16));
  m = c.match(/^#([0-9a-f]{2})([0-9a-f]{2})([0-9a-f]{2})$/i);
  if (m) return [1, 2, 3].map((k) => parseInt(m[k], 16));
  throw new Error(`colour ${c}`);
}
const toHex = (rgb) => "#" + rgb.map(hex2).join("");
const over = (fg, a, bg) => fg.map((f, k) => a * f + (1 - a) * bg[k]);

function attrs(s) {
  const out = [];
  for (const m of s.matchAll(/([\w:-]+)="([^"]*)"/g)) out.push([m[1], m[2]]);
  return out;
}

// Flatten geopattern's translucent overlays over `bg`.
function flatten(tile, bg) {
  return tile.replace(/<(\w+)((?:\s+[\w:-]+="[^"]*")*)\s*(\/?)>/g, (m, tag, a, selfClose) => {
    const map = new Map(attrs(a));
    if (map.get("stroke") === "#000" && map.get("stroke-opacity") === "0.02") {
      map.delete("stroke");
      map.delete("stroke-opacity");
      map.delete("stroke-width");
    }
    const alpha = +(map.get("fill-opacity") ?? map.get("opacity") ?? 1);
    const fill = map.get("fill");
    if (fill && fill !== "none") map.set("fill", toHex(over(parseColour(fill), alpha, bg)));
    const stroke = map.get("stroke");
    if (stroke && stroke !== "none") {
      const sa = +(map.get("stroke-opacity") ?? map.get("opacity") ?? 1);
      map.set("stroke", toHex(over(parseColour(stroke), sa, bg)));
      map.delete("stroke-opacity");
    }
    map.delete("fill-opacity");
    map.delete("opacity");
    const as = [...map].map(([k, v]) => ` ${k}="${v}"`).join("");
    return `<${tag}${as}${selfClose ? " /" : ""}>`;
  });
}

function build(d) {
  const p = GeoPattern.generate(d.name, { generator: d.generator, hash: d.hash, color: d.color });
  const svg = p.toSvg();
  const W = +svg.match(/<svg[^>]*\swidth="([\d.e+-]+)"/)[1];
  const H = +svg.match(/<svg[^>]*\sheight="([\d.e+-]+)"/)[1];
  const bgm = svg.match(/<rect x="0" y="0" width="100%" height="100%" fill="([^"]+)"><\/rect>/);
  const bg = parseColour(bgm[1]);
  const inner = svg
    .replace(/^<svg[^>]*>/, "")
    .replace(/<\/svg>\s*$/, "")
    .replace(bgm[0], "");
  const tile = flatten(inner, bg);
  const [ox, oy] = d.offset;
  const k = d.scale;
  const uses = [];
  const c0 = Math.floor(-ox / (k * W)) - 1, c1 = Math.ceil((SIZE - ox) / (k * W));
  const r0 = Math.floor(-oy / (k * H)) - 1, r1 = Math.ceil((SIZE - oy) / (k * H));
  for (let r = r0; r <= r1; r++)
    for (let c = c0; c <= c1; c++) uses.push(`<use href="#tile" x="${c * W}" y="${r * H}" />`);
  return `<svg xmlns="http://www.w3.org/2000/svg" width="${SIZE}" height="${SIZE}" viewBox="0 0 ${SIZE} ${SIZE}">
<!-- ${d.name}: geopattern (npm, MIT) generator "${d.generator}", hash ${d.hash},
     colour ${d.color}; tile ${W} x ${H} geopattern px, scaled by ${k} and offset by
     (${ox}, ${oy}) px (tile at the exact, unfloored size); overlays flattened to opaque colours, 2% hairline strokes dropped.
     Made by make-geopattern.mjs. -->
<defs><g id="tile">${tile}</g></defs>
<rect x="0" y="0" width="${SIZE}" height="${SIZE}" fill="${toHex(bg)}" />
<g transform="translate(${ox} ${oy}) scale(${k})">
${uses.join("\n")}
</g>
</svg>
`;
}

const only = process.argv.slice(2).filter((a) => !a.startsWith("--"));
for (const d of DESIGNS) {
  if (only.length && !only.includes(d.name)) continue;
  writeFileSync(join(here, `${d.name}.svg`), build(d));
  console.log(`wrote ${d.name}.svg`);
}
