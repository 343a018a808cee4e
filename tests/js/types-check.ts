// phex — compiled by types.test.js with `tsc --noEmit --strict`: the typings must accept real use.
import { createPHex, meshToOBJ, PHexError, triangulateFaces } from '../../wasm/js/phex.js';
import type { Progress, Result, RunParams, SurfaceSpec } from '../../wasm/js/phex.js';

async function main(): Promise<void> {
  const phex = await createPHex({ worker: false });
  const version: string = phex.version;
  const surfaces: SurfaceSpec[] = await phex.surfaces();
  const torus = surfaces.find((s) => s.name === 'torus');
  const params: RunParams = {
    surface: 'torus',
    surfaceParams: Object.fromEntries((torus?.parameters ?? []).map((p) => [p.name, p.default])),
    faces: 2000,
    tolerance: 1e-9,
    duality: 'dupin',
  };
  const controller = new AbortController();
  try {
    const result: Result = await phex.run(params, {
      onProgress: (p: Progress) => console.log(p.stage, p.fraction.toFixed(2), p.message),
      signal: controller.signal,
    });
    const hexagons: number = result.metrics.facesBySize['6'] ?? 0;
    const worst: number = result.metrics.planarity.reduce((a, b) => Math.max(a, b), 0);
    const { positions, index, faceOfTriangle } = triangulateFaces(result.hex);
    const stats: [number, number, number, number, boolean] = [hexagons, worst, positions.length + index.length, faceOfTriangle.length, result.solve.converged];
    console.log(version, stats, result.timings.total, result.solve.log.map((l) => l.planarityMax), meshToOBJ(result.initial).length);
  } catch (error) {
    if (error instanceof PHexError && error.code === 'cancelled') return;
    throw error;
  } finally {
    phex.dispose();
  }
}

main();
