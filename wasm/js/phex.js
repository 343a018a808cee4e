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

/**
 * The run() parameters besides `surface` / `mesh`: type, default, range and meaning. The core enforces
 * the ranges (its messages name the parameter); the table serves type checks here and tooltips in UIs.
 * `requires` names the capability a parameter needs (see capabilities()).
 */
export const PARAMETERS = Object.freeze([
  { name: 'faces', type: 'integer', default: 2000, min: 12, max: 1_000_000, description: 'Wanted number of hexagons. Ignored when cell > 0.' },
  { name: 'cell', type: 'number', default: 0, min: 0, max: Infinity, description: 'Wanted edge length of the triangulation, in model units; 0 derives it from faces.' },
  { name: 'tolerance', type: 'number', default: 1e-9, min: 1e-15, max: 0.1, description: 'Planarity goal: largest corner distance from the face plane over the mean edge length.' },
  { name: 'lambda', type: 'number', default: 1, min: 0, max: 1e6, description: 'Initial closeness weight, divided by 10 every round (§6).' },
  { name: 'mu', type: 'number', default: 0, min: 0, max: 1e6, description: 'Weight of the distance to the surface (§6).' },
  { name: 'maxIterations', type: 'integer', default: 100, min: 1, max: 10_000, description: 'Cap on solver iterations.' },
  { name: 'duality', type: 'enum', default: 'auto', values: ['auto', 'dupin', 'tangent'], description: 'Initial dual mesh: Dupin centres (§6), intersections of tangent planes (§4.1), or auto: Dupin, and tangent as well where that solve stalls or leaves faces crossing themselves (the better is kept; result.duality says which).' },
  { name: 'solver', type: 'enum', default: 'local', values: ['local', 'planes', 'volumes'], description: "Planarity solver: 'local' (fastest), 'planes' (Ceres on face planes), 'volumes' (the paper's tetrahedron volumes)." },
  { name: 'folds', type: 'enum', default: 'prevent', values: ['prevent', 'allow'], description: "The local solver never turns a simple face into a self-intersecting one ('prevent'; where that is the only way to planarity it stops short and says so), or lets faces fold to reach the planarity goal ('allow')." },
  { name: 'surfaceFit', type: 'enum', default: 'on', values: ['on', 'off'], description: "Once planar, shift every face plane along its normal, each node following to the intersection of its three planes, so the faces stay exactly planar while the nodes come closer to the surface ('on'), or leave the planar mesh as the solver ends ('off')." },
  { name: 'splitBoundary', type: 'enum', default: 'on', values: ['on', 'off'], description: "A boundary panel the solver leaves off planar while every face away from it is planar (where a boundary meets a parabolic curve a panel may have no planar shape that does not fold), or one that crosses itself, is cut in two along its best diagonal and the solve goes on ('on'; solve.boundaryPanelsSplit counts them; interior faces left off planar where only folding would make them planar are cut too, counted in solve.interiorFacesSplit: a few, at most 8, or all of them where the solve stalled, up to 1 in 20 faces, or on a surface laid in several systems of rows or by the global method, up to cutShare of them, by default 1 in 10), or left as it is ('off')." },
  { name: 'cutShare', type: 'number', default: 0.1, min: 0, max: 1, description: "The largest share of the interior faces that may be cut in two so that the mesh comes out planar (each cut makes two nodes of four faces): faces the solve leaves off planar on a surface laid in several systems of rows or by the global method, and the faces a solve with folds allowed folds. Where a surface folds more (near-developable or coarse uploads: the noisy shared models fold 11-28 % of their faces), a larger share gives a planar mesh with more such nodes instead of one left off planar." },
  { name: 'clipBoundary', type: 'enum', default: 'on', values: ['on', 'off'], description: "Once solved, clip the boundary panels to the surface's boundary curve ('on'): each panel's boundary edges follow the curve projected onto its plane, and the nodes it shares with its neighbours move along the shared edge onto the curve, so the edge panels can be cut as drawn (boundaryClip counts them); or leave the boundary as the dual ends it ('off')." },
  { name: 'method', type: 'enum', default: 'auto', values: ['auto', 'progressive', 'prespecified', 'subdivision', 'lattice', 'global'], requires: 'methods', description: "Triangulation: 'auto' (the surface's recommended method, see surfaces(); for an uploaded mesh pre-specified where trial lays find one system of rows covering it and its lay leaves no part bare, else 'global'; §7's geodesic route for a closed convex one), progressive conjugation (§5.2 Method 1), pre-specified conjugation along a field (§5.2 Method 2), Loop subdivision of a convex control mesh (§7), the parameter lattice, or 'global': any surface (any genus, any boundary) tiled along a 6-fold field in the Dupin metric, with pentagons and heptagons at the field's singular points (triangulation.singularities)." },
  { name: 'field', type: 'field', default: 'principal', values: ['principal', 'angle:DEG', 'param', 'radial', 'diverging', 'spiral', 'section'], requires: 'fields', description: "Direction field of the conjugate methods (§5.2): principal directions (under method 'auto', the surface's recommended field, see surfaces()), a fixed angle to them ('angle:30'), parameter lines, radial, diverging or spiral, or plane sections ('section', 'section:DEG': sections by parallel planes standing on the surface's mean plane, free of singularities on a dome)." },
  { name: 'start', type: 'point', default: null, description: 'Where the conjugate methods start their base curve L0: a point [x, y, z] near the surface. Default (null): chosen by trial lays among the middle of the bounds and the most elliptic and hyperbolic points.' },
  { name: 'direction', type: 'point', default: null, description: 'Which way L0 runs at the start: a vector [x, y, z], projected onto the tangent plane (the nearer family of the network). Default (null): along the smaller normal curvature.' },
  { name: 'lowerBound', type: 'number', default: 0.3, min: 0, max: 2, requires: 'lowerBound', description: 'Lower bound b on the step ratio |CM|/|AB| near parabolic curves (§5.3), applied smoothly; 0 turns it off.' },
  { name: 'anisotropy', type: 'number', default: 2, min: 1, max: 8, requires: 'globalOptions', description: "Method 'global': the largest ratio of the Dupin metric's two axes the field follows; 1 gives triangles equilateral in space, larger values follow the Dupin indicatrix further where it is elongated." },
  { name: 'alignment', type: 'number', default: 3, min: 0, max: 10, requires: 'globalOptions', description: "Method 'global': weight of the field's alignment with the principal direction of least |curvature| (where the curvature is anisotropic) against its smoothness; 0 leaves it free but along the boundary." },
  { name: 'foldFlips', type: 'enum', default: 'on', values: ['on', 'off'], requires: 'globalOptions', description: "Method 'global': where the dual, solved with folds allowed, has faces crossing themselves (next to parabolic curves; at most 8 % of the faces, so not on a coarse or noisy upload), flip an edge of each such face's star (or, at a folded boundary panel, drop its vertex where it lies nearly on the chord between its boundary neighbours) and solve again, round after round ('on', default): fewer faces cut later, each cut making two nodes of four faces (on analytic surfaces at a point or two of hexagons and some time); or lay the triangulation as the field gives it ('off')." },
  { name: 'principalField', type: 'enum', default: 'try', values: ['try', 'off'], requires: 'globalOptions', description: "Method 'global': also solve the direction field held to the principal directions wherever the curvature is anisotropic, and lay it where it has at most three quarters of the singular points of the field smoothest in the Dupin metric ('try', default: on surfaces without umbilics, such as a cyclide, fewer singular points and more hexagons; surfaces with umbilics are not tried); or lay the smoothest field alone ('off')." },
  { name: 'dislocations', type: 'enum', default: 'cancel', values: ['cancel', 'keep'], requires: 'globalOptions', description: "Method 'global': the lattice's dislocations (a vertex of five next to one of seven, where the position field adds or drops a half row) cancelled before the triangle mesh is extracted, each joined with one of the opposite sense, or moved into a singular point of the field ('cancel', default: more hexagons, rows that run on unbroken); or the lattice as the position field leaves it ('keep')." },
  { name: 'curvatureSizing', type: 'number', default: 0, min: 0, max: 1, requires: 'globalOptions', description: "Method 'global': how far the cell follows the curvature: 0 panels of one size; 1 cells shrinking as the square root of the largest |curvature| relative to the surface's median (within a factor 3 either way)." },
  { name: 'curvatureFloor', type: 'number', default: 0.25, min: 0.01, max: 1, requires: 'globalOptions', description: "Method 'global': where |curvature| is small the Dupin metric tends to the isotropic one: each principal |curvature| gets this share of the surface's median largest one added before their ratio is taken. Smaller values follow a near-developable surface's elongated indicatrix further (up to anisotropy)." },
  { name: 'fairness', type: 'number', default: 0.03, min: 0, max: 1, requires: 'globalOptions', description: "Method 'global': the local solver pulls each interior node towards its neighbours' mean with this weight times the square root of lambda, gone with lambda, so the faces' planes follow a smooth mesh instead of folding (fewer faces cut); not on a noisy upload's first lay (see relay); 0 off." },
  { name: 'relay', type: 'enum', default: 'on', values: ['on', 'off'], requires: 'globalOptions', description: "Method 'global': where the lay does not reach a P-Hex mesh, or its cuts make nodes of four faces at over 5 % of its faces, lay it again following the Dupin metric further (anisotropy 2.5, curvature floor 0.05) and keep the better (a noisy upload's first lay, without the repairs that trade hexagons for cuts there: where it does not reach a P-Hex mesh, it is laid again with them, as a smooth upload is, and that lay kept where it reaches one); under 'auto', an upload whose Method 2 rows leave a point of it over a mean panel edge from any panel, cut faces, or reach no P-Hex mesh: tile it by the global method, kept where it reaches one covering the upload more closely or, both within a panel edge, with fewer nodes of four faces from cuts; then, at up to 5000 faces (10000 where they are over 0.25 % of the faces), where the global lay kept still has nodes of four faces from cuts, lay it again for 3 % fewer and more faces and keep the best ('on', default; result.relay says what ran); or keep the first lay ('off')." },
]);

/**
 * The options of structure() (and of the structure's schedules and OBJ): face distances in model units. Missing
 * ones take their defaults; the core enforces the ranges (its messages name the option, the distance and the panel
 * that collapses).
 */
export const STRUCTURE_OPTIONS = Object.freeze([
  { name: 'offset', type: 'number', default: null, description: 'Face distance of the offset mesh (either side, not 0; > 0 towards the normals): every face plane moved by it, each node along its axis. Default (null): no offset mesh.' },
  { name: 'beamHeight', type: 'number', default: null, min: 0, description: 'Height of the beams behind the panels, as a face distance (> 0): one planar quad per edge between the mesh and its offset at -beamHeight. Default (null): a fifth of the mean edge length.' },
  { name: 'beamWidth', type: 'number', default: null, min: 0, description: 'Width of the beams in the solid model (> 0). Default (null): a quarter of the beam height.' },
  { name: 'panelThickness', type: 'number', default: null, min: 0, description: 'Thickness of the panels in the solid model (> 0), towards the normal side. Default (null): a fiftieth of the mean edge length.' },
]);

/** The structure options without undefined or null entries; a non-number is named (ranges are the core's). */
function checkStructureOptions(options) {
  if (options === null || typeof options !== 'object' || Array.isArray(options)) throw invalid(`structure options must be an object, got ${describe(options)}`);
  const known = STRUCTURE_OPTIONS.map((o) => o.name);
  const out = {};
  for (const [name, value] of Object.entries(options)) {
    if (!known.includes(name)) throw invalid(`unknown structure option '${name}' (known: ${known.join(', ')})`);
    if (value === undefined || value === null) continue;
    checkNumber(name, value);
    out[name] = value;
  }
  return out;
}

/** Formats of uploaded meshes: run({mesh, meshFormat}). */
export const MESH_FORMATS = Object.freeze(['obj', 'off', 'ply', 'stl']);

const PARAMETER = Object.fromEntries(PARAMETERS.map((p) => [p.name, p]));
const FIELD_PATTERN = /^(principal|param(:[uv])?|radial|(diverging|spiral|section)(:-?\d+(\.\d+)?)?|angle:-?\d+(\.\d+)?)$/;
const INT32_MAX = 2 ** 31 - 1;

function invalid(message) {
  return new PHexError('invalid_parameter', message);
}

function unsupported(name) {
  return new PHexError('unsupported', `${name} is not supported by this phex core build (see capabilities())`);
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

/** A capability a parameter value needs is declared by the core, or the value is rejected as unsupported. */
function checkSupported(spec, value, capabilities) {
  if (!spec.requires) return;
  const declared = capabilities[spec.requires];
  if (Array.isArray(declared)) {
    const forms = typeof value === 'string' ? [value, value.replace(/:.*$/, ':DEG'), value.split(':')[0]] : [value];
    if (!forms.some((form) => declared.includes(form))) {
      throw declared.length === 0 ? unsupported(spec.name) : invalid(`${spec.name} ${JSON.stringify(value)} is not available in this core build (available: ${declared.join(', ')})`);
    }
  } else if (!declared) {
    throw unsupported(spec.name);
  }
}

/**
 * Checks the types of run() parameters and returns a copy without undefined entries. Ranges are
 * left to the core, which knows them and says them in its messages.
 */
function checkParams(params, capabilities) {
  if (params === null || typeof params !== 'object' || Array.isArray(params)) {
    throw invalid(`run() expects a parameter object, got ${describe(params)}`);
  }
  const known = ['surface', 'surfaceParams', 'mesh', 'meshFormat', 'meshName', ...PARAMETERS.map((p) => p.name)];
  const out = {};
  for (const [name, value] of Object.entries(params)) {
    if (!known.includes(name)) throw invalid(`unknown parameter '${name}' (known: ${known.join(', ')})`);
    if (value === undefined || (value === null && PARAMETER[name]?.type === 'point')) continue;  // the default
    const spec = PARAMETER[name];
    if (name === 'surface') {
      if (typeof value !== 'string' || value === '') throw invalid(`surface must be a surface name, got ${describe(value)}`);
    } else if (name === 'surfaceParams') {
      if (value === null || typeof value !== 'object' || Array.isArray(value)) {
        throw invalid(`surfaceParams must be an object of numbers, got ${describe(value)}`);
      }
      for (const [key, v] of Object.entries(value)) checkNumber(`surfaceParams.${key}`, v);
    } else if (name === 'mesh') {
      if (!(value instanceof Uint8Array) && !(value instanceof ArrayBuffer)) {
        throw invalid(`mesh must be the bytes of a mesh file (Uint8Array or ArrayBuffer), got ${describe(value)}`);
      }
    } else if (name === 'meshFormat') {
      if (!MESH_FORMATS.includes(value)) throw invalid(`meshFormat must be one of ${MESH_FORMATS.join(', ')}, got ${describe(value)}`);
    } else if (name === 'meshName') {
      if (typeof value !== 'string') throw invalid(`meshName must be a string, got ${describe(value)}`);
    } else if (spec.type === 'enum') {
      if (!spec.values.includes(value)) throw invalid(`${name} must be one of ${spec.values.join(', ')}, got ${describe(value)}`);
      checkSupported(spec, value, capabilities);
    } else if (spec.type === 'point') {
      if (!Array.isArray(value) || value.length !== 3 || !value.every((x) => typeof x === 'number' && Number.isFinite(x))) {
        throw invalid(`${name} must be an array of three finite numbers [x, y, z], got ${describe(value)}`);
      }
    } else if (spec.type === 'field') {
      if (typeof value !== 'string' || !FIELD_PATTERN.test(value)) {
        throw invalid(`field must be one of principal, angle:DEG (e.g. angle:30), param, param:v, radial, diverging[:DEG], spiral[:DEG], section[:DEG]; got ${describe(value)}`);
      }
      checkSupported(spec, value, capabilities);
    } else {
      checkNumber(name, value);
      // The core takes these as 32-bit integers; anything else would be silently truncated on the way.
      if (spec.type === 'integer' && (!Number.isInteger(value) || Math.abs(value) > INT32_MAX)) {
        throw invalid(`${name} must be an integer, got ${describe(value)}`);
      }
      checkSupported(spec, value, capabilities);
    }
    if (name === 'surfaceParams') out[name] = { ...value };
    else if (spec?.type === 'point') out[name] = [...value];
    else if (name === 'mesh') out[name] = value instanceof ArrayBuffer ? new Uint8Array(value) : value;
    else out[name] = value;
  }
  if (out.mesh !== undefined && out.surface !== undefined) throw invalid('give either surface or mesh, not both');
  if (out.mesh === undefined && out.surface === undefined) throw invalid('surface is required (see surfaces() for the names), or mesh with the bytes of a mesh file');
  if (out.mesh === undefined && (out.meshFormat !== undefined || out.meshName !== undefined)) throw invalid('meshFormat and meshName need mesh');
  if (out.mesh !== undefined && !capabilities.meshInput) throw unsupported('mesh input');
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
    return this.call('run', [params, onProgress]);
  }

  async call(method, args) {
    const engine = await this.start();
    try {
      const value = engine[method](...args);
      // A heap grown to its limit never shrinks: the next call gets a fresh instance, this one's memory is freed.
      if (value?.code === 'out_of_memory') this.#engine = null;
      return value;
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
  #ready = null; // promise of {version, surfaces, capabilities} from the current worker
  #pending = new Map(); // id -> {resolve, reject, onProgress} of the requests in flight
  #nextId = 1;

  start() {
    if (this.#worker) return this.#ready;
    const worker = new Worker(new URL('./phex.worker.js', import.meta.url), { type: 'module', name: ENGINE_WORKER_NAME });
    this.#worker = worker;
    this.#ready = new Promise((resolve, reject) => {
      worker.addEventListener('message', ({ data }) => {
        if (data.type === 'ready') resolve(data.info);
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
    const request = this.#pending.get(data.id);
    if (!request) return;
    if (data.type === 'progress') {
      request.onProgress?.({ stage: data.stage, fraction: data.fraction, message: data.message });
    } else if (data.type === 'reply') {
      this.#pending.delete(data.id);
      request.resolve(data.value);
      // A heap grown to its limit never shrinks: the worker goes (its memory with it), the next call starts another.
      if (data.value?.code === 'out_of_memory') this.#stop(null);
    } else if (data.type === 'crashed') {
      this.#stop(new PHexError('internal', `the phex core failed: ${data.message}`));
    }
  }

  /** Terminates the worker; the requests in flight, if any, are rejected with `error`. */
  #stop(error) {
    this.#worker?.terminate();
    this.#worker = null;
    this.#ready = null;
    const pending = [...this.#pending.values()];
    this.#pending.clear();
    if (error) for (const request of pending) request.reject(error);
  }

  run(params, onProgress, signal) {
    return this.call('run', [params], { onProgress, signal });
  }

  async call(method, args, { onProgress, signal } = {}) {
    await this.start();
    if (signal?.aborted) throw cancelled();
    return new Promise((resolve, reject) => {
      const id = this.#nextId++;
      const onAbort = () => {
        if (this.#pending.has(id)) this.#stop(cancelled());
      };
      signal?.addEventListener('abort', onAbort, { once: true });
      const done = () => signal?.removeEventListener('abort', onAbort);
      this.#pending.set(id, {
        onProgress,
        resolve: (v) => (done(), resolve(v)),
        reject: (e) => (done(), reject(e)),
      });
      // Typed arrays are copied, not transferred: the caller keeps its mesh bytes.
      this.#worker.postMessage({ type: 'call', id, method, args, progress: Boolean(onProgress) });
    });
  }

  dispose() {
    this.#stop(disposed());
  }
}

class PHex {
  #backend;
  #info;
  #queue = Promise.resolve(); // one request after another: the core computes one mesh at a time
  #disposed = false;

  constructor(backend, info) {
    this.#backend = backend;
    this.#info = info;
    this.version = info.version;
  }

  /** Queues `request` (a function starting a backend call) behind the earlier ones. */
  #enqueue(request, signal) {
    return new Promise((resolve, reject) => {
      if (this.#disposed) throw disposed();
      if (signal?.aborted) throw cancelled();
      // A request still waiting for its turn is rejected at once; one in flight is stopped by the backend.
      const onAbort = () => reject(cancelled());
      signal?.addEventListener('abort', onAbort, { once: true });
      const turn = this.#queue.then(() => {
        if (signal?.aborted) throw cancelled();
        if (this.#disposed) throw disposed();
        return request();
      });
      this.#queue = turn.catch(() => {});
      turn
        .then(settle)
        .then(resolve, reject)
        .finally(() => signal?.removeEventListener('abort', onAbort));
    });
  }

  run(params, { onProgress, signal } = {}) {
    return new Promise((resolve) => {
      const checked = checkParams(params, this.#info.capabilities);
      resolve(this.#enqueue(() => this.#backend.run(checked, onProgress, signal), signal));
    });
  }

  async surfaces() {
    return structuredClone(this.#info.surfaces);
  }

  capabilities() {
    return structuredClone(this.#info.capabilities);
  }

  surfacePreview(params, { signal } = {}) {
    return new Promise((resolve) => {
      if (!this.#info.capabilities.surfacePreview) throw unsupported('surfacePreview');
      const checked = checkParams(params, this.#info.capabilities);
      resolve(this.#enqueue(() => this.#backend.call('surfacePreview', [checked], { signal }), signal));
    });
  }

  memory() {
    return this.#enqueue(() => this.#backend.call('memory', []).then((value) => ({ ok: true, ...value })));
  }

  /**
   * Lets go of the last uploaded mesh's surface (its estimated curvature and search structures), which runs and
   * previews on the same upload reuse (result.surfaceReused). Queued like run(); resolves when done.
   */
  clearUploadCache() {
    return this.#enqueue(() => this.#backend.call('clearUploadCache', [])).then(() => undefined);
  }

  /**
   * The faces of a polygon mesh (a run's `hex`) laid flat, true to size, for cutting: an SVG cut sheet of
   * outlines labelled P1..Pn (face n, seen from its normal side) or, with format 'csv', the panel schedule.
   * Resolves to the text.
   */
  panels(mesh, { format = 'svg', gap, width, unit, labels } = {}) {
    return new Promise((resolve) => {
      if (format !== 'svg' && format !== 'csv') throw invalid(`format must be 'svg' or 'csv', got ${describe(format)}`);
      if (gap !== undefined) checkNumber('gap', gap);
      if (width !== undefined) checkNumber('width', width);
      if (unit !== undefined && !['mm', 'cm', 'm', 'in'].includes(unit)) throw invalid(`unit must be 'mm', 'cm', 'm' or 'in', got ${describe(unit)}`);
      if (labels !== undefined && typeof labels !== 'boolean') throw invalid(`labels must be true or false, got ${describe(labels)}`);
      const options = Object.fromEntries(Object.entries({ format, gap, width, unit, labels }).filter(([, v]) => v !== undefined));
      resolve(this.#enqueue(() => this.#backend.call('fabrication', [mesh, options])));
    }).then((value) => value.text);
  }

  /**
   * The edges of a polygon mesh (a run's `hex`) as the frame's beam schedule, CSV: one row per beam with its
   * nodes, length, the panels either side and the fold between them (positive at a ridge). With `beamHeight` (and
   * the other structure options), each row gains the structure's beam: heights, plane, planarity, twist and the
   * quad's corners. Resolves to the text.
   */
  beams(mesh, options = {}) {
    return this.#fabricate(mesh, 'beams', options);
  }

  /**
   * The structure on a polygon mesh (a run's `hex`; phex's P-Hex meshes are conical, §1): every node's axis, the
   * offset at face distance `offset` (where given), one planar beam per edge of height `beamHeight` behind the
   * panels, and the solid model (panels with a thickness, beams with a width, the axes) as typed arrays for
   * three.js. See phex.d.ts for the fields. A distance the offset cannot take is a PHexError naming the option,
   * the panel and the range that can be taken.
   */
  structure(mesh, options = {}) {
    return new Promise((resolve) => {
      const checked = checkStructureOptions(options);
      resolve(this.#enqueue(() => this.#backend.call('structure', [mesh, checked])));
    });
  }

  /** The node schedule of a polygon mesh, CSV: position, axis, the panels at each node and the angles between. */
  nodes(mesh) {
    return this.#fabricate(mesh, 'nodes', {});
  }

  /** The structure's solid model as OBJ text: an object per panel (P<n>) and per beam (B<k>). */
  structureOBJ(mesh, options = {}) {
    return this.#fabricate(mesh, 'structure-obj', options);
  }

  /** A fabrication text of `format` with the structure options checked. */
  #fabricate(mesh, format, options) {
    return new Promise((resolve) => {
      const checked = checkStructureOptions(options);
      resolve(this.#enqueue(() => this.#backend.call('fabrication', [mesh, { ...checked, format }])));
    }).then((value) => value.text);
  }

  /**
   * Test-only: makes the core fail as a bug in it would ('unreachable': a wasm trap, 'abort', 'memory': a read
   * past the heap). Rejects with a PHexError 'internal'; the next call runs on a fresh core.
   * @internal
   */
  debugTrap(kind = 'unreachable') {
    return this.#enqueue(() => this.#backend.call('debugTrap', [kind]));
  }

  dispose() {
    this.#disposed = true;
    this.#backend.dispose();
  }
}

// A module of one function holding one `try` block: it validates only where the engine has WebAssembly exception
// handling, which the core is built with (Chrome and Edge 95, Firefox 100, Safari 15.2, node 17 and later).
const EXCEPTIONS_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 4, 1, 96, 0, 0, 3, 2, 1, 0, 10, 7, 1, 5, 0, 6, 64, 11, 11]);

/**
 * Loads phex. In browsers the core runs in a module Web Worker unless `options.worker` is false;
 * where there is no Worker (Node) it runs in the calling thread.
 */
export async function createPHex(options = {}) {
  if (typeof WebAssembly !== 'object' || !WebAssembly.validate(EXCEPTIONS_PROBE))
    throw new PHexError('unsupported', 'this JavaScript engine lacks WebAssembly exception handling, which the phex ' +
      'core needs (Chrome and Edge 95, Firefox 100, Safari 15.2, node 17 and later have it)');
  const useWorker = (options.worker ?? true) && typeof Worker === 'function';
  const backend = useWorker ? new WorkerBackend() : new LocalBackend();
  const engine = await backend.start();
  return new PHex(backend, { version: engine.version, surfaces: engine.surfaces, capabilities: engine.capabilities });
}

/**
 * Triangulates a polygon mesh for rendering: face f with n corners becomes n - 2 triangles, each turning as
 * the face does. A convex face is fanned from its first corner (v0, vi, vi+1); a non-convex one (the hexagons
 * of a P-Hex mesh where the surface is saddle-shaped, K < 0, have two reflex corners; a boundary panel clipped
 * to a curve may have more) is cut into ears in its plane, so that no triangle covers what lies outside the
 * face. Positions are converted to single precision, as GPUs want them.
 */
export function triangulateFaces(mesh) {
  const { positions, faceOffsets, faceIndices } = mesh;
  const faceCount = faceOffsets.length - 1;
  let triangleCount = 0;
  for (let f = 0; f < faceCount; f++) triangleCount += Math.max(0, faceOffsets[f + 1] - faceOffsets[f] - 2);
  const index = new Uint32Array(triangleCount * 3);
  const faceOfTriangle = new Uint32Array(triangleCount);
  const polygon = { x: [], y: [], corner: [] };
  let t = 0;
  const emit = (f, a, b, c) => {
    index[3 * t] = a;
    index[3 * t + 1] = b;
    index[3 * t + 2] = c;
    faceOfTriangle[t++] = f;
  };
  for (let f = 0; f < faceCount; f++) {
    const first = faceOffsets[f];
    const n = faceOffsets[f + 1] - first;
    if (n < 3) continue;
    if (n > 3 && projectFace(positions, faceIndices, first, n, polygon) && !isConvex(polygon, n)) {
      clipEars(polygon, n, (a, b, c) => emit(f, a, b, c));
      continue;
    }
    for (let i = first + 1; i + 1 < first + n; i++) emit(f, faceIndices[first], faceIndices[i], faceIndices[i + 1]);
  }
  return { positions: Float32Array.from(positions), index, faceOfTriangle };
}

/**
 * The face's corners in 2D (`out.x`, `out.y`, `out.corner` = vertex ids), in a basis of its plane oriented so
 * that the face turns counter-clockwise: the plane's normal by Newell's method (the face's vector area). False
 * for a face with no area.
 */
function projectFace(p, faceIndices, first, n, out) {
  let nx = 0;
  let ny = 0;
  let nz = 0;
  for (let i = 0; i < n; i++) {
    const a = 3 * faceIndices[first + i];
    const b = 3 * faceIndices[first + ((i + 1) % n)];
    nx += (p[a + 1] - p[b + 1]) * (p[a + 2] + p[b + 2]);
    ny += (p[a + 2] - p[b + 2]) * (p[a] + p[b]);
    nz += (p[a] - p[b]) * (p[a + 1] + p[b + 1]);
  }
  const length = Math.hypot(nx, ny, nz);
  if (!(length > 0)) return false;
  nx /= length;
  ny /= length;
  nz /= length;
  // u: any unit vector across the normal; v = n x u.
  let ux = 0;
  let uy = 0;
  let uz = 0;
  if (Math.abs(nx) < 0.9) [ux, uy, uz] = [0, -nz, ny];
  else [ux, uy, uz] = [nz, 0, -nx];
  const ul = Math.hypot(ux, uy, uz);
  ux /= ul;
  uy /= ul;
  uz /= ul;
  const vx = ny * uz - nz * uy;
  const vy = nz * ux - nx * uz;
  const vz = nx * uy - ny * ux;
  out.x.length = out.y.length = out.corner.length = n;
  for (let i = 0; i < n; i++) {
    const id = faceIndices[first + i];
    const a = 3 * id;
    out.x[i] = p[a] * ux + p[a + 1] * uy + p[a + 2] * uz;
    out.y[i] = p[a] * vx + p[a + 1] * vy + p[a + 2] * vz;
    out.corner[i] = id;
  }
  return true;
}

/** Twice the signed area of triangle (a, b, c) of the projected polygon. */
function turn(x, y, a, b, c) {
  return (x[b] - x[a]) * (y[c] - y[a]) - (y[b] - y[a]) * (x[c] - x[a]);
}

/** No corner of the (counter-clockwise) projected polygon turns clockwise. */
function isConvex({ x, y }, n) {
  for (let i = 0; i < n; i++) if (turn(x, y, (i + n - 1) % n, i, (i + 1) % n) < 0) return false;
  return true;
}

/**
 * Ear clipping of the counter-clockwise projected polygon: a corner turning counter-clockwise whose triangle
 * with its two neighbours holds no other remaining corner is cut off, then its neighbours are looked at again.
 * A polygon left with no ear (one crossing itself) is fanned from what remains, so the count stays n - 2.
 */
function clipEars({ x, y, corner }, n, emit) {
  const next = new Int32Array(n);
  const prev = new Int32Array(n);
  for (let i = 0; i < n; i++) {
    next[i] = (i + 1) % n;
    prev[i] = (i + n - 1) % n;
  }
  const inside = (a, b, c, q) => turn(x, y, a, b, q) >= 0 && turn(x, y, b, c, q) >= 0 && turn(x, y, c, a, q) >= 0;
  const isEar = (b) => {
    const a = prev[b];
    const c = next[b];
    if (!(turn(x, y, a, b, c) > 0)) return false;
    for (let q = next[c]; q !== a; q = next[q]) {
      // A corner at the same place as one of the ear's (a polygon touching itself) does not block it.
      const same = (x[q] === x[a] && y[q] === y[a]) || (x[q] === x[b] && y[q] === y[b]) || (x[q] === x[c] && y[q] === y[c]);
      if (!same && inside(a, b, c, q)) return false;
    }
    return true;
  };
  let left = n;
  let b = 0;
  let tried = 0; // corners looked at since the last ear
  while (left > 3 && tried < left) {
    if (isEar(b)) {
      emit(corner[prev[b]], corner[b], corner[next[b]]);
      next[prev[b]] = next[b];
      prev[next[b]] = prev[b];
      b = prev[b];
      left--;
      tried = 0;
    } else {
      b = next[b];
      tried++;
    }
  }
  for (let c = next[b]; next[c] !== b; c = next[c]) emit(corner[b], corner[c], corner[next[c]]);
}

/** Face corners of a polygon mesh, or of a triangulation ({positions, triangles}) as a mesh of triangles. */
function polygonsOf(mesh) {
  if (mesh.faceOffsets) return mesh;
  const faceOffsets = new Uint32Array(mesh.triangles.length / 3 + 1);
  for (let f = 0; f < faceOffsets.length; f++) faceOffsets[f] = 3 * f;
  return { positions: mesh.positions, faceOffsets, faceIndices: mesh.triangles };
}

/** Area of each face (model units squared): the length of its vector area, exact for planar faces. */
export function faceAreas(mesh) {
  const { positions: p, faceOffsets, faceIndices } = polygonsOf(mesh);
  const areas = new Float64Array(faceOffsets.length - 1);
  for (let f = 0; f < areas.length; f++) {
    let x = 0;
    let y = 0;
    let z = 0;
    const first = faceOffsets[f];
    const n = faceOffsets[f + 1] - first;
    for (let i = 0; i < n; i++) {
      const a = 3 * faceIndices[first + i];
      const b = 3 * faceIndices[first + ((i + 1) % n)];
      x += p[a + 1] * p[b + 2] - p[a + 2] * p[b + 1];
      y += p[a + 2] * p[b] - p[a] * p[b + 2];
      z += p[a] * p[b + 1] - p[a + 1] * p[b];
    }
    areas[f] = 0.5 * Math.hypot(x, y, z);
  }
  return areas;
}

/**
 * The mesh (or a triangulation) as Wavefront OBJ text (1-based indices, full double precision), as
 * `phex run --out` writes it.
 */
export function meshToOBJ(mesh) {
  const { positions, faceOffsets, faceIndices } = polygonsOf(mesh);
  const lines = [mesh.faceOffsets ? '# phex P-Hex mesh' : '# phex triangulation'];
  for (let i = 0; i < positions.length; i += 3) lines.push(`v ${positions[i]} ${positions[i + 1]} ${positions[i + 2]}`);
  for (let f = 0; f + 1 < faceOffsets.length; f++) {
    const corners = Array.from(faceIndices.subarray(faceOffsets[f], faceOffsets[f + 1]), (v) => v + 1);
    lines.push(`f ${corners.join(' ')}`);
  }
  return `${lines.join('\n')}\n`;
}

/**
 * The mesh (or a triangulation) as ASCII PLY text with full double precision; `faceValues` adds named
 * per-face properties (e.g. {planarity: metrics.planarity}), each of length face count.
 */
export function meshToPLY(mesh, faceValues = {}) {
  const { positions, faceOffsets, faceIndices } = polygonsOf(mesh);
  const faceCount = faceOffsets.length - 1;
  const extra = Object.entries(faceValues);
  for (const [name, values] of extra) {
    if (values.length !== faceCount) throw new PHexError('invalid_parameter', `faceValues.${name} has ${values.length} values for ${faceCount} faces`);
  }
  const lines = [
    'ply',
    'format ascii 1.0',
    'comment phex P-Hex mesh',
    `element vertex ${positions.length / 3}`,
    'property double x',
    'property double y',
    'property double z',
    `element face ${faceCount}`,
    'property list uchar uint vertex_indices',
    ...extra.map(([name]) => `property double ${name}`),
    'end_header',
  ];
  for (let i = 0; i < positions.length; i += 3) lines.push(`${positions[i]} ${positions[i + 1]} ${positions[i + 2]}`);
  for (let f = 0; f < faceCount; f++) {
    const corners = faceIndices.subarray(faceOffsets[f], faceOffsets[f + 1]);
    lines.push([corners.length, ...corners, ...extra.map(([, values]) => values[f])].join(' '));
  }
  return `${lines.join('\n')}\n`;
}
