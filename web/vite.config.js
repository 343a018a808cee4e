// phex web app: built from web/ into build/web, importing the library from build/pkg as a user would.
import { fileURLToPath } from 'node:url';
import { defineConfig } from 'vite';

const here = (p) => fileURLToPath(new URL(p, import.meta.url));

export default defineConfig({
  root: here('.'),
  base: './', // relative URLs, so build/web works from any path or a file server
  resolve: { alias: { phex: here('../build/pkg/phex.js') } },
  // The library starts its worker as an ES module (it imports phex_core.js).
  worker: { format: 'es' },
  // three.js alone is some 550 kB minified: one chunk of it is expected, not a warning.
  build: { outDir: here('../build/web'), emptyOutDir: true, target: 'es2022', chunkSizeWarningLimit: 1024 },
  server: { fs: { allow: [here('..')] } },
});
