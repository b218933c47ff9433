// Render every design SVG in this folder to two 256×256 PNG targets:
//   <name>.png       crisp: shape-rendering="crispEdges" on the root, so no
//                    anti-aliasing and only the design's exact flat colours;
//   <name>_hard.png  the same SVG rendered normally (anti-aliased edges).
//
// Usage (from anywhere; nothing is installed in the repository):
//   mkdir -p /tmp/gp && cd /tmp/gp && npm init -y && npm install playwright-core
//   DESIGNS_DEPS=/tmp/gp node /path/to/bench/designs/render.mjs [name ...]
// playwright-core never downloads a browser; it drives the system Chromium
// (CHROMIUM, default /usr/bin/chromium).
import { createRequire } from "node:module";
import { readFileSync, readdirSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = process.env.DESIGNS_DIR || dirname(fileURLToPath(import.meta.url));
const deps = process.env.DESIGNS_DEPS || "/tmp/gp";
const require = createRequire(join(deps, "package.json"));
const { chromium } = require("playwright-core");

const SIZE = 256;
const names = process.argv.slice(2).length
  ? process.argv.slice(2)
  : readdirSync(here)
      .filter((f) => f.endsWith(".svg"))
      .map((f) => f.slice(0, -4))
      .sort();

// Force the root <svg> to 256×256 and optionally add crispEdges to it (the
// property is inherited by every shape in the drawing).
function prepare(svg, crisp) {
  return svg.replace(/<svg\b([^>]*)>/, (m, attrs) => {
    let a = attrs
      .replace(/\swidth="[^"]*"/, "")
      .replace(/\sheight="[^"]*"/, "")
      .replace(/\sshape-rendering="[^"]*"/, "");
    a += ` width="${SIZE}" height="${SIZE}"`;
    if (crisp) a += ' shape-rendering="crispEdges"';
    return `<svg${a}>`;
  });
}

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run"],
});
const page = await browser.newPage({
  viewport: { width: SIZE, height: SIZE },
  deviceScaleFactor: 1,
});
for (const name of names) {
  const svg = readFileSync(join(here, `${name}.svg`), "utf8");
  for (const [crisp, out] of [[true, `${name}.png`], [false, `${name}_hard.png`]]) {
    const html = `<!doctype html><html><head><style>html,body{margin:0;padding:0;` +
      `overflow:hidden;background:#fff}svg{display:block}</style></head>` +
      `<body>${prepare(svg, crisp)}</body></html>`;
    await page.setContent(html);
    await page.screenshot({
      path: join(here, out),
      clip: { x: 0, y: 0, width: SIZE, height: SIZE },
      omitBackground: false,
    });
  }
  console.log(`rendered ${name}`);
}
await browser.close();
