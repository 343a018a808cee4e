// phex — the hand-written typings (wasm/js/phex.d.ts) type-check a program that uses the whole API.
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';

const repo = fileURLToPath(new URL('../..', import.meta.url));
const tsc = fileURLToPath(new URL('../../node_modules/.bin/tsc', import.meta.url));

test('phex.d.ts passes tsc --strict', { skip: !existsSync(tsc) && 'typescript is not installed (npm ci)' }, () => {
  const args = ['--noEmit', '--strict', '--target', 'es2022', '--module', 'nodenext', '--lib', 'es2022,dom', 'tests/js/types-check.ts'];
  const { status, stdout, stderr } = spawnSync(tsc, args, { cwd: repo, encoding: 'utf8' });
  assert.equal(status, 0, `tsc failed:\n${stdout}${stderr}`);
});
