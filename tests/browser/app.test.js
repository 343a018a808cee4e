// phex — browser tests of the web app (build/web): headless Chromium through playwright-core.
// Needs `npx vite build --config web/vite.config.js` (or `npm run build:web`) first, and /usr/bin/chromium.
import assert from 'node:assert/strict';
import { existsSync, mkdirSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { serve } from '../../scripts/serve.js';

const repo = fileURLToPath(new URL('../..', import.meta.url));
const webDir = join(repo, 'build/web');
const artifacts = join(repo, 'build/test-artifacts');
const CHROMIUM = process.env.PHEX_CHROMIUM ?? '/usr/bin/chromium';
const BACKGROUND = [0xee, 0xf1, 0xf5]; // web/main.js BACKGROUND
const RUN_TIMEOUT_MS = 120_000; // wasm under a 2-core CI machine, without GPU

let server;
let url;
let context;
let profile;
let page;
const pageErrors = [];

before(async () => {
  assert.ok(existsSync(join(webDir, 'index.html')), 'build/web is missing: run `npm run build:web` first');
  ({ server, url } = await serve(webDir, 0));
  // A fresh profile each run, so no cache or state of an earlier run leaks in.
  profile = mkdtempSync(join(tmpdir(), 'phex-chromium-'));
  context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    args: [
      '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update',
      '--disable-sync', '--no-first-run', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    ],
    viewport: { width: 1200, height: 800 },
    acceptDownloads: true,
  });
  page = context.pages()[0] ?? (await context.newPage());
  page.on('pageerror', (error) => pageErrors.push(error.message));
  await page.goto(url);
});

after(async () => {
  await context?.close();
  server?.close();
  if (profile) rmSync(profile, { recursive: true, force: true });
});

/** Counts pixels of a PNG screenshot that differ clearly from the background colour, decoded in the page. */
async function nonBackgroundPixels(png) {
  return page.evaluate(
    async ({ data, background }) => {
      const bitmap = await createImageBitmap(new Blob([Uint8Array.from(atob(data), (c) => c.charCodeAt(0))]));
      const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
      const ctx = canvas.getContext('2d');
      ctx.drawImage(bitmap, 0, 0);
      const { data: pixels } = ctx.getImageData(0, 0, bitmap.width, bitmap.height);
      let count = 0;
      for (let i = 0; i < pixels.length; i += 4) {
        const d = Math.abs(pixels[i] - background[0]) + Math.abs(pixels[i + 1] - background[1]) + Math.abs(pixels[i + 2] - background[2]);
        if (d > 24) count++;
      }
      return { count, total: pixels.length / 4 };
    },
    { data: png.toString('base64'), background: BACKGROUND },
  );
}

test('the default torus is computed and drawn on load', async () => {
  await page.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
  const planarity = Number(await page.textContent('#planarity-max'));
  assert.ok(Number.isFinite(planarity) && planarity <= 1e-9, `planarity max ${planarity}`);
  assert.ok(Number(await page.textContent('#face-count')) > 1000);
  assert.equal(await page.textContent('#invalid-faces'), '0');
  assert.equal(await page.inputValue('#surface'), 'torus');

  const png = await page.locator('#viewport').screenshot();
  mkdirSync(artifacts, { recursive: true });
  await page.screenshot({ path: join(artifacts, 'app.png') });
  const { count, total } = await nonBackgroundPixels(png);
  assert.ok(count > total * 0.05, `only ${count} of ${total} viewport pixels show the mesh`);
  assert.deepEqual(pageErrors, []);
});

test('a bad parameter shows an error, and the next valid edit works again', async () => {
  await page.fill('#faces', '0');
  await page.waitForSelector('body[data-state=error]', { timeout: RUN_TIMEOUT_MS });
  assert.ok(await page.isVisible('#error'));
  assert.match(await page.textContent('#error'), /faces/);

  await page.fill('#faces', '300');
  await page.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
  assert.ok(!(await page.isVisible('#error')));
  const faces = Number(await page.textContent('#face-count'));
  assert.ok(faces > 150 && faces < 600, `face count ${faces} for 300 wanted`);
  assert.ok(Number(await page.textContent('#planarity-max')) <= 1e-9);
  assert.deepEqual(pageErrors, []);
});

test('cancel stops a run and the page stays usable', async () => {
  // Large enough to still be running when Cancel is clicked.
  await page.fill('#faces', '300000');
  await page.waitForSelector('body[data-state=running]');
  await page.click('#cancel');
  await page.waitForSelector('body[data-state=ready]', { timeout: 10_000 });
  assert.equal(await page.textContent('#stage'), 'cancelled');

  await page.fill('#faces', '500');
  await page.waitForFunction(() => document.body.dataset.state === 'ready' && document.getElementById('stage').textContent.startsWith('done'), null, { timeout: RUN_TIMEOUT_MS });
  assert.deepEqual(pageErrors, []);
});

test('export OBJ downloads the mesh', async () => {
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-obj')]);
  const path = await download.path();
  const { readFileSync } = await import('node:fs');
  const text = readFileSync(path, 'utf8');
  const faces = text.split('\n').filter((l) => l.startsWith('f ')).length;
  assert.equal(faces, Number(await page.textContent('#face-count')));
});
