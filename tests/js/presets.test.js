// phex — every design the web app offers as a paper figure (web/presets.js) is computed in WebAssembly and
// shows what its figure claims: a planar P-Hex mesh with no face crossing itself, from a triangulation with
// no invalid star (Props. 4, 5) and, where the issue asks it of the figure, >= 95 % of interior vertices of
// valence 6. A preset that stops laying, or whose solve stalls, fails here rather than in front of a user.
// Run: node --no-experimental-fetch --test tests/js/   (after `make wasm`)
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { after, before, test } from 'node:test';
import { createPHex } from '../../build/pkg/phex.js';
import { MODELS, PRESETS } from '../../web/presets.js';
import { assertClosedDual, assertNoCut, assertSingularities } from './meshes.js';

// Interior valence 6 measured below 95 % (known shortfalls, in the README): Method 1 on the whole cyclide
// resamples its rows three times and zips two fronts of different counts; the bumps are beyond the method
// (no regular conjugate network exists around their umbilics) and laid in several systems with seams.
const VALENCE_FLOOR = {
  'Fig. 1 cyclide, progressive conjugation': 0.94,
  'Two round bumps (umbilics: beyond the method, partly covered)': 0.8,
};
// The bumps' seams may leave a star or two the repair cannot mend; every paper figure has none.
const INVALID_STARS_ALLOWED = { 'Two round bumps (umbilics: beyond the method, partly covered)': 3 };

// The global method's presets are on closed models: their genus, which fixes the sum of the singular indices.
const MODEL_GENUS = { 'phcpf_3holes_r.off': 3, 'phcpf_car_r.off': 0 };

let phex;
before(async () => {
  phex = await createPHex();
});
after(() => phex.dispose());

/** A preset's run parameters, with its bundled model's bytes as the upload where it names one (as the app loads it). */
function runParams({ params, model }) {
  if (!model) return params;
  return { ...params, mesh: new Uint8Array(readFileSync(new URL(MODELS[model].url))), meshFormat: model.split('.').pop(), meshName: model };
}

const paperFigures = Object.entries(PRESETS).filter(([, preset]) => preset.params.method !== 'global');
const globalPresets = Object.entries(PRESETS).filter(([, preset]) => preset.params.method === 'global');

for (const [label, preset] of paperFigures) {
  test(`preset "${label}"`, async () => {
    const r = await phex.run(runParams(preset));
    const check = r.triangulation.check;
    const summary = JSON.stringify({
      faces: r.metrics.faceCount, planarityMax: r.metrics.planarityMax, invalidStars: check.invalidStars.length,
      valence6: check.regularFraction, coverage: check.coverage,
    });
    assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9, `not planar: ${summary}`);
    assert.equal(r.metrics.selfIntersectingCount, 0, summary);
    assert.ok(check.invalidStars.length <= (INVALID_STARS_ALLOWED[label] ?? 0), `invalid stars: ${summary}`);
    assert.ok(check.regularFraction >= (VALENCE_FLOOR[label] ?? 0.95), `valence 6: ${summary}`);
    assert.ok(check.coverage > 0.85, `coverage: ${summary}`);
  });
}

// The global method's presets show what it claims on any surface: the model covered, its singular points adding
// up to 12 (1 - g), a closed P-Hex mesh consistent with its report, no face crossing itself; and issue 31's goal,
// planar with no face cut (every node of three faces).
for (const [label, preset] of globalPresets) {
  test(`preset "${label}": planar, no face cut (issue 31)`, async () => {
    const r = await phex.run(runParams(preset));
    assert.equal(r.method, 'global');
    assert.equal(assertSingularities(r.triangulation.singularities), 12 * (1 - MODEL_GENUS[preset.model]));
    assertClosedDual(r, MODEL_GENUS[preset.model]);
    assert.equal(r.metrics.selfIntersectingCount, 0);
    assert.ok(r.triangulation.check.coverage > 0.95, `coverage ${r.triangulation.check.coverage}`);
    assertNoCut(r);
    assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9, String(r.metrics.planarityMax));
  });
}
