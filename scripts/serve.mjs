// A static server for the app (no npm dependency; esbuild, when installed,
// only remakes the page bundle), and an exported start() the
// end-to-end tests use with a random port.
//
// Every response is `cache-control: no-cache` (the browser revalidates each
// time: the app updates through its service worker and the precache
// revisions, so nothing may go stale), with a strong ETag so a revalidation
// of an unchanged file is a 304 without a body. Text and wasm are sent
// gzipped to clients that accept it; the gzip representation has its own
// ETag (suffix `-gz`), as RFC 9110 requires of a different representation.
// The hash and the compressed bytes are computed once per file version
// (path, inode, size, mtime), not per request.
import http from 'node:http';
import fs from 'node:fs/promises';
import path from 'node:path';
import crypto from 'node:crypto';
import zlib from 'node:zlib';
import { promisify } from 'node:util';
import { fileURLToPath } from 'node:url';
import { APP_BUNDLE, appBundle } from './bundle.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const TYPES = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8', '.css': 'text/css; charset=utf-8',
  '.json': 'application/json', '.webmanifest': 'application/manifest+json',
  '.wasm': 'application/wasm', '.png': 'image/png', '.svg': 'image/svg+xml',
  '.ico': 'image/x-icon', '.txt': 'text/plain; charset=utf-8', '.flg': 'text/plain; charset=utf-8',
};
// Worth compressing: text and wasm. Images are compressed already.
const COMPRESSIBLE = new Set(['.html', '.js', '.mjs', '.css', '.json', '.webmanifest', '.wasm', '.svg', '.txt', '.flg']);
// Level 9: compressed once per file version, so the slower level costs nothing per request.
const gzip = promisify(zlib.gzip);
const GZIP_OPTIONS = { level: 9 };
// Forbidden: anything under a dot-name (.git, .cargo, .gitignore, ...),
// dependencies and build output: whole path parts, so www/fit/target.js is served.
const FORBIDDEN = /(^|[\\/])(\.|(node_modules|target)([\\/]|$))/;

/**
 * Whether `header` (an Accept-Encoding value) accepts gzip: a `gzip` (or
 * `x-gzip`) token, else `*`, with a q-value above 0.
 */
export function acceptsGzip(header) {
  if (!header) return false;
  let star = null;
  for (const part of header.split(',')) {
    const [name, ...params] = part.trim().toLowerCase().split(';');
    const qParam = params.map((p) => p.trim()).find((p) => p.startsWith('q='));
    const q = qParam === undefined ? 1 : Number(qParam.slice(2));
    if (name === 'gzip' || name === 'x-gzip') return q > 0;
    if (name === '*') star = q > 0;
  }
  return star === true;
}

/** Whether an If-None-Match value names `etag` (weak comparison, RFC 9110 §13.1.2). */
function matches(ifNoneMatch, etag) {
  if (!ifNoneMatch) return false;
  if (ifNoneMatch.trim() === '*') return true;
  return ifNoneMatch.split(',').some((t) => t.trim().replace(/^W\//, '') === etag);
}

/**
 * The cache of file versions: path → {key, body, etag, gz}, where `gz` is
 * the promise of {body, etag} or null (not worth it). At most CACHE_BYTES of
 * bodies; the least recently used go first.
 */
const CACHE_BYTES = 512 * 1024 * 1024;

function makeCache() {
  const entries = new Map();
  let bytes = 0;
  const size = (e) => e.body.length + (e.gzBytes || 0);
  const drop = (file) => {
    const e = entries.get(file);
    if (e) { bytes -= size(e); entries.delete(file); }
  };
  return {
    get(file, key) {
      const e = entries.get(file);
      if (!e || e.key !== key) return null;
      entries.delete(file); entries.set(file, e); // most recently used last
      return e;
    },
    set(file, e) {
      drop(file);
      entries.set(file, e);
      bytes += size(e);
      for (const [f] of entries) {
        if (bytes <= CACHE_BYTES || f === file) break;
        drop(f);
      }
    },
    grow(file, e, n) {
      if (entries.get(file) !== e) return;
      e.gzBytes = n;
      bytes += n;
    },
  };
}

/**
 * The file's current version: its bytes and ETag, and `gzip()` for its
 * compressed bytes. The stat and the bytes come from one open file, so they
 * belong together even while a build rewrites it.
 */
async function load(cache, file) {
  const handle = await fs.open(file, 'r');
  try {
    const st = await handle.stat({ bigint: true });
    if (!st.isFile()) throw Object.assign(new Error('not a file'), { code: 'ENOENT' });
    const key = `${st.ino}:${st.size}:${st.mtimeNs}`;
    let entry = cache.get(file, key);
    if (!entry) {
      const body = await handle.readFile();
      // The same hash as the precache revisions (scripts/precache.mjs).
      const hash = crypto.createHash('sha256').update(body).digest('hex').slice(0, 16);
      entry = { key, body, etag: `"${hash}"`, gz: undefined };
      // Written to while we read: serve these bytes, but do not keep them.
      const after = await handle.stat({ bigint: true });
      if (after.mtimeNs === st.mtimeNs && after.size === st.size) cache.set(file, entry);
    }
    return entry;
  } finally {
    await handle.close();
  }
}

/** The gzip representation of `entry`, or null when it is not smaller. */
function gzipped(cache, file, entry) {
  if (entry.gz === undefined) {
    // One compression per version, shared by concurrent requests.
    entry.gz = gzip(entry.body, GZIP_OPTIONS).then((body) => {
      if (body.length >= entry.body.length) return null;
      cache.grow(file, entry, body.length);
      return { body, etag: `"${entry.etag.slice(1, -1)}-gz"` };
    }, () => null); // could not compress: send it as it is
  }
  return entry.gz;
}

export function start(port = 8080, root = ROOT) {
  root = path.resolve(root);
  const cache = makeCache();
  const server = http.createServer(async (req, res) => {
    try {
      if (req.method !== 'GET' && req.method !== 'HEAD') {
        res.writeHead(405, { allow: 'GET, HEAD', 'content-type': 'text/plain' }).end('method not allowed');
        return;
      }
      const url = new URL(req.url, 'http://x');
      let rel = decodeURIComponent(url.pathname);
      if (rel.endsWith('/')) rel += 'index.html';
      const file = path.resolve(root, '.' + rel);
      if (!file.startsWith(root + path.sep) || FORBIDDEN.test(path.relative(root, file))) {
        res.writeHead(403).end('forbidden');
        return;
      }
      // The page's bundle of www/ (scripts/bundle.mjs), remade first when a
      // source is newer, so an edit is served as edited. A source that does
      // not build is a 500 with esbuild's message, not the old bundle.
      if (file === APP_BUNDLE) {
        try {
          await appBundle({ ifStale: true });
        } catch (err) {
          res.writeHead(500, { 'content-type': 'text/plain; charset=utf-8' }).end(`bundle: ${err.message}`);
          return;
        }
      }
      const entry = await load(cache, file);
      const ext = path.extname(file);
      const headers = {
        'content-type': TYPES[ext] || 'application/octet-stream',
        'cache-control': 'no-cache',
      };
      let { body, etag } = entry;
      if (COMPRESSIBLE.has(ext)) {
        headers.vary = 'Accept-Encoding';
        const gz = acceptsGzip(req.headers['accept-encoding']) ? await gzipped(cache, file, entry) : null;
        if (gz) {
          ({ body, etag } = gz);
          headers['content-encoding'] = 'gzip';
        }
      }
      headers.etag = etag;
      if (matches(req.headers['if-none-match'], etag)) {
        delete headers['content-encoding'];
        res.writeHead(304, headers).end();
        return;
      }
      headers['content-length'] = body.length;
      res.writeHead(200, headers);
      res.end(req.method === 'HEAD' ? undefined : body);
    } catch {
      if (res.headersSent) { res.destroy(); return; }
      res.writeHead(404, { 'content-type': 'text/plain' }).end('not found');
    }
  });
  return new Promise((resolve) => server.listen(port, '127.0.0.1', () => resolve(server)));
}

if (process.argv[1] === fileURLToPath(import.meta.url)) {
  const port = Number(process.argv[2] || 8080);
  await start(port);
  console.log(`Filigree at http://localhost:${port}/`);
}
