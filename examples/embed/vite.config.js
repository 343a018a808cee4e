// The embedding example, built into build/web/embed next to the app (npm run build:web).
import { fileURLToPath } from 'node:url';
import { defineConfig } from 'vite';

const here = (p) => fileURLToPath(new URL(p, import.meta.url));

export default defineConfig({
  root: here('.'),
  base: './',
  // A real project would `npm install phex`; here the package is the one in build/pkg.
  resolve: { alias: { phex: here('../../build/pkg/phex.js') } },
  worker: { format: 'es' },
  build: { outDir: here('../../build/web/embed'), emptyOutDir: true, target: 'es2022', chunkSizeWarningLimit: 1024 },
});
