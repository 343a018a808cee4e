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

/**
 * Instantiates phex_core and returns a thin synchronous engine over it. run() returns the raw
 * result object of the binding ({ok: true, ...} or {ok: false, code, message}); it throws only when
 * the wasm itself failed (a trap), after which the engine must not be used again.
 */
export async function loadEngine() {
  const core = await createPHexModule(moduleOptions());
  return {
    version: core.version(),
    surfaces: core.surfaces(),
    run(params, onProgress) {
      const report = onProgress ? (stage, fraction, message) => onProgress({ stage, fraction, message }) : undefined;
      return core.run(params, report);
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
    (engine) => postMessage({ type: 'ready', version: engine.version, surfaces: engine.surfaces }),
    (error) => postMessage({ type: 'failed', message: `could not load the phex wasm module: ${error?.message ?? error}` }),
  );
  addEventListener('message', async ({ data }) => {
    if (data?.type !== 'run') return;
    const engine = await ready;
    const progress = (p) => postMessage({ type: 'progress', id: data.id, ...p });
    try {
      const result = engine.run(data.params, progress);
      postMessage({ type: 'result', id: data.id, result }, buffersOf(result));
    } catch (error) {
      // A trap leaves the wasm instance unusable: tell phex.js to replace this worker.
      postMessage({ type: 'crashed', id: data.id, message: String(error?.message ?? error) });
    }
  });
}

if (typeof WorkerGlobalScope !== 'undefined' && globalThis instanceof WorkerGlobalScope && globalThis.name === ENGINE_WORKER_NAME) {
  serve();
}
