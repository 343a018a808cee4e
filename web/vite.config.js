// phex web app: built from web/ into build/web, importing the library from build/pkg as a user would.
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { defineConfig } from 'vite';

const here = (p) => fileURLToPath(new URL(p, import.meta.url));

/** Emits sw.js (web/sw.js) with the list of every built file to cache for offline use. */
function serviceWorker() {
  return {
    name: 'phex-service-worker',
    apply: 'build',
    generateBundle(_, bundle) {
      const files = ['./', './index.html', ...Object.keys(bundle).map((f) => `./${f}`)];
      const source = readFileSync(here('sw.js'), 'utf8')
        .replace('__PRECACHE__', JSON.stringify(files))
        .replace('__BUILD_ID__', Date.now().toString(36));
      this.emitFile({ type: 'asset', fileName: 'sw.js', source });
    },
  };
}

export default defineConfig({
  root: here('.'),
  base: './', // relative URLs, so build/web works from any path or a file server
  resolve: { alias: { phex: here('../build/pkg/phex.js') } },
  plugins: [serviceWorker()],
  // The library starts its worker as an ES module (it imports phex_core.js).
  worker: { format: 'es' },
  // three.js alone is some 550 kB minified: one chunk of it is expected, not a warning.
  build: { outDir: here('../build/web'), emptyOutDir: true, target: 'es2022', chunkSizeWarningLimit: 1024 },
  server: { fs: { allow: [here('..')] } },
});
