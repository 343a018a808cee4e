// phex — browser performance figures of the web app (build/web) in headless Chromium. Measures, never fails.
// Run after `make wasm && npm run build:web`:  node bench/browser.mjs
//   first render    page load → default mesh on screen (performance measure 'phex:first-render')
//   edit → screen   a 2k-face parameter edit → new mesh on screen ('phex:edit-to-screen'; includes the
//                   app's 300 ms edit debounce, shown separately)
//   long tasks      the longest main-thread task (PerformanceObserver 'longtask') during a 10k-face run
//   sizes           gzipped phex_core.wasm, phex.js, phex.worker.js and the app bundle
import { readdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { gzipSync } from 'node:zlib';
import { chromium } from 'playwright-core';
import { serve } from '../scripts/serve.js';

const repo = fileURLToPath(new URL('..', import.meta.url));
const DEBOUNCE_MS = 150; // web/main.js RERUN_DELAY_MS
const EDITS = 5;

const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];
const gz = (path) => gzipSync(readFileSync(path), { level: 9 }).length;
const kB = (n) => `${(n / 1024).toFixed(1)} kB`;

const { server, url } = await serve(join(repo, 'build/web'), 0);
const browser = await chromium.launch({
  executablePath: process.env.PHEX_CHROMIUM ?? '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
try {
  const page = await browser.newPage({ viewport: { width: 1200, height: 800 } });
  await page.addInitScript(() => {
    window.__longTasks = [];
    new PerformanceObserver((list) => window.__longTasks.push(...list.getEntries().map((e) => ({ start: e.startTime, duration: e.duration })))).observe({ type: 'longtask', buffered: true });
  });
  const runs = () => page.getAttribute('body', 'data-runs').then(Number);
  const waitRun = (n) => page.waitForFunction((k) => Number(document.body.dataset.runs) > k && document.body.dataset.state === 'ready', n, { timeout: 600_000 });

  await page.goto(`${url}/#surface=torus&faces=2000`);
  await waitRun(0);
  await page.waitForFunction(() => performance.getEntriesByName('phex:first-render').length > 0);
  const firstRender = await page.evaluate(() => performance.getEntriesByName('phex:first-render')[0].duration);

  const edits = [];
  for (let i = 0; i < EDITS; i++) {
    const n = await runs();
    await page.fill('#faces', String(2000 + ((i % 2) ? 0 : 10)));
    await waitRun(n);
    await page.waitForFunction((k) => performance.getEntriesByName('phex:edit-to-screen').length > k, i);
    edits.push(await page.evaluate((k) => performance.getEntriesByName('phex:edit-to-screen')[k].duration, i));
  }

  const n = await runs();
  const t0 = await page.evaluate(() => performance.now());
  await page.fill('#faces', '10000');
  await waitRun(n);
  const t1 = await page.evaluate(() => performance.now());
  const faces10k = Number(await page.textContent('#face-count'));
  const longTasks = await page.evaluate(([a, b]) => window.__longTasks.filter((t) => t.start >= a && t.start <= b).map((t) => t.duration), [t0, t1]);

  const assets = join(repo, 'build/web/assets');
  const app = readdirSync(assets).filter((f) => /^index-.*\.(js|css)$/.test(f));
  const sizes = {
    'phex_core.wasm': gz(join(repo, 'build/pkg/phex_core.wasm')),
    'phex_core.js': gz(join(repo, 'build/pkg/phex_core.js')),
    'phex.js': gz(join(repo, 'build/pkg/phex.js')),
    'phex.worker.js': gz(join(repo, 'build/pkg/phex.worker.js')),
    'app bundle (three.js included)': app.reduce((s, f) => s + gz(join(assets, f)), 0),
  };
  const total = Object.values(sizes).reduce((a, b) => a + b, 0);

  console.log('phex browser figures (headless Chromium, SwiftShader, this machine)');
  console.log(`  first render of the default torus after load   ${firstRender.toFixed(0)} ms`);
  console.log(`  2k-face edit → new mesh on screen (median of ${EDITS})  ${median(edits).toFixed(0)} ms (${(median(edits) - DEBOUNCE_MS).toFixed(0)} ms after the ${DEBOUNCE_MS} ms debounce)`);
  console.log(`  ${faces10k}-face run: ${(t1 - t0).toFixed(0)} ms, main-thread long tasks: ${longTasks.length}, longest ${longTasks.length ? Math.max(...longTasks).toFixed(0) : 0} ms`);
  for (const [name, size] of Object.entries(sizes)) console.log(`  gzip ${name.padEnd(32)} ${kB(size)}`);
  console.log(`  gzip total                                  ${kB(total)}`);
} finally {
  await browser.close();
  server.close();
}
