// phex — compiled by types.test.js with `tsc --noEmit --strict`: the typings must accept real use.
import { createPHex, faceAreas, MESH_FORMATS, meshToOBJ, meshToPLY, PARAMETERS, PHexError, STRUCTURE_OPTIONS, triangulateFaces } from '../../wasm/js/phex.js';
import type { Capabilities, MemoryUse, Method, ParameterSpec, Progress, Result, RunParams, Singularities, Structure, StructureOptions, SurfaceSpec } from '../../wasm/js/phex.js';

async function main(): Promise<void> {
  const phex = await createPHex({ worker: false });
  const version: string = phex.version;
  const surfaces: SurfaceSpec[] = await phex.surfaces();
  const capabilities: Capabilities = phex.capabilities();
  const torus = surfaces.find((s) => s.name === 'torus');
  const params: RunParams = {
    surface: 'torus',
    surfaceParams: Object.fromEntries((torus?.parameters ?? []).map((p) => [p.name, p.default])),
    faces: 2000,
    tolerance: 1e-9,
    duality: 'dupin',
    ...(capabilities.methods.includes('prespecified') ? { method: 'prespecified', field: 'angle:30' } : {}),
  };
  const upload: RunParams = { mesh: new Uint8Array(0), meshFormat: MESH_FORMATS[0], meshName: 'patch.obj' };
  // The global method and its options, on an upload or an analytic surface.
  const method: Method = 'global';
  const global: RunParams = capabilities.globalOptions
    ? { surface: 'torus', faces: 600, method, anisotropy: 2, alignment: 0.5, curvatureSizing: 0, curvatureFloor: 0.25, relay: 'on', fairness: 0.03 }
    : { surface: 'torus', faces: 600, method };
  const globalSpecs: ParameterSpec[] = PARAMETERS.filter((p) => p.requires === 'globalOptions' || p.name === 'curvatureSizing');
  const tooltips: string[] = PARAMETERS.map((p) => `${p.name} (${p.min ?? ''}..${p.max ?? ''}, default ${p.default}): ${p.description}`);
  const controller = new AbortController();
  try {
    const result: Result = await phex.run(params, {
      onProgress: (p: Progress) => console.log(p.stage, p.fraction.toFixed(2), p.message),
      signal: controller.signal,
    });
    const hexagons: number = result.metrics.facesBySize['6'] ?? 0;
    const worst: number = result.metrics.planarity.reduce((a, b) => Math.max(a, b), 0);
    const { positions, index, faceOfTriangle } = triangulateFaces(result.hex);
    const areas: Float64Array = result.metrics.faceArea ?? faceAreas(result.hex);
    const lines = result.triangulation.fieldLines;
    const farNodes: number = result.farNodes;
    const coverageGap: number = result.coverageGap;
    const relayed: boolean = result.relay.tried && result.relay.kept && result.relay.firstNodesOfFour >= 0;
    const edgeOffset: number = result.boundaryOffset.max + result.solve.boundaryNodesPlaced;
    const clipped: number = result.boundaryClip.panels + result.boundaryClip.gapMax;
    const stats: [number, number, number, number, boolean] = [hexagons, worst, positions.length + index.length, faceOfTriangle.length, result.solve.converged];
    console.log(version, stats, farNodes, coverageGap, relayed, edgeOffset, clipped, areas.length, lines?.offsets.length, result.timings.total, result.solve.log.map((l) => l.planarityMax), meshToOBJ(result.initial).length);
    console.log(meshToOBJ(result.triangulation).length, meshToPLY(result.hex, { planarity: result.metrics.planarity }).length, tooltips.length);
    const field = await phex.run(global);
    const singular: Singularities | undefined = field.triangulation.singularities;
    const pentagons: number = singular ? singular.index.filter((i) => i > 0).length : 0;
    const first: [number, number, number] | null = singular && singular.index.length ? [singular.positions[0], singular.positions[1], singular.positions[2]] : null;
    console.log(field.method === 'global', pentagons, first, globalSpecs.map((p) => `${p.name} ${p.min}..${p.max}`));
    if (capabilities.surfacePreview) {
      const preview = await phex.surfacePreview(params);
      console.log(preview.k1.length + preview.k2.length + preview.triangles.length);
    }
    if (capabilities.meshInput) {
      const reused: boolean = (await phex.run(upload)).surfaceReused;
      const cleared: void = await phex.clearUploadCache();
      console.log(reused, cleared);
    }
    // The structure on the panels: solids for three.js, the offset, schedules.
    const options: StructureOptions = { offset: 0.05, beamHeight: 0.1, beamWidth: null };
    const structure: Structure = await phex.structure(result.hex, options);
    const { origin, panels, beams, axes } = structure.solid;
    const placed: [number, number, number] = origin;
    const drawn: number = panels.positions.length + beams.index.length + axes.positions.length + panels.element.length;
    const planarBoundary: number = structure.report.boundaryBeamsPlanar / Math.max(structure.report.boundaryBeams, 1);
    const named: string[] = [...structure.nodes.bestFit, ...structure.nodes.folded].map((v) => `node ${v + 1}`);
    const offsetVertices: number = structure.offset?.positions.length ?? 0;
    const range: [number, number] = structure.report.offsetRange;
    console.log(placed, drawn, planarBoundary, named, offsetVertices, range, structure.beams.quads.length, structure.nodes.kind[0]);
    console.log((await phex.nodes(result.hex)).length, (await phex.beams(result.hex, { beamHeight: 0.1 })).length, (await phex.structureOBJ(result.hex)).length);
    console.log(STRUCTURE_OPTIONS.map((o) => `${o.name}: ${o.description}`).join('\n'));
    const memory: MemoryUse = await phex.memory();
    console.log(memory.heapBytes, memory.usedBytes ?? 'unknown');
  } catch (error) {
    if (error instanceof PHexError && (error.code === 'cancelled' || error.code === 'unsupported')) return;
    throw error;
  } finally {
    phex.dispose();
  }
}

main();
