// phex web app: designs P-Hex meshes with the phex library (in a worker) and shows them with three.js.
import * as THREE from 'three';
import { createPHex, MESH_FORMATS, meshToOBJ, meshToPLY, PARAMETERS, STRUCTURE_OPTIONS, triangulateFaces } from 'phex';
import { CURVATURE_MODES, curvatureColoring, FACE_MODES, faceColoring, faceQuantities, fmt } from './coloring.js';
import { MODELS, PRESETS } from './presets.js';
import { structureGroup, Viewer } from './viewer.js';

const $ = (id) => document.getElementById(id);
// Edits within this delay coalesce (typing a number); short enough that a finished 2k-face edit is on screen
// within 300 ms.
const RERUN_DELAY_MS = 150;
const DEFAULT_SURFACE = 'torus';
// Run parameters with a form field of the same id; those with `requires` show only when the core supports them.
const FORM_PARAMS = PARAMETERS.filter((p) => $(p.name));
const PARAMETER_SPEC = Object.fromEntries(PARAMETERS.map((p) => [p.name, p]));
const VIEW_KEYS = ['view', 'color'];
// Singular-point markers' radius over the triangulation's mean edge: large enough to find, small enough that a
// pentagon-heptagon pair shows as two.
const MARKER_RADIUS = 0.25;
// What each triangulation method does, under the method selector.
const METHOD_TEXT = {
  auto: "The surface's recommended method (see its description); for an upload, pre-specified conjugation, or §7's route for a closed convex one.",
  progressive: 'Method 1 (§5.2): each row of triangles laid from the last by progressive conjugation.',
  prespecified: 'Method 2 (§5.2): rows of triangles along a pre-specified direction field (below).',
  subdivision: '§7: Loop subdivision of a convex control mesh; a closed convex surface gets 12 pentagons.',
  lattice: 'Rows of the parameter domain, every other one shifted (analytic surfaces).',
  global: 'Tiles any surface, uploaded or analytic, of any genus and boundary, along a 6-fold direction field in the Dupin metric: the field places pentagons and heptagons at its singular points (markers in the triangulation view), and every node joins three faces.',
};
// Parameters that apply to one method only: their fields show, and are sent, only when it is chosen.
const METHOD_PARAMS = { global: ['anisotropy', 'alignment', 'curvatureSizing', 'foldFlips', 'dislocations', 'principalField', 'relay'] };
// Parameters the global method does not read (its field is its own): hidden while it is chosen.
const NOT_GLOBAL = ['field', 'lowerBound'];

const viewer = new Viewer($('viewport'));
const ms = (x) => Math.round(x).toString();

let phex;
let surfaces = [];
let capabilities;
let upload = null; // {bytes, name, format} of an uploaded mesh in place of the analytic surface
let last = null; // {result, params, quantities: {hex, initial}}
let preview = null; // {key, data} of the curvature preview
let structure = null; // {result, key, data} of the structure view: phex.structure of the shown mesh
let running = null; // AbortController of the run in flight
let rerunTimer = 0;
let runs = 0;

// ---------------------------------------------------------------- status, errors

function setState(state) {
  document.body.dataset.state = state;
}

function showError(message) {
  $('error').textContent = message;
  $('error').hidden = false;
}

function clearError() {
  $('error').hidden = true;
  $('error').textContent = '';
}

function showProgress({ stage, fraction, message }) {
  $('progress').value = fraction;
  $('stage').textContent = `${stage}: ${message}`;
}

// ---------------------------------------------------------------- form

/** Reads an "x, y, z" input: empty is the default (null); anything else goes to the library to be named. */
function pointOf(input) {
  const text = input.value.trim();
  return text === '' ? null : text.split(/[\s,]+/).map(Number);
}

/** Reads a number input; an empty or unparsable field is passed on as NaN, for the library to name it. */
function numberOf(input) {
  return input.value.trim() === '' ? Number.NaN : Number(input.value);
}

function supported(spec) {
  if (!spec.requires) return true;
  const c = capabilities[spec.requires];
  return Array.isArray(c) ? c.length > 0 : Boolean(c);
}

/** Whether a parameter applies to the chosen method (see METHOD_PARAMS, NOT_GLOBAL). */
function applies(name) {
  const method = $('method').value;
  const only = Object.entries(METHOD_PARAMS).find(([, names]) => names.includes(name));
  if (only) return only[0] === method;
  return !(method === 'global' && NOT_GLOBAL.includes(name));
}

/** Shows the chosen method's description and the fields of the parameters that apply to it. */
function showMethodOptions() {
  $('method-description').textContent = METHOD_TEXT[$('method').value] ?? '';
  $('global-params').hidden = !applies('anisotropy');
  for (const name of NOT_GLOBAL) $(name).closest('label').hidden = !supported(PARAMETER_SPEC[name]) || !applies(name);
}

/** Tooltip text and HTML range of a parameter, from its description and range. */
function describeInput(input, { description, min, max, default: value, values }) {
  const range = values ? `one of ${values.join(', ')}` : `${min} … ${max === Infinity ? '∞' : max}`;
  input.title = `${description}\nRange: ${range}. Default: ${value}.`;
  input.closest('label').title = input.title;
  if (Number.isFinite(min)) input.min = String(min);
  if (Number.isFinite(max)) input.max = String(max);
}

function buildForm() {
  // Analytic surfaces, then the built-in control meshes of the subdivision method (§7).
  const controls = (capabilities.subdivisionControls ?? []).map((n) => new Option(`${n} (subdivision control)`, n));
  $('surface').replaceChildren(...surfaces.map((s) => new Option(s.name, s.name)), ...controls);
  for (const spec of PARAMETERS) {
    const input = $(spec.name);
    if (!input) continue;
    describeInput(input, spec);
    input.closest('label').hidden = !supported(spec);
    // The global method's fields say their range in the label, as they have no other hint.
    if (input.closest('#global-params')) input.closest('label').firstChild.textContent += ` (${spec.min} – ${spec.max})`;
  }
  $('method').replaceChildren(...capabilities.methods.map((m) => new Option(m, m, m === 'auto', m === 'auto')));
  $('field-values').replaceChildren(...capabilities.fields.map((f) => new Option(f.replace('angle:DEG', 'angle:30'))));
  $('color').replaceChildren(...Object.entries(FACE_MODES).map(([value, label]) => new Option(label, value)));
  const curvature = $('view').querySelector('[value=curvature]');
  curvature.disabled = !capabilities.surfacePreview;
  if (curvature.disabled) curvature.textContent += ' (needs a newer phex core)';

  const figures = $('figure-presets');
  for (const label of Object.keys(PRESETS)) {
    const button = document.createElement('button');
    button.type = 'button';
    button.textContent = label;
    button.dataset.preset = label;
    const { model } = PRESETS[label];
    button.title = model ? `Compute this design on the model ${MODELS[model].credit}` : 'Compute this design';
    button.addEventListener('click', () => applyPreset(label));
    figures.append(button);
  }
}

function buildSurfaceParams(name, values = {}) {
  const spec = surfaces.find((s) => s.name === name) ?? {
    parameters: [],
    description: 'A convex control mesh: Loop subdivision gives a closed convex surface whose P-Hex mesh has 12 pentagons (§7). Use the subdivision method.',
  };
  const fieldset = $('surface-params');
  fieldset.replaceChildren();
  for (const p of spec.parameters) {
    const label = document.createElement('label');
    label.textContent = p.name;
    const input = document.createElement('input');
    Object.assign(input, { type: 'number', step: 'any', value: String(values[p.name] ?? p.default) });
    input.id = `param-${p.name}`;
    input.dataset.param = p.name;
    label.append(input);
    describeInput(input, p);
    fieldset.append(label);
  }
  $('surface-description').textContent = spec.description;
}

/** The run parameters the form describes (the uploaded mesh, if any, in place of the surface). */
function readParams() {
  const params = {};
  if (upload) Object.assign(params, { mesh: upload.bytes, meshFormat: upload.format, meshName: upload.name });
  else {
    params.surface = $('surface').value;
    params.surfaceParams = {};
    for (const input of $('surface-params').querySelectorAll('input')) params.surfaceParams[input.dataset.param] = numberOf(input);
  }
  for (const spec of FORM_PARAMS) {
    if (!supported(spec) || !applies(spec.name)) continue;
    const input = $(spec.name);
    params[spec.name] = spec.type === 'integer' || spec.type === 'number' ? numberOf(input) : spec.type === 'point' ? pointOf(input) : input.value.trim();
  }
  return params;
}

/** Sets the form from a design (a preset's or a link's params); missing entries take their defaults. */
function knownSurface(name) {
  return surfaces.some((s) => s.name === name) || (capabilities.subdivisionControls ?? []).includes(name);
}

function writeForm(params) {
  const name = knownSurface(params.surface) ? params.surface : DEFAULT_SURFACE;
  $('surface').value = name;
  buildSurfaceParams(name, params.surfaceParams);
  for (const spec of FORM_PARAMS) {
    const value = params[spec.name] ?? spec.default;
    $(spec.name).value = spec.type === 'point' ? (value ?? []).join(', ') : String(value);
  }
  showMethodOptions();
}

// ---------------------------------------------------------------- the design in the URL

/** The design as a URL hash: only what differs from the defaults. */
function designToHash(params) {
  const q = new URLSearchParams();
  if (upload?.model) q.set('model', upload.model);
  else if (params.surface) q.set('surface', params.surface);
  const spec = surfaces.find((s) => s.name === params.surface);
  for (const [k, v] of Object.entries(params.surfaceParams ?? {})) {
    if (spec?.parameters.find((p) => p.name === k)?.default !== v) q.set(`s.${k}`, String(v));
  }
  for (const p of FORM_PARAMS) if (params[p.name] != null && params[p.name] !== p.default) q.set(p.name, String(params[p.name]));
  if ($('view').value !== 'hex') q.set('view', $('view').value);
  if ($('color').value !== 'planarity') q.set('color', $('color').value);
  return `#${q}`;
}

/** The hash to keep in the URL for the shown design: an upload of the user's own is not in a link, so it keeps the last one. */
function designLink(params) {
  return upload && !upload.model ? location.hash : designToHash(params);
}

/** The design of a link (hash, or query as a fallback), or null when it has none. */
function designFromUrl() {
  const text = location.hash.length > 1 ? location.hash.slice(1) : location.search.slice(1);
  if (!text) return null;
  const q = new URLSearchParams(text);
  const params = { surfaceParams: {} };
  const view = {};
  for (const [key, value] of q) {
    const spec = PARAMETERS.find((p) => p.name === key);
    if (key === 'surface' || key === 'model') params[key] = value;
    else if (key.startsWith('s.')) params.surfaceParams[key.slice(2)] = Number(value);
    else if (spec) params[key] = spec.type === 'integer' || spec.type === 'number' ? Number(value) : spec.type === 'point' ? value.split(',').map(Number) : value;
    else if (VIEW_KEYS.includes(key)) view[key] = value;
  }
  return { params, view };
}

// ---------------------------------------------------------------- showing results

function colorOptions() {
  const view = $('view').value;
  const modes = view === 'curvature' ? CURVATURE_MODES : view === 'triangulation' || view === 'structure' ? { none: 'Plain' } : FACE_MODES;
  const current = $('color').value;
  if (Object.keys(modes).join() !== [...$('color').options].map((o) => o.value).join()) {
    $('color').replaceChildren(...Object.entries(modes).map(([value, label]) => new Option(label, value)));
    if (current in modes) $('color').value = current;
  }
}

function showLegend(legend) {
  $('legend').hidden = !legend;
  if (!legend) return;
  $('legend-title').textContent = legend.title;
  $('legend-bar').style.background = legend.background;
  $('legend-low').textContent = legend.low;
  $('legend-high').textContent = legend.high;
  $('legend-goal').hidden = legend.mark === undefined;
  if (legend.mark !== undefined) $('legend-goal').style.left = `${100 * Math.min(Math.max(legend.mark, 0), 1)}%`;
}

function shading() {
  return { flat: $('flat').checked, wireframe: $('wireframe').checked };
}

/** Draws the current view of the last result; `refit` frames it. */
async function draw({ refit = false } = {}) {
  if (!last) return;
  colorOptions();
  const view = $('view').value;
  const mode = $('color').value;
  viewer.clear();
  if (view === 'hex' || view === 'initial') {
    const { faceColor, legend } = faceColoring(mode, last.quantities[view], last.params.tolerance ?? 1e-9);
    viewer.showPolygons(last.result[view], faceColor, shading());
    showLegend(legend);
  } else if (view === 'triangulation') {
    const { triangulation } = last.result;
    viewer.showTriangles(triangulation, null, { ...shading(), markerRadius: MARKER_RADIUS * (triangulation.check?.edgeMean ?? 0) });
    showLegend(null);
  } else if (view === 'structure') {
    showLegend(null);
    const data = await structureOf();
    if (!data || $('view').value !== 'structure') return;
    viewer.clear();
    viewer.showStructure(data.solid);
  } else if (view === 'curvature') {
    const data = await curvaturePreview();
    if (!data || $('view').value !== 'curvature') return;
    const { vertexColor, legend } = curvatureColoring(mode, data);
    viewer.clear();
    viewer.showTriangles(data, vertexColor, shading());
    showLegend(legend);
  }
  if (refit) viewer.fitToView();
  viewer.render();
}

async function curvaturePreview() {
  const key = JSON.stringify(last.params, (k, v) => (v instanceof Uint8Array ? `${v.length} bytes` : v));
  if (preview?.key !== key) {
    try {
      preview = { key, data: await phex.surfacePreview(last.params) };
    } catch (error) {
      showError(`Curvature view: ${error.message}`);
      return null;
    }
  }
  return preview.data;
}

/** The structure options of the form: empty fields take the library's defaults; anything else goes to it to be named. */
function structureOptions() {
  const options = {};
  for (const { name } of STRUCTURE_OPTIONS) {
    const text = $(name).value.trim();
    if (text !== '') options[name] = Number(text);
  }
  return options;
}

/** phex.structure of the shown mesh with the form's options, kept while neither changes; null after an error (shown). */
async function structureOf() {
  const options = structureOptions();
  const key = JSON.stringify(options);
  if (structure?.result !== last.result || structure.key !== key) {
    try {
      structure = { result: last.result, key, data: await phex.structure(last.result.hex, options) };
    } catch (error) {
      structure = null;
      showError(`Structure: ${error.message}`);
      $('structure-info').textContent = '–';
      return null;
    }
    clearError();
    showStructureInfo(structure.data.report);
  }
  return structure.data;
}

/** The structure's summary under the statistics: nodes, beams, the boundary rule's reach and the offset range. */
function showStructureInfo(report) {
  const k = report.nodesByKind;
  const named = k['best-fit'] + k.folded;
  const [lo, hi] = report.offsetRange.map((d) => (Number.isFinite(d) ? d.toPrecision(2) : d > 0 ? '∞' : '−∞'));
  $('structure-info').textContent = `${report.nodeCount} nodes${named ? ` (${k['best-fit']} best fit, ${k.folded} folded)` : ''} · ${
    report.beamCount} beams, ${report.beamLength.toPrecision(4)} long${
    report.boundaryBeams ? ` · boundary ${report.boundaryBeamsPlanar}/${report.boundaryBeams} planar` : ''} · offsets ${lo} … ${hi}`;
  $('structure-info').title = report.notes.join('\n');
}

// Notes that tell a designer the result falls short, or why the method chose what it did against the form:
// shown open and marked, where the rest (start chosen, layers laid) stay folded.
const WARNING_NOTE = /covers only|noisy|crease|umbilic|cannot|stopped short|no valid triangle|asymptotic direction|fold onto|coarse for this lay|polyhedron|off the surface, the farthest/i;

/** The triangulation's notes (laying, start choice, repairs, shortfalls) in a folded list under the statistics. */
function showNotes(notes) {
  const list = $('run-notes-list');
  const warnings = notes.filter((note) => WARNING_NOTE.test(note)).length;
  list.replaceChildren(...notes.map((note) => {
    const item = document.createElement('li');
    item.textContent = note;
    if (WARNING_NOTE.test(note)) item.className = 'warn';
    return item;
  }));
  $('run-notes-summary').textContent = `Notes (${notes.length})${warnings ? ` · ${warnings} to read` : ''}`;
  $('run-notes').classList.toggle('warn', warnings > 0);
  $('run-notes').hidden = notes.length === 0;
}

/** Nodes by the number of faces at them ("3: 1200 · 4: 2"), those of more than three marked: nodes of more beams. */
function nodeFaces(valence) {
  if (!valence) return '–';
  const entries = Object.entries(valence).sort(([a], [b]) => Number(a) - Number(b));
  const over = entries.filter(([faces]) => Number(faces) > 3).reduce((sum, [, count]) => sum + count, 0);
  return `${entries.map(([faces, count]) => `${faces}: ${count}`).join(' · ')}${over ? ` (${over} of more than 3)` : ''}`;
}

/** "min – max (×max/min)" in model units, the mean in the tooltip of element `id`. */
function showSpread(id, min, mean, max) {
  const ok = [min, mean, max].every(Number.isFinite);
  const ratio = ok && min > 0 ? ` (×${(max / min).toFixed(1)})` : '';
  $(id).textContent = ok ? `${min.toPrecision(3)} – ${max.toPrecision(3)}${ratio}` : '–';
  $(id).title = ok ? `mean ${mean.toPrecision(3)}` : '';
}

/** The field's singular points by index ("14 · +1: 13 · −1: 1 · sum 12"), coloured as their markers; – for none. */
function showSingularities(singularities) {
  const dd = $('singular-points');
  if (!singularities?.index.length) {
    dd.textContent = singularities ? '0' : '–';
    return;
  }
  const byIndex = new Map();
  let sum = 0;
  for (const i of singularities.index) (byIndex.set(i, (byIndex.get(i) ?? 0) + 1), (sum += i));
  const parts = [...byIndex].sort(([a], [b]) => b - a).map(([i, count]) => {
    const span = document.createElement('span');
    span.className = i > 0 ? 'pentagon' : 'heptagon';
    span.textContent = `${i > 0 ? '+' : '−'}${Math.abs(i)}: ${count}`;
    return span;
  });
  dd.replaceChildren(String(singularities.index.length), ...parts.flatMap((span) => [' · ', span]), ` · sum ${sum}`);
}

function showStats({ metrics, solve, timings, method, field, triangulation, duality, boundaryClip, boundaryOffset, relay }) {
  showNotes(triangulation?.notes ?? []);
  showSingularities(method === 'global' ? triangulation.singularities : null);
  const invalidStars = triangulation?.check?.invalidStars?.length;
  $('triangulation-info').textContent = [method, field, invalidStars === undefined ? null : `${invalidStars} invalid stars`]
    .filter(Boolean)
    .join(' · ') || '–';
  $('face-count').textContent = String(metrics.faceCount);
  $('faces-by-size').textContent = Object.entries(metrics.facesBySize)
    .map(([size, count]) => `${size}-gons ${count}`)
    .join(', ');
  $('hexagon-share').textContent = Number.isFinite(metrics.interiorHexagonFraction)
    ? `${(100 * metrics.interiorHexagonFraction).toFixed(1)} %`
    : '–';
  $('node-faces').textContent = nodeFaces(metrics.vertexValence);
  $('planarity-max').textContent = fmt(metrics.planarityMax);
  $('planarity-mean').textContent = fmt(metrics.planarityMean);
  $('planarity-diagonals').textContent = metrics.planarityDiagonals?.length
    ? `${fmt(metrics.planarityDiagonals.reduce((a, b) => Math.max(a, b), 0))} % max`
    : '–';
  showSpread('edge-length', metrics.edgeLengthMin, metrics.edgeLengthMean, metrics.edgeLengthMax);
  if (metrics.shortEdgeCount) $('edge-length').textContent += `, ${metrics.shortEdgeCount} under 1 % of the mean`;
  showSpread('face-area', metrics.faceAreaMin, metrics.faceAreaMean, metrics.faceAreaMax);
  $('invalid-faces').textContent = String(metrics.selfIntersectingCount);
  $('convexity-mismatch').textContent =
    metrics.convexityMismatchCount === undefined
      ? '–'
      : `${metrics.convexityMismatchCount} off${metrics.parabolicFaceCount ? `, ${metrics.parabolicFaceCount} across K = 0` : ''}`;
  $('regularity-mean').textContent = metrics.regularityMean === undefined ? '–' : metrics.regularityMean.toFixed(3);
  $('surface-distance').textContent = Number.isFinite(metrics.surfaceDistanceMax) ? `${fmt(metrics.surfaceDistanceMax)} max` : '–';
  $('edge-info').textContent = !boundaryOffset?.nodes
    ? '–'
    : [boundaryClip?.panels ? `${boundaryClip.panels} panels clipped` : null, boundaryClip?.skipped ? `${boundaryClip.skipped} not` : null,
       boundaryClip?.fillers ? `${boundaryClip.fillers} fillers` : null,
       boundaryClip?.cutDropped ? `${boundaryClip.cutDropped} cut panel${boundaryClip.cutDropped > 1 ? 's' : ''} dropped` : null,
       boundaryClip?.removed ? `${boundaryClip.removed} outside removed` : null,
       boundaryClip?.panels ? `gap ${boundaryClip.gapMax.toFixed(3)} edges` : null, `nodes off ${boundaryOffset.max.toFixed(3)} edges max`]
        .filter(Boolean)
        .join(', ');
  $('iterations').textContent = `${solve.iterations}${solve.converged ? '' : ' (not converged)'}${
    solve.boundaryPanelsSplit ? `, ${solve.boundaryPanelsSplit} boundary panel${solve.boundaryPanelsSplit > 1 ? 's' : ''} split` : ''}${
    solve.interiorFacesSplit ? `, ${solve.interiorFacesSplit} interior face${solve.interiorFacesSplit > 1 ? 's' : ''} split` : ''}${
    duality === 'tangent' && $('duality').value === 'auto' ? ', from the tangent dual' : ''}${
    solve.foldsAllowed ? ', solved without the fold guard (none left folded)' : ''}${
    relay?.tried
      ? relay.globally
        ? `, laid twice (Method 2's rows: ${relay.firstCoverageGap.toFixed(2)} edges bare at most, ${relay.firstNodesOfFour} nodes of four from cuts; ${relay.kept ? 'tiled by the global method' : 'the rows kept'})`
        : `, laid twice (the ${relay.kept ? 'second' : 'first'} lay kept)`
      : ''}${
    relay?.trials
      ? `, laid ${relay.trials} more time${relay.trials > 1 ? 's' : ''} for other face counts (its cuts left ${relay.trialNodesOfFour} nodes of four; ${relay.trialShare ? `the lay for ${Math.round(100 * relay.trialShare)} % of the faces kept` : 'the first kept'})`
      : ''}${
    relay?.noisyRepairs
      ? `, a noisy upload laid again with the repairs of a smooth one (${relay.noisyRepairsKept ? 'that lay kept' : 'the first lay kept'})`
      : ''}`;
  $('timings').textContent = Object.entries(timings)
    .filter(([stage]) => stage !== 'total')
    .map(([stage, t]) => `${stage} ${ms(t)}`)
    .concat(`total ${ms(timings.total)}`)
    .join(' · ');
}

// ---------------------------------------------------------------- runs

/** Computes the design of the form. Resolves with 'ok', 'error', 'cancelled' or 'superseded'. */
async function compute() {
  clearTimeout(rerunTimer);
  running?.abort();
  const controller = new AbortController();
  running = controller;
  setState('running');
  $('cancel').disabled = false;
  showProgress({ stage: 'start', fraction: 0, message: 'starting' });
  let params;
  try {
    params = readParams();
    const result = await phex.run(params, { onProgress: showProgress, signal: controller.signal });
    if (running !== controller) return 'superseded';
    const first = !last;
    last = { result, params, quantities: { hex: faceQuantities(result.hex, result.metrics), initial: faceQuantities(result.initial, null) } };
    clearError();
    await draw({ refit: first || params.surface !== lastSurfaceKey || Boolean(params.mesh) });
    lastSurfaceKey = params.surface;
    showStats(result);
    for (const button of document.querySelectorAll('.exports button')) button.disabled = false;
    $('stage').textContent = `done in ${ms(result.timings.total)} ms`;
    history.replaceState(null, '', designLink(params));
    markShown(first);
    setState('ready');
    return 'ok';
  } catch (error) {
    if (running !== controller) return 'superseded';
    if (error.code === 'cancelled') {
      $('stage').textContent = 'cancelled';
      setState(last ? 'ready' : 'error');
      return 'cancelled';
    }
    showError(error.message);
    $('stage').textContent = '';
    setState('error');
    return 'error';
  } finally {
    if (running === controller) {
      running = null;
      $('cancel').disabled = true;
      $('progress').value = 0;
      document.body.dataset.runs = String(++runs);
    }
  }
}
let lastSurfaceKey = null;

/** Performance marks: first mesh on screen after load, and edit → new mesh on screen. */
function markShown(first) {
  requestAnimationFrame(() => {
    performance.mark('phex:shown');
    if (first) performance.measure('phex:first-render', { start: 0, end: 'phex:shown' });
    else if (performance.getEntriesByName('phex:edit', 'mark').length) {
      performance.measure('phex:edit-to-screen', 'phex:edit', 'phex:shown');
      performance.clearMarks('phex:edit');
    }
  });
}

function scheduleRun() {
  performance.mark('phex:edit');
  clearTimeout(rerunTimer);
  rerunTimer = setTimeout(compute, RERUN_DELAY_MS);
}

async function applyPreset(label) {
  const { model } = PRESETS[label];
  const loaded = model ? await modelUpload(model) : null;
  if (model && !loaded) return;
  setUpload(loaded);
  writeForm(structuredClone(PRESETS[label].params));
  if (PRESETS[label].view?.color) $('color').value = PRESETS[label].view.color;
  lastSurfaceKey = null; // frame the new design
  compute();
}

// ---------------------------------------------------------------- uploads

/** Sets the form to a link's design, with its bundled model as the upload where it names one. */
async function openDesign({ params }) {
  setUpload(params.model ? await modelUpload(params.model) : null);
  writeForm(params);
}

/** A model bundled with the app (MODELS) as an upload, fetched; null, with the reason shown, when it cannot be. */
async function modelUpload(name) {
  try {
    if (!MODELS[name]) throw new Error('no such model in this app');
    const response = await fetch(MODELS[name].url);
    if (!response.ok) throw new Error(`${response.status} ${response.statusText}`);
    return { bytes: new Uint8Array(await response.arrayBuffer()), name, format: name.split('.').pop(), model: name };
  } catch (error) {
    showError(`Could not load the model ${name}: ${error.message}`);
    return null;
  }
}

function setUpload(value) {
  upload = value;
  $('mesh-source').hidden = !upload;
  // A bundled model names its source and licence (CC BY-SA asks for the credit where it is used).
  const credit = upload?.model ? ` — ${MODELS[upload.model].credit}` : '';
  $('mesh-name').textContent = upload ? `Mesh: ${upload.name} (${(upload.bytes.length / 1024).toFixed(0)} kB)${credit}` : '';
  $('surface').disabled = Boolean(upload);
  $('surface-params').disabled = Boolean(upload);
  // The analytic surface's description and parameters do not apply to an upload: hidden while one is loaded.
  $('surface-description').hidden = Boolean(upload);
  $('surface-params').hidden = Boolean(upload);
}

async function openFile(file) {
  const format = file.name.includes('.') ? file.name.split('.').pop().toLowerCase() : '';
  if (!MESH_FORMATS.includes(format)) {
    showError(`${file.name}: not a mesh file phex reads (use OBJ, OFF, PLY or STL).`);
    return;
  }
  if (!capabilities.meshInput) {
    showError(`Cannot open ${file.name}: this phex core build does not read meshes yet; choose an analytic surface.`);
    return;
  }
  const previous = upload;
  setUpload({ bytes: new Uint8Array(await file.arrayBuffer()), name: file.name, format });
  lastSurfaceKey = null;
  const outcome = await compute();
  // A file the core refuses is dropped again, so the next edit computes what was shown before.
  if (outcome === 'error') setUpload(previous);
}

function setUpDrop() {
  let depth = 0;
  const overlay = $('drop-overlay');
  addEventListener('dragenter', (event) => {
    if (!event.dataTransfer?.types.includes('Files')) return;
    depth++;
    overlay.hidden = false;
  });
  addEventListener('dragleave', () => {
    depth = Math.max(0, depth - 1);
    if (depth === 0) overlay.hidden = true;
  });
  addEventListener('dragover', (event) => event.preventDefault());
  addEventListener('drop', (event) => {
    event.preventDefault();
    depth = 0;
    overlay.hidden = true;
    const [file] = event.dataTransfer?.files ?? [];
    if (file) openFile(file);
  });
}

// ---------------------------------------------------------------- hover

function setUpHover() {
  const tooltip = $('tooltip');
  let frame = 0;
  viewer.canvas.addEventListener('pointermove', (event) => {
    if (frame || event.buttons) return;
    frame = requestAnimationFrame(() => {
      frame = 0;
      const view = $('view').value;
      const face = last && (view === 'hex' || view === 'initial') ? viewer.pick(event.clientX, event.clientY) : -1;
      tooltip.hidden = face < 0;
      if (face < 0) return;
      const q = last.quantities[view];
      const mesh = last.result[view];
      const rows = [
        // P<n>: the label the panel export gives this face (1-based, as in OBJ).
        ['Face', `${face} (${mesh.faceOffsets[face + 1] - mesh.faceOffsets[face]} corners)${view === 'hex' ? `, panel P${face + 1}` : ''}`],
        ['Planarity', fmt(q.get('planarity')[face])],
        ['Area', fmt(q.get('area')[face])],
        ['Convex', q.get('convexity')[face] ? 'yes' : 'no'],
        ['Regularity', Number.isFinite(q.get('regularity')[face]) ? q.get('regularity')[face].toFixed(3) : '–'],
      ];
      if (q.invalid) rows.push(['Self-intersecting', q.invalid[face] ? 'yes' : 'no']);
      if (q.mismatch?.[face]) rows.push(['Convexity', 'against the sign of K']);
      const distance = q.get('distance');
      if (distance) rows.push(['Distance to surface', fmt(distance[face])]);
      tooltip.replaceChildren(...rows.map(([k, v]) => Object.assign(document.createElement('div'), { textContent: `${k}: ${v}` })));
      const box = $('viewport').getBoundingClientRect();
      tooltip.style.left = `${event.clientX - box.left + 14}px`;
      tooltip.style.top = `${event.clientY - box.top + 14}px`;
    });
  });
  viewer.canvas.addEventListener('pointerleave', () => (tooltip.hidden = true));
}

// ---------------------------------------------------------------- exports

function download(data, name, type) {
  const link = document.createElement('a');
  link.href = typeof data === 'string' && data.startsWith('data:') ? data : URL.createObjectURL(new Blob([data], { type }));
  link.download = name;
  link.click();
  setTimeout(() => URL.revokeObjectURL(link.href), 0);
}

function baseName() {
  const source = upload ? upload.name.replace(/\.[^.]*$/, '') : last.params.surface;
  return `phex-${source}-${last.result.metrics.faceCount}`;
}

/** Typed arrays as plain arrays, for JSON. */
const plain = (value) => JSON.parse(JSON.stringify(value, (k, v) => (ArrayBuffer.isView(v) ? Array.from(v) : v)));

const EXPORTS = {
  'export-obj': () => download(meshToOBJ(last.result.hex), `${baseName()}.obj`, 'text/plain'),
  'export-ply': () => download(meshToPLY(last.result.hex, { planarity: last.result.metrics.planarity }), `${baseName()}.ply`, 'text/plain'),
  'export-json': () => {
    const { mesh, ...params } = last.params;
    const { hex, metrics, solve, timings } = last.result;
    const json = { generator: `phex ${phex.version}`, params: mesh ? { ...params, mesh: upload?.name } : params, mesh: hex, metrics, solve, timings };
    download(JSON.stringify(plain(json)), `${baseName()}.json`, 'application/json');
  },
  'export-gltf': async () => {
    const { GLTFExporter } = await import('three/addons/exporters/GLTFExporter.js');
    const glb = await new GLTFExporter().parseAsync(viewer.exportable(), { binary: true });
    download(glb, `${baseName()}.glb`, 'model/gltf-binary');
  },
  'export-tri': () => download(meshToOBJ(last.result.triangulation), `${baseName()}-triangulation.obj`, 'text/plain'),
  'export-png': () => download(viewer.snapshot(), `${baseName()}.png`, 'image/png'),
  'export-panels': async () => download(await phex.panels(last.result.hex), `${baseName()}-panels.svg`, 'image/svg+xml'),
  'export-schedule': async () => download(await phex.panels(last.result.hex, { format: 'csv' }), `${baseName()}-panels.csv`, 'text/csv'),
  // In the structure view the beam schedule carries the structure's beams (heights, plane, corners) too.
  'export-beams': async () => {
    const shown = $('view').value === 'structure' ? await structureOf() : null;
    const options = shown ? { ...structureOptions(), beamHeight: shown.report.beamHeight } : {};
    download(await phex.beams(last.result.hex, options), `${baseName()}-beams.csv`, 'text/csv');
  },
  'export-structure-gltf': async () => {
    const data = await structureOf();
    if (!data) return;
    const { GLTFExporter } = await import('three/addons/exporters/GLTFExporter.js');
    const glb = await new GLTFExporter().parseAsync(structureGroup(data.solid), { binary: true });
    download(glb, `${baseName()}-structure.glb`, 'model/gltf-binary');
  },
  'export-structure-obj': async () => download(await phex.structureOBJ(last.result.hex, structureOptions()), `${baseName()}-structure.obj`, 'text/plain'),
  'export-nodes': async () => download(await phex.nodes(last.result.hex), `${baseName()}-nodes.csv`, 'text/csv'),
  'export-offset-obj': async () => {
    const offset = await offsetLayer();
    if (offset) download(meshToOBJ(offset), `${baseName()}-offset.obj`, 'text/plain');
  },
  'export-offset-ply': async () => {
    const offset = await offsetLayer();
    if (offset) download(meshToPLY(offset), `${baseName()}-offset.ply`, 'text/plain');
  },
  'export-offset-gltf': async () => {
    const offset = await offsetLayer();
    if (!offset) return;
    const { positions, index } = triangulateFaces(offset);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(index, 1));
    const mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: 0x9cc7e6 }));
    mesh.name = 'offset';
    const { GLTFExporter } = await import('three/addons/exporters/GLTFExporter.js');
    download(await new GLTFExporter().parseAsync(mesh, { binary: true }), `${baseName()}-offset.glb`, 'model/gltf-binary');
  },
};

/** The offset layer at the form's offset distance (the structure view's Offset field), or null with the reason shown. */
async function offsetLayer() {
  const { offset } = structureOptions();
  if (offset === undefined) {
    showError('Offset: enter the face distance of the offset layer in the Offset field (View: structure).');
    return null;
  }
  return (await phex.structure(last.result.hex, { offset })).offset;
}

// ---------------------------------------------------------------- start

async function start() {
  setState('running');
  try {
    phex = await createPHex();
    surfaces = await phex.surfaces();
    capabilities = phex.capabilities();
  } catch (error) {
    showError(`phex could not start: ${error.message}`);
    setState('error');
    return;
  }
  document.body.dataset.meshInput = String(capabilities.meshInput);
  buildForm();
  const linked = designFromUrl();
  await openDesign(linked ?? { params: { surface: DEFAULT_SURFACE } });
  if (linked?.params.surface && !knownSurface(linked.params.surface)) {
    showError(`The link names an unknown surface "${linked.params.surface}"; showing the ${DEFAULT_SURFACE}.`);
  }
  for (const key of VIEW_KEYS) {
    const value = linked?.view[key];
    if (key === 'color') colorOptions();
    if (value && [...$(key).options].some((o) => o.value === value && !o.disabled)) $(key).value = value;
  }

  $('surface').addEventListener('change', () => {
    buildSurfaceParams($('surface').value);
    lastSurfaceKey = null;
    scheduleRun();
  });
  $('params').addEventListener('input', (event) => {
    if (event.target !== $('surface') && event.target !== $('file')) scheduleRun();
  });
  $('params').addEventListener('submit', (event) => {
    event.preventDefault();
    compute();
  });
  $('file').addEventListener('change', () => {
    const [file] = $('file').files;
    $('file').value = '';
    if (file) openFile(file);
  });
  $('mesh-clear').addEventListener('click', () => {
    setUpload(null);
    lastSurfaceKey = null;
    // The core keeps the upload's surface for the next run on it (clearUploadCache): the design is closed.
    phex.clearUploadCache().catch(() => {});
    compute();
  });
  $('method').addEventListener('input', showMethodOptions);  // before the form's listener reads the parameters
  $('cancel').addEventListener('click', () => running?.abort());
  $('view').addEventListener('change', () => {
    $('structure-params').hidden = $('view').value !== 'structure';
    draw().then(() => last && history.replaceState(null, '', designLink(last.params)));
  });
  let structureTimer = 0;
  $('structure-params').addEventListener('input', () => {
    clearTimeout(structureTimer);
    structureTimer = setTimeout(() => draw(), RERUN_DELAY_MS);
  });
  $('color').addEventListener('change', () => draw().then(() => last && history.replaceState(null, '', designLink(last.params))));
  $('wireframe').addEventListener('change', () => viewer.setShading(shading()));
  $('flat').addEventListener('change', () => draw());
  $('fit').addEventListener('click', () => viewer.fitToView());
  for (const [id, action] of Object.entries(EXPORTS)) {
    $(id).addEventListener('click', () => {
      if (!last) return;
      Promise.resolve()
        .then(action)
        .catch((error) => showError(`Export failed: ${error.message}`));
    });
  }
  $('copy-link').addEventListener('click', async () => {
    try {
      await navigator.clipboard.writeText(location.href);
      $('stage').textContent = 'link copied';
    } catch {
      showError(`Copy this link: ${location.href}`);
    }
  });
  addEventListener('hashchange', () => {
    const design = designFromUrl();
    if (!design || location.hash === designToHash(readParams())) return;
    openDesign(design).then(compute);
  });
  addEventListener('error', (event) => showError(String(event.message)));
  addEventListener('unhandledrejection', (event) => showError(String(event.reason?.message ?? event.reason)));
  $('structure-params').hidden = $('view').value !== 'structure';
  for (const spec of STRUCTURE_OPTIONS) $(spec.name).title = spec.description;
  setUpDrop();
  setUpHover();

  viewer.resize();
  await compute();
}

// Offline use: a service worker caches the app shell and the wasm (production builds only).
if (import.meta.env.PROD && 'serviceWorker' in navigator && location.protocol.startsWith('http')) {
  addEventListener('load', () => navigator.serviceWorker.register('./sw.js').catch(() => {}));
}

start();
