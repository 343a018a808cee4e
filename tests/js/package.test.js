// phex — build/pkg is a working npm package: `npm pack` it, install the tarball into an empty project
// (unpacked into node_modules, no network), then import 'phex' from there and type-check a consumer.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';

const pkg = fileURLToPath(new URL('../../build/pkg', import.meta.url));
const tsc = fileURLToPath(new URL('../../node_modules/.bin/tsc', import.meta.url));
const missing = !existsSync(join(pkg, 'package.json')) && 'build/pkg/package.json is missing: rebuild with `make wasm` (re-run cmake if wasm/js/package.json is new)';

let project;
let packed; // npm pack --json report of the tarball

before(() => {
  if (missing) return;
  project = mkdtempSync(join(tmpdir(), 'phex-consumer-'));
  [packed] = JSON.parse(execFileSync('npm', ['pack', '--json', '--pack-destination', project], { cwd: pkg, encoding: 'utf8' }));
  const target = join(project, 'node_modules/phex');
  mkdirSync(target, { recursive: true });
  execFileSync('tar', ['-xzf', join(project, packed.filename), '-C', target, '--strip-components=1']);
  writeFileSync(join(project, 'package.json'), JSON.stringify({ name: 'consumer', private: true, type: 'module' }));
});

after(() => {
  if (project) rmSync(project, { recursive: true, force: true });
});

test('the tarball holds the module, the worker, the wasm, the typings and the README', { skip: missing }, () => {
  assert.equal(packed.name, 'phex');
  assert.equal(packed.version, '0.1.0');
  const files = packed.files.map((f) => f.path).sort();
  assert.deepEqual(files, ['README.md', 'package.json', 'phex.d.ts', 'phex.js', 'phex.worker.js', 'phex_core.js', 'phex_core.wasm']);
});

test("an outside project imports 'phex' and computes a torus", { skip: missing }, () => {
  writeFileSync(
    join(project, 'main.js'),
    `import { createPHex, triangulateFaces } from 'phex';
const phex = await createPHex();
const result = await phex.run({ surface: 'torus', faces: 300 });
const { index } = triangulateFaces(result.hex);
console.log(JSON.stringify({ faces: result.metrics.faceCount, planarity: result.metrics.planarityMax, triangles: index.length / 3 }));
phex.dispose();
`,
  );
  const out = JSON.parse(execFileSync(process.execPath, ['--no-experimental-fetch', 'main.js'], { cwd: project, encoding: 'utf8' }));
  assert.ok(out.faces > 150 && out.faces < 600, `face count ${out.faces}`);
  assert.ok(out.planarity <= 1e-9, `planarity ${out.planarity}`);
  assert.ok(out.triangles >= 3 * out.faces)  // a fan of n - 2 triangles per n-gon, n >= 5 here;
});

test("the package's typings resolve through its exports for a TypeScript consumer", { skip: missing || (!existsSync(tsc) && 'typescript is not installed') }, () => {
  writeFileSync(
    join(project, 'consumer.ts'),
    `import { createPHex, type Result } from 'phex';
const phex = await createPHex();
const result: Result = await phex.run({ surface: 'torus' });
const n: number = result.metrics.faceCount;
console.log(n);
`,
  );
  const args = ['--noEmit', '--strict', '--target', 'es2022', '--module', 'nodenext', '--lib', 'es2022,dom', 'consumer.ts'];
  try {
    execFileSync(tsc, args, { cwd: project, encoding: 'utf8' });
  } catch (error) {
    assert.fail(`tsc failed:\n${error.stdout}${error.stderr}`);
  }
  assert.ok(readFileSync(join(project, 'node_modules/phex/phex.d.ts'), 'utf8').includes('createPHex'));
});
