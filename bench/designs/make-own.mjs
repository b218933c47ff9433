// Write the hand-made designs of this set (classic CSS-gallery-style
// repeating backgrounds, drawn as plain SVG on a 256×256 square; MIT, own
// work). Each design's numbers are written out below in px; the SVG is
// explicit shapes (no <pattern>), so both renders are exact.
//
// Usage: node /path/to/bench/designs/make-own.mjs [name ...]   (no dependencies)
import { writeFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = process.env.DESIGNS_DIR || dirname(fileURLToPath(import.meta.url));
const S = 256;
const f = (v) => +v.toFixed(3);
const range = (a, b) => Array.from({ length: b - a + 1 }, (_, k) => a + k);
// Lattice indices whose copies can reach the canvas (generous margins).
const span = (o, p, m = 2) => range(Math.floor(-o / p) - m, Math.ceil((S - o) / p) + m);

function svg(name, note, bg, body) {
  return `<svg xmlns="http://www.w3.org/2000/svg" width="${S}" height="${S}" viewBox="0 0 ${S} ${S}">
<!-- ${name}: ${note} (own work, MIT). Made by make-own.mjs. -->
<rect x="0" y="0" width="${S}" height="${S}" fill="${bg}" />
${body.join("\n")}
</svg>
`;
}

const D = {};

// Diagonal stripes at 45° ("/"), like repeating-linear-gradient(45deg, …):
// stripe width 13 px every 34 px measured across the stripes.
D["diagonal-stripes"] = () => {
  const P = 34, w = 13, phase = 9;
  const body = ['<g transform="rotate(-45 128 128)">'];
  for (let k = -7; k <= 7; k++)
    body.push(`<rect x="-120" y="${128 + k * P + phase}" width="496" height="${w}" fill="#f4d35e" />`);
  body.push("</g>");
  return svg("diagonal-stripes", `45° stripes, width ${w} px, period ${P} px across, phase ${phase} px`, "#0d3b66", body);
};

// Polka dots: two dots per 46 px square cell (at the corner and the centre),
// like two radial-gradient layers offset by half a cell.
D["polka-dots"] = () => {
  const d = 46, r = 10.5, ox = 14, oy = 9;
  const body = [];
  for (const j of span(oy, d)) for (const i of span(ox, d)) {
    body.push(`<circle cx="${ox + i * d}" cy="${oy + j * d}" r="${r}" fill="#e4572e" />`);
    body.push(`<circle cx="${ox + i * d + d / 2}" cy="${oy + j * d + d / 2}" r="${r}" fill="#e4572e" />`);
  }
  return svg("polka-dots", `dots r ${r} px, cell ${d} px with a dot at the corner and the centre, origin (${ox}, ${oy})`, "#fbeee0", body);
};

// Seigaiha (blue ocean waves / fish scales): scales of radius R on rows R/2
// apart, each row shifted by R, each drawn over the row above; every scale
// is a navy disc with a light rim and three concentric light rings.
D["seigaiha"] = () => {
  const R = 30, ox = 21, oy = 4, w = 3.2;
  const body = [];
  for (let row = -4; row <= Math.ceil((S - oy) / (R / 2)) + 2; row++) {
    const c0 = Math.floor((-R - ox - row * R) / (2 * R)) - 1;
    const c1 = Math.ceil((S + R - ox - row * R) / (2 * R)) + 1;
    for (let col = c0; col <= c1; col++) {
      const cx = f(ox + col * 2 * R + row * R), cy = f(oy + row * R / 2);
      body.push(`<circle cx="${cx}" cy="${cy}" r="${R - w / 2}" fill="#1d3557" stroke="#f1faee" stroke-width="${w}" />`);
      for (const q of [0.75, 0.5, 0.25])
        body.push(`<circle cx="${cx}" cy="${cy}" r="${q * R}" fill="none" stroke="#f1faee" stroke-width="${w}" />`);
    }
  }
  return svg("seigaiha", `scale radius ${R} px (outer edge), rows ${R / 2} px apart shifted ${R} px, rings at 0.75/0.5/0.25 R, line ${w} px, origin (${ox}, ${oy})`, "#f1faee", body);
};

// Honeycomb outline: flat-topped hexagons of circumradius a, walls only.
D["honeycomb-outline"] = () => {
  const a = 19, ox = 7, oy = 12, w = 4;
  const h = Math.sqrt(3) * a;
  const body = [];
  for (const i of span(ox, 1.5 * a, 3)) for (const j of span(oy, h, 2)) {
    const cx = ox + i * 1.5 * a, cy = oy + (j + 0.5 * (((i % 2) + 2) % 2)) * h;
    const pts = range(0, 5).map((k) => `${f(cx + a * Math.cos(k * Math.PI / 3))},${f(cy + a * Math.sin(k * Math.PI / 3))}`);
    body.push(`<polygon points="${pts.join(" ")}" fill="none" stroke="#9c6644" stroke-width="${w}" />`);
  }
  return svg("honeycomb-outline", `flat-topped hexagon walls, circumradius ${a} px, wall ${w} px, a centre at (${ox}, ${oy})`, "#ffe8a3", body);
};

// Graph paper: minor lines every 17 px (2 px), a major line every 4 minor
// cells (4 px), majors drawn over minors.
D["graph-paper-major"] = () => {
  const d = 17, n = 4, ox = 11.4, oy = 23.7, wm = 2, wM = 4;
  const body = [];
  for (const k of span(ox, d)) body.push(`<rect x="${ox + k * d - wm / 2}" y="0" width="${wm}" height="${S}" fill="#bcd7ee" />`);
  for (const k of span(oy, d)) body.push(`<rect x="0" y="${oy + k * d - wm / 2}" width="${S}" height="${wm}" fill="#bcd7ee" />`);
  for (const k of span(ox, n * d)) body.push(`<rect x="${ox + k * n * d - wM / 2}" y="0" width="${wM}" height="${S}" fill="#4a90c8" />`);
  for (const k of span(oy, n * d)) body.push(`<rect x="0" y="${oy + k * n * d - wM / 2}" width="${S}" height="${wM}" fill="#4a90c8" />`);
  return svg("graph-paper-major", `minor lines ${wm} px every ${d} px, major lines ${wM} px every ${n * d} px, a major crossing at (${ox}, ${oy})`, "#ffffff", body);
};

// Tartan (flat colours): dark bands across both ways on red, darker where
// they cross, a thin yellow line both ways halfway between bands, on top.
D["tartan"] = () => {
  const P = 72, b = 24, t = 3, ox = 17.6, oy = 30.3, lo = 36;
  const body = [];
  for (const k of span(oy, P)) body.push(`<rect x="0" y="${oy + k * P}" width="${S}" height="${b}" fill="#1f3b2c" />`);
  for (const k of span(ox, P)) body.push(`<rect x="${ox + k * P}" y="0" width="${b}" height="${S}" fill="#1f3b2c" />`);
  for (const j of span(oy, P)) for (const i of span(ox, P))
    body.push(`<rect x="${ox + i * P}" y="${oy + j * P}" width="${b}" height="${b}" fill="#14261d" />`);
  for (const k of span(oy, P)) body.push(`<rect x="0" y="${oy + k * P + b / 2 + lo - t / 2}" width="${S}" height="${t}" fill="#f2c14e" />`);
  for (const k of span(ox, P)) body.push(`<rect x="${ox + k * P + b / 2 + lo - t / 2}" y="0" width="${t}" height="${S}" fill="#f2c14e" />`);
  return svg("tartan", `period ${P} px, dark bands ${b} px starting at (${ox}, ${oy}), yellow lines ${t} px, ${lo} px from band centre`, "#b22234", body);
};

// Brick wall (running bond): bricks 52 × 21 px, 4 px mortar, every other
// course shifted by half a brick.
D["brick-wall"] = () => {
  const L = 56, H = 25, g = 4, ox = 19.3, oy = 8.6; // (ox, oy): a brick's centre
  const body = [];
  for (const r of span(oy, H)) for (const c of span(ox, L)) {
    const cx = ox + c * L + (((r % 2) + 2) % 2) * L / 2, cy = oy + r * H;
    body.push(`<rect x="${cx - (L - g) / 2}" y="${cy - (H - g) / 2}" width="${L - g}" height="${H - g}" fill="#a0462e" />`);
  }
  return svg("brick-wall", `bricks ${L - g} x ${H - g} px, mortar ${g} px, course ${H} px, half-brick bond, a brick centred at (${ox}, ${oy})`, "#ddd3c4", body);
};

// Shippo (seven treasures): outlined circles of radius r at (2r i, 2r j) and
// (2r i + r, 2r j + r), so each meets its four neighbours at quarter points.
D["shippo"] = () => {
  const r = 28, ox = 9, oy = 17, w = 3;
  const body = [];
  for (const row of span(oy, r, 3)) for (const col of span(ox, 2 * r, 3)) {
    const cx = ox + col * 2 * r + (((row % 2) + 2) % 2) * r, cy = oy + row * r;
    body.push(`<circle cx="${cx}" cy="${cy}" r="${r}" fill="none" stroke="#d4a73c" stroke-width="${w}" />`);
  }
  return svg("shippo", `outlined circles r ${r} px on a lattice (2r, 0), (r, r), line ${w} px, a centre at (${ox}, ${oy})`, "#1e2d4f", body);
};

// Cross-hatch: two families of thin lines at +45° and −45°, 20 px apart
// (measured across), 3 px wide.
D["cross-hatch"] = () => {
  const P = 20, w = 3, p1 = 6, p2 = 13;
  const body = [];
  for (const [ang, ph] of [[-45, p1], [45, p2]]) {
    body.push(`<g transform="rotate(${ang} 128 128)">`);
    for (let k = -10; k <= 10; k++)
      body.push(`<rect x="-120" y="${128 + k * P + ph - w / 2}" width="496" height="${w}" fill="#3d405b" />`);
    body.push("</g>");
  }
  return svg("cross-hatch", `lines ${w} px every ${P} px across at -45° (phase ${p1}) and +45° (phase ${p2}) about the centre`, "#f7f3e3", body);
};

const only = process.argv.slice(2);
for (const [name, make] of Object.entries(D)) {
  if (only.length && !only.includes(name)) continue;
  writeFileSync(join(here, `${name}.svg`), make());
  console.log(`wrote ${name}.svg`);
}
