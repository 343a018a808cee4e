// phex web app — per-face quantities to colour by, their colour scales and legends.
// The core's per-face arrays are used where a result has them; the rest are computed here.
import * as THREE from 'three';
import { faceAreas } from 'phex';

const SEQUENTIAL = ['#30123b', '#3e6ff2', '#1ccfd5', '#62fc6b', '#d4e735', '#fb8022', '#b21a02'].map((c) => new THREE.Color(c));
const DIVERGING = ['#2166ac', '#67a9cf', '#d1e5f0', '#f7f7f7', '#fddbc7', '#ef8a62', '#b2182b'].map((c) => new THREE.Color(c));
const INVALID = new THREE.Color(0xd4148c); // self-intersecting faces, off every scale
const CONVEX = new THREE.Color(0x3e7fc1);
const NON_CONVEX = new THREE.Color(0xf08a24);
const MISMATCH = new THREE.Color(0xc62828); // convexity disagrees with the sign of K
const NONE = new THREE.Color(0xb9c6d6);
const DECADES_BELOW_GOAL = 6;
const DECADES_ABOVE_GOAL = 1;

/** The colour modes of polygon views: label, and whether a result is needed that has the data. */
export const FACE_MODES = {
  planarity: 'Planarity',
  convexity: 'Convexity (K > 0: convex)',
  regularity: 'Regularity',
  distance: 'Distance to surface',
  area: 'Face area',
  none: 'Plain',
};

export const CURVATURE_MODES = { gaussian: 'Gaussian curvature K', mean: 'Mean curvature H' };

function ramp(stops, t, target) {
  const x = THREE.MathUtils.clamp(Number.isFinite(t) ? t : 0, 0, 1) * (stops.length - 1);
  const i = Math.min(Math.floor(x), stops.length - 2);
  return target.lerpColors(stops[i], stops[i + 1], x - i);
}

const gradient = (stops) => `linear-gradient(to right, ${stops.map((c, i) => `#${c.getHexString()} ${((100 * i) / (stops.length - 1)).toFixed(1)}%`).join(', ')})`;
const fmt = (x) => (x === 0 ? '0' : Math.abs(x) >= 0.01 && Math.abs(x) < 1e4 ? x.toPrecision(3) : x.toExponential(2));

/** Face normal by Newell's method (unnormalized vector area). */
function newellNormal(p, corners) {
  const n = new THREE.Vector3();
  for (let i = 0; i < corners.length; i++) {
    const a = 3 * corners[i];
    const b = 3 * corners[(i + 1) % corners.length];
    n.x += (p[a + 1] - p[b + 1]) * (p[a + 2] + p[b + 2]);
    n.y += (p[a + 2] - p[b + 2]) * (p[a] + p[b]);
    n.z += (p[a] - p[b]) * (p[a + 1] + p[b + 1]);
  }
  return n.normalize();
}

function cornersOf(mesh, f) {
  return mesh.faceIndices.subarray(mesh.faceOffsets[f], mesh.faceOffsets[f + 1]);
}

/**
 * Per-face quantities of a polygon mesh. `metrics` are the core's (of result.hex) or null (the
 * initial mesh): then planarity is estimated here against the Newell plane.
 */
export function faceQuantities(mesh, metrics) {
  const p = mesh.positions;
  const count = mesh.faceOffsets.length - 1;
  const cache = {};
  const compute = {
    area: () => metrics?.faceArea ?? faceAreas(mesh),
    planarity: () => {
      if (metrics) return metrics.planarity;
      const out = new Float64Array(count);
      for (let f = 0; f < count; f++) {
        const c = cornersOf(mesh, f);
        const n = newellNormal(p, c);
        let cx = 0;
        let cy = 0;
        let cz = 0;
        for (const v of c) (cx += p[3 * v]), (cy += p[3 * v + 1]), (cz += p[3 * v + 2]);
        (cx /= c.length), (cy /= c.length), (cz /= c.length);
        let worst = 0;
        let perimeter = 0;
        for (let i = 0; i < c.length; i++) {
          const a = 3 * c[i];
          const b = 3 * c[(i + 1) % c.length];
          worst = Math.max(worst, Math.abs((p[a] - cx) * n.x + (p[a + 1] - cy) * n.y + (p[a + 2] - cz) * n.z));
          perimeter += Math.hypot(p[a] - p[b], p[a + 1] - p[b + 1], p[a + 2] - p[b + 2]);
        }
        out[f] = worst / (perimeter / c.length);
      }
      return out;
    },
    // 1 convex, 0 not: every turn has the same sign about the face normal (§4.2).
    convexity: () => {
      if (metrics?.convex) return metrics.convex;
      const out = new Uint8Array(count);
      const e1 = new THREE.Vector3();
      const e2 = new THREE.Vector3();
      for (let f = 0; f < count; f++) {
        const c = cornersOf(mesh, f);
        const n = newellNormal(p, c);
        let positive = 0;
        let negative = 0;
        for (let i = 0; i < c.length; i++) {
          const a = 3 * c[i];
          const b = 3 * c[(i + 1) % c.length];
          const d = 3 * c[(i + 2) % c.length];
          e1.set(p[b] - p[a], p[b + 1] - p[a + 1], p[b + 2] - p[a + 2]);
          e2.set(p[d] - p[b], p[d + 1] - p[b + 1], p[d + 2] - p[b + 2]);
          const turn = e1.cross(e2).dot(n);
          if (turn > 0) positive++;
          else if (turn < 0) negative++;
        }
        out[f] = positive === 0 || negative === 0 ? 1 : 0;
      }
      return out;
    },
    // Affine regularity of hexagons: opposite edges of an affine regular hexagon are equal and
    // opposite (e_i = -e_{i+3}); 1 - Σ|e_i + e_{i+3}| / Σ|e_i| is 1 for those. NaN for other polygons.
    regularity: () => {
      if (metrics?.regularity) return metrics.regularity;
      const out = new Float64Array(count).fill(Number.NaN);
      for (let f = 0; f < count; f++) {
        const c = cornersOf(mesh, f);
        if (c.length !== 6) continue;
        const edge = (i) => {
          const a = 3 * c[i % 6];
          const b = 3 * c[(i + 1) % 6];
          return [p[b] - p[a], p[b + 1] - p[a + 1], p[b + 2] - p[a + 2]];
        };
        let defect = 0;
        let length = 0;
        for (let i = 0; i < 6; i++) {
          const e = edge(i);
          length += Math.hypot(...e);
          if (i < 3) {
            const o = edge(i + 3);
            defect += 2 * Math.hypot(e[0] + o[0], e[1] + o[1], e[2] + o[2]);
          }
        }
        out[f] = Math.max(0, 1 - defect / length);
      }
      return out;
    },
    // Per face: the largest distance of its corners to the surface (relative to the bounding-box diagonal).
    distance: () => {
      const d = metrics?.surfaceDistance;
      if (!d || d.length === 0) return null;
      const out = new Float64Array(count);
      for (let f = 0; f < count; f++) for (const v of cornersOf(mesh, f)) out[f] = Math.max(out[f], d[v]);
      return out;
    },
  };
  return {
    get(name) {
      if (!(name in cache)) cache[name] = compute[name]?.() ?? null;
      return cache[name];
    },
    invalid: metrics?.selfIntersecting ?? null,
    mismatch: metrics?.convexityMismatch ?? null,
  };
}

function range(values) {
  let lo = Infinity;
  let hi = -Infinity;
  for (const v of values) if (Number.isFinite(v)) (lo = Math.min(lo, v)), (hi = Math.max(hi, v));
  return lo <= hi ? [lo, hi] : [0, 1];
}

/**
 * The colour function and legend of a face colour mode: {faceColor(f, color), legend: {title, background,
 * low, high, mark?}}. `tolerance` anchors the planarity scale (log10, the goal near the top).
 */
export function faceColoring(mode, quantities, tolerance) {
  const invalid = quantities.invalid;
  const wrap = (color) => (f, target) => (invalid?.[f] ? target.copy(INVALID) : color(f, target));
  if (mode === 'planarity') {
    const values = quantities.get('planarity');
    const low = Math.log10(tolerance) - DECADES_BELOW_GOAL;
    const high = Math.log10(tolerance) + DECADES_ABOVE_GOAL;
    const position = (x) => (Math.log10(Math.max(x, 1e-300)) - low) / (high - low);
    return {
      faceColor: wrap((f, c) => ramp(SEQUENTIAL, position(values[f]), c)),
      legend: {
        title: `Face planarity (goal ${fmt(tolerance)} at the mark; magenta: invalid face)`,
        background: gradient(SEQUENTIAL),
        low: `≤ ${fmt(10 ** low)}`,
        high: `≥ ${fmt(10 ** high)}`,
        mark: position(tolerance),
      },
    };
  }
  if (mode === 'convexity') {
    const values = quantities.get('convexity');
    const mismatch = quantities.mismatch;
    const stops = [CONVEX, NON_CONVEX, ...(mismatch ? [MISMATCH] : [])].map((c) => `#${c.getHexString()}`);
    const third = 100 / stops.length;
    return {
      faceColor: wrap((f, c) => c.copy(mismatch?.[f] ? MISMATCH : values[f] ? CONVEX : NON_CONVEX)),
      legend: {
        title: `Convex faces where K > 0, non-convex where K < 0 (§4.2)${mismatch ? '; red: against the sign of K' : ''}; magenta: invalid`,
        background: `linear-gradient(to right, ${stops.map((c, i) => `${c} ${i * third}% ${(i + 1) * third}%`).join(', ')})`,
        low: 'convex',
        high: mismatch ? 'non-convex · against K' : 'non-convex',
      },
    };
  }
  if (mode === 'none') {
    return { faceColor: wrap((f, c) => c.copy(NONE)), legend: null };
  }
  const values = quantities.get(mode);
  if (!values) return faceColoring('none', quantities, tolerance);
  const [lo, hi] = mode === 'regularity' ? [Math.min(range(values)[0], 0.9), 1] : range(values);
  const titles = {
    regularity: 'Affine regularity of hexagons (1: affine regular)',
    distance: 'Largest corner distance to the surface / bounding-box diagonal',
    area: 'Face area (model units²)',
  };
  return {
    faceColor: wrap((f, c) => (Number.isFinite(values[f]) ? ramp(SEQUENTIAL, (values[f] - lo) / (hi - lo || 1), c) : c.copy(NONE))),
    legend: { title: titles[mode], background: gradient(SEQUENTIAL), low: fmt(lo), high: fmt(hi) },
  };
}

/** Per-vertex curvature colours on a diverging scale symmetric about 0 (98th percentile of |value|). */
export function curvatureColoring(mode, { k1, k2 }) {
  const values = Float64Array.from(k1, (a, i) => (mode === 'mean' ? 0.5 * (a + k2[i]) : a * k2[i]));
  const magnitudes = Float64Array.from(values, Math.abs).sort();
  const scale = magnitudes[Math.floor(0.98 * (magnitudes.length - 1))] || 1;
  return {
    vertexColor: (v, c) => ramp(DIVERGING, 0.5 + (0.5 * values[v]) / scale, c),
    legend: {
      title: `${CURVATURE_MODES[mode]} (white: 0${mode === 'gaussian' ? ', parabolic' : ''})`,
      background: gradient(DIVERGING),
      low: `≤ ${fmt(-scale)}`,
      high: `≥ ${fmt(scale)}`,
      mark: 0.5,
    },
  };
}

export { fmt };
