// The static server (scripts/serve.mjs): gzip when the client accepts it,
// strong ETags per representation, 304 on revalidation, `no-cache` on every
// file, and the forbidden paths. No browser: plain fetch (Node's fetch
// decodes gzip itself, so compressed bodies are read with node:http).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';
import { ROOT } from './harness.mjs';
import { start, acceptsGzip } from '../../scripts/serve.mjs';

let server;
let base;
before(async () => {
  server = await start(0);
  base = `http://127.0.0.1:${server.address().port}`;
});
after(async () => {
  await new Promise((r) => server.close(r));
});

/** GET (or `method`) `rel` with raw bytes: {status, headers, body} (body never decoded). */
function get(rel, headers = {}, method = 'GET', url = base) {
  const { hostname, port } = new URL(url);
  return new Promise((resolve, reject) => {
    // `path` as written: a URL object would resolve `..` and `%2e%2e` first.
    http.request({ hostname, port, path: rel, method, headers }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => resolve({ status: res.statusCode, headers: res.headers, body: Buffer.concat(chunks) }));
    }).on('error', reject).end();
  });
}

const JS = '/www/app/protocol.js';
const jsBytes = () => fs.readFileSync(path.join(ROOT, JS));

test('a .js file is gzipped for a client that accepts it, and gunzips to the file', async () => {
  const res = await get(JS, { 'accept-encoding': 'gzip, deflate, br' });
  assert.equal(res.status, 200);
  assert.equal(res.headers['content-encoding'], 'gzip');
  assert.match(res.headers['content-type'], /^text\/javascript/);
  assert.equal(res.headers.vary, 'Accept-Encoding');
  assert.equal(res.headers['cache-control'], 'no-cache');
  assert.equal(Number(res.headers['content-length']), res.body.length);
  assert.ok(res.body.length < jsBytes().length, 'the gzipped body is smaller');
  assert.deepEqual(zlib.gunzipSync(res.body), jsBytes());
});

test('identity when the client does not ask for gzip (or refuses it)', async () => {
  for (const headers of [{}, { 'accept-encoding': 'identity' }, { 'accept-encoding': 'gzip;q=0, br' }]) {
    const res = await get(JS, headers);
    assert.equal(res.status, 200);
    assert.equal(res.headers['content-encoding'], undefined, JSON.stringify(headers));
    assert.equal(res.headers.vary, 'Accept-Encoding');
    assert.equal(Number(res.headers['content-length']), jsBytes().length);
    assert.deepEqual(res.body, jsBytes());
  }
});

test('Accept-Encoding is read as RFC 9110 says', () => {
  assert.equal(acceptsGzip('gzip'), true);
  assert.equal(acceptsGzip('br, GZIP;q=0.5'), true);
  assert.equal(acceptsGzip('*'), true);
  assert.equal(acceptsGzip('gzip;q=0'), false);
  assert.equal(acceptsGzip('*, gzip;q=0'), false);
  assert.equal(acceptsGzip('br, *;q=0'), false);
  assert.equal(acceptsGzip(''), false);
  assert.equal(acceptsGzip(undefined), false);
});

test('strong ETags: present, stable, and different for gzip and identity', async () => {
  const id1 = await get(JS);
  const id2 = await get(JS);
  const gz1 = await get(JS, { 'accept-encoding': 'gzip' });
  const gz2 = await get(JS, { 'accept-encoding': 'gzip' });
  assert.match(id1.headers.etag, /^"[0-9a-f]+"$/, 'a strong ETag (no W/)');
  assert.match(gz1.headers.etag, /^"[0-9a-f]+-gz"$/);
  assert.equal(id2.headers.etag, id1.headers.etag);
  assert.equal(gz2.headers.etag, gz1.headers.etag);
  assert.notEqual(gz1.headers.etag, id1.headers.etag);
  assert.deepEqual(gz2.body, gz1.body, 'the same compressed bytes each time');
});

test('If-None-Match with the current ETag gives 304 and no body, per representation', async () => {
  const id = await get(JS);
  const gz = await get(JS, { 'accept-encoding': 'gzip' });
  const notModified = await get(JS, { 'if-none-match': id.headers.etag });
  assert.equal(notModified.status, 304);
  assert.equal(notModified.body.length, 0);
  assert.equal(notModified.headers.etag, id.headers.etag);
  assert.equal(notModified.headers['cache-control'], 'no-cache');
  const gzNotModified = await get(JS, { 'accept-encoding': 'gzip', 'if-none-match': `"nope", ${gz.headers.etag}` });
  assert.equal(gzNotModified.status, 304);
  assert.equal(gzNotModified.body.length, 0);
  assert.equal(gzNotModified.headers.etag, gz.headers.etag);
  // The other representation's tag does not validate this one.
  const crossed = await get(JS, { 'accept-encoding': 'gzip', 'if-none-match': id.headers.etag });
  assert.equal(crossed.status, 200);
  assert.equal(crossed.headers['content-encoding'], 'gzip');
  const stale = await get(JS, { 'if-none-match': '"0000000000000000"' });
  assert.equal(stale.status, 200);
  assert.deepEqual(stale.body, jsBytes());
});

test('HEAD: the same headers as GET, no body', async () => {
  const getRes = await get(JS, { 'accept-encoding': 'gzip' });
  const head = await get(JS, { 'accept-encoding': 'gzip' }, 'HEAD');
  assert.equal(head.status, 200);
  assert.equal(head.body.length, 0);
  for (const h of ['content-type', 'content-encoding', 'content-length', 'etag', 'vary', 'cache-control']) {
    assert.equal(head.headers[h], getRes.headers[h], h);
  }
});

test('a png is never compressed', async () => {
  const png = '/tests/fixtures/fish.png';
  const res = await get(png, { 'accept-encoding': 'gzip' });
  assert.equal(res.status, 200);
  assert.equal(res.headers['content-type'], 'image/png');
  assert.equal(res.headers['content-encoding'], undefined);
  assert.equal(res.headers.vary, undefined);
  assert.deepEqual(res.body, fs.readFileSync(path.join(ROOT, png)));
  assert.match(res.headers.etag, /^"[0-9a-f]+"$/);
});

test('forbidden: build output, dependencies, dot-files at any depth, and paths outside the root', async () => {
  for (const rel of ['/target/x', '/node_modules/playwright-core/package.json', '/.gitignore', '/.git/HEAD',
    '/.cargo/config.toml', '/www/.hidden', '/..%2f..%2fetc/passwd']) {
    assert.equal((await get(rel)).status, 403, rel);
  }
  // Only whole path parts: a file named like them is served.
  assert.equal((await get('/www/fit/target.js')).status, 200);
});

test('404 for a missing file and for a directory', async () => {
  assert.equal((await get('/www/no-such-file.js')).status, 404);
  assert.equal((await get('/www')).status, 404);
});

test('a changed file gets a new ETag and its new bytes (cached per version, not forever)', async () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-serve-'));
  const own = await start(0, dir);
  const url = `http://127.0.0.1:${own.address().port}`;
  try {
    const file = path.join(dir, 'a.js');
    fs.writeFileSync(file, 'export const a = 1;\n'.repeat(50));
    const first = await get('/a.js', { 'accept-encoding': 'gzip' }, 'GET', url);
    fs.writeFileSync(file, 'export const b = 2;\n'.repeat(60));
    const second = await get('/a.js', { 'accept-encoding': 'gzip' }, 'GET', url);
    assert.notEqual(second.headers.etag, first.headers.etag);
    assert.equal(zlib.gunzipSync(second.body).toString(), 'export const b = 2;\n'.repeat(60));
    const revalidated = await get('/a.js', { 'accept-encoding': 'gzip', 'if-none-match': first.headers.etag }, 'GET', url);
    assert.equal(revalidated.status, 200, 'the old ETag no longer validates');
  } finally {
    await new Promise((r) => own.close(r));
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('the page bundle: index.html loads it, it holds the modules main.js imports, and an edited source remakes it', async () => {
  const bundle = path.join(ROOT, 'www/app/main.bundle.js');
  assert.match((await get('/')).body.toString(), /<script type="module" src="www\/app\/main\.bundle\.js"><\/script>/);
  const first = await get('/www/app/main.bundle.js');
  assert.equal(first.status, 200);
  const text = first.body.toString();
  assert.match(text, /^\/\/ Generated by scripts\/bundle\.mjs/, 'made by esbuild (npm ci installs it)');
  for (const m of ['www/app/document.js', 'www/app/client.js', 'www/tangle/panel.js', 'www/micro/panel.js']) {
    assert.ok(text.includes(`// ${m}\n`), `the bundle holds ${m}`);
  }
  assert.ok(text.includes('import("../vendor/code-editor.bundle.js")'), 'the code editor stays a dynamic import');
  // Every source newer than the bundle (the bundle dated back to 2000, as
  // after an edit): the next request remakes it first.
  const old = new Date('2000-01-01T00:00:00Z');
  fs.utimesSync(bundle, old, old);
  assert.equal((await get('/www/app/main.bundle.js')).status, 200);
  assert.ok(fs.statSync(bundle).mtimeMs > Date.now() - 60e3, 'remade after the edit');
  assert.equal(fs.readFileSync(bundle, 'utf8'), text, 'the same sources make the same bundle');
});
