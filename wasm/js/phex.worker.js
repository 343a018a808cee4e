// phex — the wasm side of the library. Loads phex_core (the Emscripten module) and runs it.
// Used two ways: phex.js spawns this file as a module Web Worker, so long
// computations never block the page; or phex.js imports loadEngine() to run in the calling thread
// (node, or createPHex({worker: false})).
import createPHexModule from './phex_core.js';

// The Worker name phex.js gives this file (kept in step there): only a worker of that name serves
// messages, so importing this file into some other worker never takes over its message port.
const ENGINE_WORKER_NAME = 'phex-engine';

// A literal URL next to this file, so bundlers see the .wasm as an asset and emit it.
const wasmUrl = new URL('./phex_core.wasm', import.meta.url);

function moduleOptions() {
  // Node: hand over the binary ourselves, since Emscripten's loader would try Node's fetch, which
  // cannot read local files.
  const builtin = globalThis.process?.getBuiltinModule;
  if (typeof builtin === 'function') {
    const { readFileSync } = builtin('node:fs');
    const { fileURLToPath } = builtin('node:url');
    return {
      wasmBinary: readFileSync(fileURLToPath(wasmUrl)),
      locateFile: (file) => fileURLToPath(new URL(file, import.meta.url)),
    };
  }
  return { locateFile: (file) => (file.endsWith('.wasm') ? wasmUrl.href : new URL(file, import.meta.url).href) };
}

/** What this core build can do beyond analytic surfaces; a build without a capabilities() binding declares nothing. */
function capabilitiesOf(core) {
  const declared = typeof core.capabilities === 'function' ? core.capabilities() : {};
  return {
    meshInput: Boolean(declared.meshInput),
    meshFormats: declared.meshFormats ?? (declared.meshInput ? ['obj', 'off', 'ply', 'stl'] : []),
    methods: declared.methods ?? [],
    fields: declared.fields ?? [],
    lowerBound: Boolean(declared.lowerBound),
    globalOptions: Boolean(declared.globalOptions),
    surfacePreview: typeof core.surfacePreview === 'function',
    memory: true,
  };
}

/** The binding's answer in the {ok, ...} form phex.js settles, for bindings that return plain values. */
const answer = (raw) => (raw && typeof raw === 'object' && 'ok' in raw ? raw : { ok: true, ...raw });

/**
 * Instantiates phex_core and returns a thin synchronous engine over it. Its methods return the raw
 * answers of the binding ({ok: true, ...} or {ok: false, code, message}); they throw only when the
 * wasm itself failed (a trap), after which the engine must not be used again.
 */
export async function loadEngine() {
  const core = await createPHexModule(moduleOptions());
  return {
    version: core.version(),
    surfaces: core.surfaces(),
    capabilities: capabilitiesOf(core),
    run(params, onProgress) {
      const report = onProgress ? (stage, fraction, message) => onProgress({ stage, fraction, message }) : undefined;
      return core.run(params, report);
    },
    surfacePreview(params) {
      return answer(core.surfacePreview(params));
    },
    fabrication(mesh, options) {
      return answer(core.fabrication(mesh, options));
    },
    structure(mesh, options) {
      return answer(core.structure(mesh, options));
    },
    /** Test-only: the core fails as a bug in it would (see PHex.debugTrap). */
    debugTrap(kind) {
      core.debugTrap(kind);
      return { ok: true };
    },
    /** Lets the last upload's surface go (see PHex.clearUploadCache). */
    clearUploadCache() {
      if (typeof core.clearUploadCache === 'function') core.clearUploadCache();
      return { ok: true };
    },
    /** Heap size, and the bytes malloc has handed out where the binding can tell (else null). */
    memory() {
      return {
        heapBytes: typeof core.heapBytes === 'function' ? core.heapBytes() : core.HEAPU8.byteLength,
        usedBytes: typeof core.mallocedBytes === 'function' ? core.mallocedBytes() : null,
      };
    },
  };
}

/** The ArrayBuffers of all typed arrays in a result, to transfer them instead of copying. */
function buffersOf(value, found = new Set()) {
  if (ArrayBuffer.isView(value)) found.add(value.buffer);
  else if (value && typeof value === 'object') for (const v of Object.values(value)) buffersOf(v, found);
  return [...found];
}

function serve() {
  const ready = loadEngine();
  ready.then(
    ({ version, surfaces, capabilities }) => postMessage({ type: 'ready', info: { version, surfaces, capabilities } }),
    (error) => postMessage({ type: 'failed', message: `could not load the phex wasm module: ${error?.message ?? error}` }),
  );
  const METHODS = ['run', 'surfacePreview', 'memory', 'fabrication', 'structure', 'clearUploadCache', 'debugTrap'];
  addEventListener('message', async ({ data }) => {
    if (data?.type !== 'call' || !METHODS.includes(data.method)) return;
    const engine = await ready;
    const args = [...data.args];
    if (data.method === 'run' && data.progress) args.push((p) => postMessage({ type: 'progress', id: data.id, ...p }));
    try {
      const value = engine[data.method](...args);
      postMessage({ type: 'reply', id: data.id, value }, buffersOf(value));
    } catch (error) {
      // A trap leaves the wasm instance unusable: tell phex.js to replace this worker.
      postMessage({ type: 'crashed', id: data.id, message: String(error?.message ?? error) });
    }
  });
}

if (typeof WorkerGlobalScope !== 'undefined' && globalThis instanceof WorkerGlobalScope && globalThis.name === ENGINE_WORKER_NAME) {
  serve();
}
