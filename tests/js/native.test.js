// phex — the wasm build must compute what the native build computes (both are built without FMA).
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { createPHex } from '../../build/pkg/phex.js';

const cli = fileURLToPath(new URL('../../build/native/bin/phex', import.meta.url));
const RELATIVE_TOLERANCE = 1e-9;

function parseObj(text) {
  const positions = [];
  const faces = [];
  for (const line of text.split('\n')) {
    const [kind, ...rest] = line.trim().split(/\s+/);
    if (kind === 'v') positions.push(...rest.map(Number));
    else if (kind === 'f') faces.push(rest.map((v) => Number(v.split('/')[0]) - 1));
  }
  return { positions, faces };
}

test('wasm and native CLI give the same torus', { skip: !existsSync(cli) && 'build/native/bin/phex is not built' }, async () => {
  const dir = mkdtempSync(join(tmpdir(), 'phex-native-'));
  try {
    const out = join(dir, 'torus.obj');
    execFileSync(cli, ['run', '--surface', 'torus', '--faces', '2000', '--quiet', '--out', out]);
    const native = parseObj(readFileSync(out, 'utf8'));

    const phex = await createPHex();
    const { hex } = await phex.run({ surface: 'torus', faces: 2000 });
    const faces = [];
    for (let f = 0; f + 1 < hex.faceOffsets.length; f++) faces.push([...hex.faceIndices.subarray(hex.faceOffsets[f], hex.faceOffsets[f + 1])]);

    assert.deepEqual(faces, native.faces, 'same faces');
    assert.equal(hex.positions.length, native.positions.length, 'same vertex count');
    const scale = Math.max(...native.positions.map(Math.abs));
    let worst = 0;
    for (let i = 0; i < native.positions.length; i++) worst = Math.max(worst, Math.abs(hex.positions[i] - native.positions[i]));
    assert.ok(worst <= RELATIVE_TOLERANCE * scale, `largest coordinate difference ${worst} (model size ${scale})`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
