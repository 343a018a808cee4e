// phex web app — one-click designs after the paper's figures and on bundled models: the run parameters of each
// (surface, triangulation method, direction field, §5.3 lower bound), the model uploaded in place of the surface
// where there is one (`model`, a name in MODELS) and, optionally, the colouring to show.

// Meshes bundled with the app (web/models/, their sources and licences in its README), by file name: the file's URL
// and the credit the app shows with it. A literal `new URL(..., import.meta.url)` lets Vite emit each file with the
// build; Node reads it from web/models/.
export const MODELS = {
  'phcpf_3holes_r.off': {
    url: new URL('./models/phcpf_3holes_r.off', import.meta.url).href,
    credit: '3holes_r.off from PH-CPF (Pluta, Edelstein, Vaxman, Ben-Chen 2021), CC BY-SA 4.0',
  },
  'phcpf_car_r.off': {
    url: new URL('./models/phcpf_car_r.off', import.meta.url).href,
    credit: 'car_r.off from PH-CPF (Pluta, Edelstein, Vaxman, Ben-Chen 2021), CC BY-SA 4.0',
  },
};

export const PRESETS = {
  'Fig. 1 cyclide, progressive conjugation': {
    params: { surface: 'cyclide', faces: 2500, method: 'progressive' },
  },
  'Fig. 3 torus: convex and non-convex faces': {
    params: { surface: 'torus', surfaceParams: { R: 1, r: 0.45 }, faces: 600 },
    view: { color: 'convexity' },
  },
  'Fig. 11 hyperboloid, valid (K < 0)': {
    params: { surface: 'hyperboloid', faces: 1500 },
  },
  // The patch spans the elliptic part around the outer equator: on a patch reaching past the parabolic
  // circles (vSpan 200 or more) Method 1 converges only without the fold guard, leaving invalid stars and
  // faces cut (a known shortfall, see the README), where Method 2 lays every span cleanly.
  'Fig. 15 cyclide patch, progressive': {
    params: { surface: 'cyclide', surfaceParams: { uSpan: 180, vSpan: 120 }, faces: 1500, method: 'progressive' },
  },
  'Fig. 15 cyclide patch, pre-specified': {
    params: { surface: 'cyclide', surfaceParams: { uSpan: 180, vSpan: 120 }, faces: 1500, method: 'prespecified', field: 'principal' },
  },
  'Fig. 18 vase, step control bottom up': {
    params: { surface: 'vase', faces: 2000, method: 'progressive', lowerBound: 0.3 },
  },
  'Fig. 18 vase, longitudinal': {
    params: { surface: 'vase', faces: 2000, method: 'prespecified', field: 'angle:90' },
  },
  'Fig. 19 torus without lower bound': {
    params: { surface: 'torus', faces: 2000, method: 'progressive', lowerBound: 0 },
  },
  // L0 on a parallel of radius 0.95, just inside the parabolic circle (radius 1): the rows grow and shrink
  // within 0.63 .. 1.47 of their spacing and are never resampled, so every interior vertex keeps valence 6
  // and every face is a hexagon, none cut (from the default start on the inner equator the rows are
  // resampled twice: 91 %; from radius 0.87, 100 % valence 6 but 23 faces cut to reach planarity).
  'Fig. 19 torus with lower bound': {
    params: { surface: 'torus', faces: 2000, method: 'progressive', lowerBound: 0.5, start: [0.95, 0, 0.4] },
  },
  'Fig. 20 sphere, radial': {
    params: { surface: 'sphere', faces: 1500, method: 'prespecified', field: 'radial' },
  },
  'Fig. 20 sphere, diverging': {
    params: { surface: 'sphere', faces: 1500, method: 'prespecified', field: 'diverging' },
  },
  'Fig. 20 sphere, spiral': {
    params: { surface: 'sphere', faces: 1500, method: 'prespecified', field: 'spiral' },
  },
  'Fig. 21 minimal surface (Enneper)': {
    params: { surface: 'enneper', faces: 1500, method: 'prespecified', field: 'principal' },
  },
  'Fig. 21 convex mesh by Loop subdivision': {
    params: { surface: 'egg', faces: 1000, method: 'subdivision' },
  },
  'Fig. 22 free-form roof: hexagons, bricks at the parabolic curve, bow-ties': {
    params: { surface: 'wave-roof', faces: 4000, method: 'prespecified', field: 'principal' },
    view: { color: 'convexity' },
  },
  // A dome of revolution: its top is an umbilic, around which the curvature lines turn (laid along them: 4
  // systems, 85 % hexagons and an invalid star at 1500 faces). Plane sections and their conjugate lines are a
  // conjugate network without that singularity: 100 % hexagons. Method auto picks them on uploaded domes.
  'Dome of revolution along plane sections (no umbilic singularity)': {
    params: { surface: 'elliptic-paraboloid', surfaceParams: { ra: 1, rb: 1 }, faces: 1500, method: 'prespecified', field: 'section' },
  },
  // A developable (§3, §5.3): K = 0 everywhere, rows along the rulings; the hexagons of a ruling's vertices
  // share its tangent plane, so they are quad-shaped and planar as laid (0 solver iterations).
  'Cone along its rulings (developable: quad-shaped hexagons)': {
    params: { surface: 'cone', faces: 1500, method: 'prespecified', field: 'principal' },
  },
  'Two round bumps (umbilics: beyond the method, partly covered)': {
    params: { surface: 'freeform', faces: 2500, method: 'prespecified', field: 'principal' },
  },
  // Beyond the paper (§7 needs a network without singularities, which a closed surface of genus 3 cannot
  // have): the global method's field places heptagons and pentagons whose indices add up to 12 (1 - 3) = -24.
  'Genus 3 upload (PH-CPF), global field: heptagons at its singular points': {
    model: 'phcpf_3holes_r.off',
    params: { faces: 1500, method: 'global' },
  },
  // PH-CPF's car, closed and near-developable over a third of it, folds faces next to its near-parabolic parts: laid
  // on the smooth blend of its jets (its triangles are over a cell at 1000 faces), the lay kept first reached a P-Hex
  // mesh only by cutting faces (184 nodes of four), and the run lays it again with the rounds against folds on more
  // folds: planar to 1e-9 with no face cut, every node of three faces, 74 % hexagons (the pentagons and heptagons
  // stand where the rounds merged vertices). (This preset was the car with a share of cuts of 0.3, planar with 72 faces
  // cut, until its lays were laid again where they cut many faces.)
  'Near-developable car upload (PH-CPF): planar, no face cut': {
    model: 'phcpf_car_r.off',
    params: { faces: 1000, method: 'global' },
  },
};
