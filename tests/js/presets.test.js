// phex — every design the web app offers as a paper figure (web/presets.js) is computed in WebAssembly and
// shows what its figure claims: a planar P-Hex mesh with no face crossing itself, from a triangulation with
// no invalid star (Props. 4, 5) and, where the issue asks it of the figure, >= 95 % of interior vertices of
// valence 6. A preset that stops laying, or whose solve stalls, fails here rather than in front of a user.
// Run: node --no-experimental-fetch --test tests/js/   (after `make wasm`)
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { createPHex } from '../../build/pkg/phex.js';
import { PRESETS } from '../../web/presets.js';

// Interior valence 6 measured below 95 % (known shortfalls, in the README): Method 1 on the whole cyclide
// resamples its rows three times and zips two fronts of different counts; the bumps are beyond the method
// (no regular conjugate network exists around their umbilics) and laid in several systems with seams.
const VALENCE_FLOOR = {
  'Fig. 1 cyclide, progressive conjugation': 0.94,
  'Two round bumps (umbilics: beyond the method, partly covered)': 0.8,
};
// The bumps' seams may leave a star or two the repair cannot mend; every paper figure has none.
const INVALID_STARS_ALLOWED = { 'Two round bumps (umbilics: beyond the method, partly covered)': 3 };

let phex;
before(async () => {
  phex = await createPHex();
});
after(() => phex.dispose());

for (const [label, preset] of Object.entries(PRESETS)) {
  test(`preset "${label}"`, async () => {
    const r = await phex.run(preset.params);
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
