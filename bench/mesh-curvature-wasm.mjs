// The WebAssembly side of the mesh benchmark: the same binary STL the native benchmark wrote, loaded and
// its curvature estimated in wasm (phex.surfacePreview reads the bytes and builds the MeshSurface).
// Usage (after build/native/bin/phex_bench_mesh_curvature): node --no-experimental-fetch bench/mesh-curvature-wasm.mjs [stl]
// PHEX_PKG_DIR: the browser package to measure (default build/pkg), as in wasm-case.mjs.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const pkg = process.env.PHEX_PKG_DIR ?? fileURLToPath(new URL('../build/pkg', import.meta.url));
const { createPHex } = await import(pathToFileURL(join(pkg, 'phex.js')).href);

const path = process.argv[2] ?? '/tmp/phex_bench_mesh_curvature.stl';
const bytes = new Uint8Array(readFileSync(path));
const phex = await createPHex({ worker: false });
const started = performance.now();
const preview = await phex.surfacePreview({ mesh: bytes, meshFormat: 'stl', meshName: path });
const ms = performance.now() - started;
console.log(`wasm: ${bytes.length / 50 | 0} triangles, ${preview.k1.length} vertices: load + curvature ${ms.toFixed(0)} ms`);
phex.dispose();
