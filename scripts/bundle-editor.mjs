// Bundles CodeMirror 6 (npm devDependencies) into one minified ES module served
// from our own origin: www/vendor/code-editor.bundle.js. Generated, not
// committed (.gitignore); scripts/build.sh runs this before the precache
// manifest so the service worker ships it for offline use. Without node_modules
// (npm not run) it says so and exits 0: www/ui/code-editor.js then falls back to
// a plain textarea.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const out = path.join(ROOT, 'www/vendor/code-editor.bundle.js');

let esbuild;
try {
  esbuild = await import('esbuild');
} catch {
  console.warn('bundle-editor: esbuild is not installed (run `npm ci`); the program editor falls back to a textarea');
  process.exit(0);
}
const result = await esbuild.build({
  entryPoints: [path.join(ROOT, 'scripts/editor-entry.mjs')],
  bundle: true,
  format: 'esm',
  minify: true,
  target: 'es2020',
  legalComments: 'eof',
  outfile: out,
  metafile: true,
  logLevel: 'warning',
});
const bytes = result.metafile.outputs[path.relative(process.cwd(), out)]?.bytes ?? fs.statSync(out).size;
console.log(`bundle-editor: ${path.relative(ROOT, out)} (${Math.round(bytes / 1024)} KiB)`);
