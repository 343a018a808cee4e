// phex — P-Hex meshes (hexagonal meshes with planar faces) from JavaScript.
// The public entry point: createPHex() loads the wasm core, in a Web Worker in browsers and in the
// calling thread in Node, and run() turns parameters into a P-Hex mesh. See phex.d.ts for the API.

/** Error of every failed phex call; `code` says what kind of failure it is. */
export class PHexError extends Error {
  constructor(code, message) {
    super(message);
    this.name = 'PHexError';
    this.code = code;
  }
}

const ENGINE_WORKER_NAME = 'phex-engine'; // phex.worker.js serves only a worker of this name

const cancelled = () => new PHexError('cancelled', 'the run was cancelled');
const disposed = () => new PHexError('cancelled', 'this phex instance was disposed');

const NUMBER_PARAMS = ['cell', 'tolerance', 'lambda', 'mu'];
const INTEGER_PARAMS = ['faces', 'maxIterations'];
const DUALITIES = ['dupin', 'tangent'];
const SOLVERS = ['local', 'planes', 'volumes'];
const INT32_MAX = 2 ** 31 - 1;

function invalid(message) {
  return new PHexError('invalid_parameter', message);
}

function describe(value) {
  if (value === null) return 'null';
  if (Array.isArray(value)) return 'an array';
  if (typeof value === 'string') return `the string ${JSON.stringify(value)}`;
  if (typeof value === 'number') return String(value);
  return `a ${typeof value}`;
}

function checkNumber(name, value) {
  if (typeof value !== 'number' || !Number.isFinite(value)) throw invalid(`${name} must be a finite number, got ${describe(value)}`);
}

/**
 * Checks the types of run() parameters and returns a copy without undefined entries. Ranges are
 * left to the core, which knows them and says them in its messages.
 */
function checkParams(params) {
  if (params === null || typeof params !== 'object' || Array.isArray(params)) {
    throw invalid(`run() expects a parameter object, got ${describe(params)}`);
  }
  const known = new Set(['surface', 'surfaceParams', 'duality', 'solver', ...NUMBER_PARAMS, ...INTEGER_PARAMS]);
  const out = {};
  for (const [name, value] of Object.entries(params)) {
    if (!known.has(name)) throw invalid(`unknown parameter '${name}' (known: ${[...known].join(', ')})`);
    if (value === undefined) continue;
    if (name === 'surface') {
      if (typeof value !== 'string' || value === '') throw invalid(`surface must be a surface name, got ${describe(value)}`);
    } else if (name === 'surfaceParams') {
      if (value === null || typeof value !== 'object' || Array.isArray(value)) {
        throw invalid(`surfaceParams must be an object of numbers, got ${describe(value)}`);
      }
      for (const [key, v] of Object.entries(value)) checkNumber(`surfaceParams.${key}`, v);
    } else if (name === 'duality') {
      if (!DUALITIES.includes(value)) throw invalid(`duality must be one of ${DUALITIES.join(', ')}, got ${describe(value)}`);
    } else if (name === 'solver') {
      if (!SOLVERS.includes(value)) throw invalid(`solver must be one of ${SOLVERS.join(', ')}, got ${describe(value)}`);
    } else {
      checkNumber(name, value);
      // The core takes these as 32-bit integers; anything else would be silently truncated on the way.
      if (INTEGER_PARAMS.includes(name) && (!Number.isInteger(value) || Math.abs(value) > INT32_MAX)) {
        throw invalid(`${name} must be an integer, got ${describe(value)}`);
      }
    }
    out[name] = name === 'surfaceParams' ? { ...value } : value;
  }
  if (out.surface === undefined) throw invalid('surface is required (see surfaces() for the names)');
  return out;
}

/** The binding's {ok, ...} answer as a resolved value, or a PHexError. */
function settle(raw) {
  if (!raw?.ok) throw new PHexError(raw?.code ?? 'internal', raw?.message ?? 'phex returned no result');
  const { ok, ...result } = raw;
  return result;
}

/** Runs the core in the calling thread. A run cannot be interrupted once started. */
class LocalBackend {
  #engine = null;

  async start() {
    this.#engine ??= import('./phex.worker.js').then(({ loadEngine }) => loadEngine());
    try {
      return await this.#engine;
    } catch (error) {
      this.#engine = null;
      throw new PHexError('io', `could not load the phex wasm module: ${error?.message ?? error}`);
    }
  }

  async run(params, onProgress) {
    const engine = await this.start();
    try {
      return engine.run(params, onProgress);
    } catch (error) {
      // A wasm trap leaves the instance unusable: load a fresh one for the next call.
      this.#engine = null;
      throw new PHexError('internal', `the phex core failed: ${error?.message ?? error}`);
    }
  }

  dispose() {
    this.#engine = null;
  }
}

/** Runs the core in a module Web Worker; cancelling terminates it and the next run starts a new one. */
class WorkerBackend {
  #worker = null;
  #ready = null; // promise of {version, surfaces} from the current worker
  #current = null; // the run in flight: {id, resolve, reject, onProgress}
  #nextId = 1;

  start() {
    if (this.#worker) return this.#ready;
    const worker = new Worker(new URL('./phex.worker.js', import.meta.url), { type: 'module', name: ENGINE_WORKER_NAME });
    this.#worker = worker;
    this.#ready = new Promise((resolve, reject) => {
      worker.addEventListener('message', ({ data }) => {
        if (data.type === 'ready') resolve({ version: data.version, surfaces: data.surfaces });
        else if (data.type === 'failed') reject(new PHexError('io', data.message));
        else this.#receive(data);
      });
      // Fires when the worker script cannot be fetched or throws outside a run.
      worker.addEventListener('error', (event) => {
        event.preventDefault();
        const error = new PHexError('io', `the phex worker failed: ${event.message || 'could not load phex.worker.js'}`);
        reject(error);
        this.#stop(error);
      });
    });
    // A worker that failed to load is dropped, so a later call tries again.
    this.#ready.catch(() => {
      if (this.#worker === worker) this.#stop(null);
    });
    return this.#ready;
  }

  #receive(data) {
    const current = this.#current;
    if (!current || data.id !== current.id) return;
    if (data.type === 'progress') {
      current.onProgress?.({ stage: data.stage, fraction: data.fraction, message: data.message });
    } else if (data.type === 'result') {
      this.#current = null;
      current.resolve(data.result);
    } else if (data.type === 'crashed') {
      this.#stop(new PHexError('internal', `the phex core failed: ${data.message}`));
    }
  }

  /** Terminates the worker; the run in flight, if any, is rejected with `error`. */
  #stop(error) {
    this.#worker?.terminate();
    this.#worker = null;
    this.#ready = null;
    const current = this.#current;
    this.#current = null;
    if (current && error) current.reject(error);
  }

  async run(params, onProgress, signal) {
    await this.start();
    if (signal?.aborted) throw cancelled();
    return new Promise((resolve, reject) => {
      const id = this.#nextId++;
      const onAbort = () => {
        if (this.#current?.id === id) this.#stop(cancelled());
      };
      signal?.addEventListener('abort', onAbort, { once: true });
      const done = () => signal?.removeEventListener('abort', onAbort);
      this.#current = {
        id,
        onProgress,
        resolve: (v) => (done(), resolve(v)),
        reject: (e) => (done(), reject(e)),
      };
      this.#worker.postMessage({ type: 'run', id, params });
    });
  }

  dispose() {
    this.#stop(disposed());
  }
}

class PHex {
  #backend;
  #surfaces;
  #queue = Promise.resolve(); // runs one after another: the core computes one mesh at a time
  #disposed = false;

  constructor(backend, info) {
    this.#backend = backend;
    this.#surfaces = info.surfaces;
    this.version = info.version;
  }

  run(params, { onProgress, signal } = {}) {
    return new Promise((resolve, reject) => {
      if (this.#disposed) throw disposed();
      const checked = checkParams(params);
      if (signal?.aborted) throw cancelled();
      // A run still waiting for its turn is rejected at once; one in flight is stopped by the backend.
      const onAbort = () => reject(cancelled());
      signal?.addEventListener('abort', onAbort, { once: true });
      const turn = this.#queue.then(() => {
        if (signal?.aborted) throw cancelled();
        if (this.#disposed) throw disposed();
        return this.#backend.run(checked, onProgress, signal);
      });
      this.#queue = turn.catch(() => {});
      turn
        .then(settle)
        .then(resolve, reject)
        .finally(() => signal?.removeEventListener('abort', onAbort));
    });
  }

  async surfaces() {
    return structuredClone(this.#surfaces);
  }

  dispose() {
    this.#disposed = true;
    this.#backend.dispose();
  }
}

/**
 * Loads phex. In browsers the core runs in a module Web Worker unless `options.worker` is false;
 * where there is no Worker (Node) it runs in the calling thread.
 */
export async function createPHex(options = {}) {
  const useWorker = (options.worker ?? true) && typeof Worker === 'function';
  const backend = useWorker ? new WorkerBackend() : new LocalBackend();
  const engine = await backend.start();
  return new PHex(backend, { version: engine.version, surfaces: engine.surfaces });
}

/**
 * Fan-triangulates a polygon mesh for rendering: face f with n corners becomes n - 2 triangles
 * (v0, vi, vi+1). Positions are converted to single precision, as GPUs want them.
 */
export function triangulateFaces(mesh) {
  const { positions, faceOffsets, faceIndices } = mesh;
  const faceCount = faceOffsets.length - 1;
  let triangleCount = 0;
  for (let f = 0; f < faceCount; f++) triangleCount += Math.max(0, faceOffsets[f + 1] - faceOffsets[f] - 2);
  const index = new Uint32Array(triangleCount * 3);
  const faceOfTriangle = new Uint32Array(triangleCount);
  let t = 0;
  for (let f = 0; f < faceCount; f++) {
    const first = faceOffsets[f];
    for (let i = first + 1; i + 1 < faceOffsets[f + 1]; i++, t++) {
      index[3 * t] = faceIndices[first];
      index[3 * t + 1] = faceIndices[i];
      index[3 * t + 2] = faceIndices[i + 1];
      faceOfTriangle[t] = f;
    }
  }
  return { positions: Float32Array.from(positions), index, faceOfTriangle };
}

/** The mesh as Wavefront OBJ text (1-based indices, full double precision), as `phex run --out` writes it. */
export function meshToOBJ(mesh) {
  const { positions, faceOffsets, faceIndices } = mesh;
  const lines = ['# phex P-Hex mesh'];
  for (let i = 0; i < positions.length; i += 3) lines.push(`v ${positions[i]} ${positions[i + 1]} ${positions[i + 2]}`);
  for (let f = 0; f + 1 < faceOffsets.length; f++) {
    const corners = Array.from(faceIndices.subarray(faceOffsets[f], faceOffsets[f + 1]), (v) => v + 1);
    lines.push(`f ${corners.join(' ')}`);
  }
  return `${lines.join('\n')}\n`;
}
