// phex — typings of the JavaScript API (phex.js). Lengths are in the model units of the surface.

/** What kind of failure a {@link PHexError} reports. */
export type PHexErrorCode =
  /** A parameter has the wrong type or is out of its range; the message names it. */
  | 'invalid_parameter'
  /** A malformed mesh or file (bad counts, NaN, non-manifold, empty ...). */
  | 'invalid_input'
  /** The method cannot produce a valid P-Hex mesh for this surface or choice of parameters. */
  | 'cannot_tile'
  /** The run was cancelled through its AbortSignal, or the instance was disposed. */
  | 'cancelled'
  /** This core build lacks the feature asked for (mesh input, a method, ...): see {@link PHex.capabilities}. */
  | 'unsupported'
  /** The wasm module or the worker could not be loaded. */
  | 'io'
  /**
   * The run needed more memory than the WebAssembly core can hold (2 GB: about 250k faces from a 20k-triangle
   * upload): ask for fewer faces. The core is restarted for the next call, which gives the memory back.
   */
  | 'out_of_memory'
  /** A bug in phex: please report it. */
  | 'internal';

/** Error of every failed phex call. */
export class PHexError extends Error {
  constructor(code: PHexErrorCode, message: string);
  readonly name: 'PHexError';
  /** What kind of failure this is. */
  readonly code: PHexErrorCode;
}

/** A polygon mesh: vertices and faces of any size, stored flat. */
export interface Mesh {
  /** Vertex coordinates x, y, z of each vertex: length 3 × vertex count. */
  positions: Float64Array;
  /** Face f's corners are faceIndices[faceOffsets[f] .. faceOffsets[f + 1]): length face count + 1. */
  faceOffsets: Uint32Array;
  /** Vertex indices (0-based) of the face corners, in order around each face. */
  faceIndices: Uint32Array;
}

/** Polylines stored flat: line i has the points offsets[i] .. offsets[i + 1] - 1 of `positions`. */
export interface Polylines {
  /** Point coordinates x, y, z: length 3 × point count. */
  positions: Float64Array;
  /** Length line count + 1. */
  offsets: Uint32Array;
}

/** Singular points of a direction field, stored flat: point i is positions[3i .. 3i + 2] with index[i]. */
export interface Singularities {
  /** Coordinates x, y, z of each point, in the coordinates of the surface (of the uploaded file): 3 × point count. */
  positions: Float64Array;
  /** The turn of the field's directions around each point, in sixths of a turn: +1 or −1 mostly. */
  index: Int32Array;
}

/** The triangle mesh laid on the surface, whose dual is the hexagonal mesh. */
export interface Triangulation {
  /** Vertex coordinates: length 3 × vertex count. */
  positions: Float64Array;
  /** Vertex indices (0-based), three per triangle. */
  triangles: Uint32Array;
  /**
   * Integral lines of the direction field the triangulation follows, when the method has one; for method
   * 'global', short segments of the field's three directions.
   */
  fieldLines?: Polylines;
  /**
   * The singular points of the field method 'global' laid along (empty for the other methods): where its
   * directions turn around a point. A P-Hex face of 6 − index corners stands at each (+1: a pentagon, −1: a
   * heptagon). On a closed surface of genus g the indices add up to 12 (1 − g).
   */
  singularities?: Singularities;
  /** What the method had to do: lower bound active, steps re-used across parabolic curves, stars repaired, ... */
  notes: string[];
  /**
   * Systems of rows laid, each from its own base curve: more than 1 where the rows from the first left much
   * of the surface uncovered (round bumps, where no one regular conjugate network exists), with seams between.
   */
  systems: number;
  /** Propositions 4/5 on every star (§4.2), valences, edge lengths, coverage. */
  check: TriangulationCheck;
}

/** The check of a triangulation's stars (§4.2). */
export interface TriangulationCheck {
  interiorVertices: number;
  /** Interior vertices of valence 6 over interior vertices. */
  regularFraction: number;
  /** Interior vertices whose star fails Proposition 4 (K > 0) or 5 (K < 0). */
  invalidStars: Uint32Array;
  /** Interior vertices at or across a parabolic curve, where the propositions cannot judge. */
  parabolicStars: number;
  edgeMin: number;
  edgeMax: number;
  edgeMean: number;
  /** Triangulation area over surface area (about 1: the whole surface is covered); -1 when unknown. */
  coverage: number;
}

/** Quality measures of the P-Hex mesh. */
export interface Metrics {
  /**
   * Per face: the distance of its farthest corner from its least-squares plane, divided by the
   * face's mean edge length (dimensionless; 0 for a perfectly planar face).
   */
  planarity: Float64Array;
  /** Per face: 1 when two non-adjacent edges cross (seen in its plane) or an edge is degenerate (an invalid face), else 0. */
  selfIntersecting: Uint8Array;
  vertexCount: number;
  faceCount: number;
  /** Number of faces by number of corners, keyed by that number as a string: {"6": 1940, "5": 12, ...}. */
  facesBySize: Record<string, number>;
  /** Largest per-face planarity (dimensionless). */
  planarityMax: number;
  /** Mean per-face planarity (dimensionless). */
  planarityMean: number;
  /** Number of self-intersecting faces. */
  selfIntersectingCount: number;
  /** Per-vertex distance to the surface, divided by the surface's bounding-box diagonal (#V). */
  surfaceDistance: Float64Array;
  /** Largest and mean of `surfaceDistance`. Where nodes lie off by over 0.01 (five times the 0.2 % goal) and a
   * mean edge, the notes name the farthest, and the command line exits 2. */
  surfaceDistanceMax: number;
  surfaceDistanceMean: number;
  /** Per face: area in model units squared (older cores lack it: use {@link faceAreas}). */
  faceArea?: Float64Array;
  /** Per face: 1 for a convex face, else 0. */
  convex?: Uint8Array;
  /** Per face: 1 where convexity disagrees with the sign of the Gaussian curvature (§4.2: convex where K > 0, non-convex where K < 0). */
  convexityMismatch?: Uint8Array;
  convexityMismatchCount?: number;
  /** Faces across a parabolic curve (their corners lie where K has another sign): not judged for convexity. */
  parabolicFaceCount?: number;
  /** Hexagons among the faces not on the boundary (a P-Hex mesh's goal: ≥ 0.9). */
  interiorHexagonFraction: number;
  /** Per face: affine regularity in [0, 1] (1 for an affine regular hexagon). */
  regularity?: Float64Array;
  regularityMean?: number;
  /** Per face: 1 for a face on the mesh boundary (closed into a planar polygon). */
  boundaryFace?: Uint8Array;
  /** Per face: planarity measured on the diagonals (dimensionless). */
  planarityDiagonals?: Float64Array;
  /** Edge lengths and face areas of the mesh, in model units. */
  edgeLengthMin?: number;
  edgeLengthMax?: number;
  edgeLengthMean?: number;
  /**
   * Edges shorter than 1 % of the mean edge, each counted once: their two nodes nearly coincide, so four panels
   * meet there in effect (next to parabolic curves a planar hexagon tends to a quad).
   */
  shortEdgeCount?: number;
  faceAreaMin?: number;
  faceAreaMax?: number;
  faceAreaMean?: number;
  /** Number of vertices by valence, keyed by the valence as a string. */
  vertexValence?: Record<string, number>;
}

/** One iteration of the planarity optimization. */
export interface IterationLog {
  /** Round number; the closeness weight lambda is divided by 10 between rounds. */
  round: number;
  /** Iteration number within the run. */
  iteration: number;
  /** Closeness weight used in this iteration. */
  lambda: number;
  /** Objective value after the iteration. */
  objective: number;
  /** Largest per-face planarity after the iteration (dimensionless). */
  planarityMax: number;
  /** Wall time of the iteration, in milliseconds. */
  milliseconds: number;
}

/** How the planarity optimization went. */
export interface SolveReport {
  /** Solver iterations done, over all rounds (0 when the initial mesh was already planar). */
  iterations: number;
  rounds: number;
  /** Whether the planarity goal (`tolerance`) was reached. */
  converged: boolean;
  /** Largest per-face planarity before optimization (dimensionless). */
  initialPlanarityMax: number;
  /** Largest per-face planarity after optimization (dimensionless). */
  planarityMax: number;
  /** Largest vertex move from the initial mesh, divided by the mean edge length. */
  displacementMax: number;
  /** Whether the face planes were shifted towards the surface after planarity (`surfaceFit: 'on'`). */
  surfaceFitted: boolean;
  /** Boundary panels cut in two to become planar (`splitBoundary: 'on'`); each piece is a face of `hex`. */
  boundaryPanelsSplit?: number;
  /** Interior faces cut in two the same way: a few left off planar where only folding would make them planar. */
  interiorFacesSplit?: number;
  /**
   * The solve kept ran without the fold guard (`folds: 'prevent'`, the default): the guarded one stalled short of
   * `tolerance`, and unguarded the mesh reached it with no face crossing itself and at most 1 in 10 faces cut
   * (the guard had refused steps through such shapes on the way to planar ones); or, with `method: 'global'`,
   * the guarded one converged only by cutting more interior faces than fold unguarded, or a quarter of the boundary
   * panels, and the unguarded one's cuts made fewer nodes of four faces, with its nodes as near the surface; or,
   * with the solver's `fairness` (method 'global', not on noisy uploads), the unguarded solve came first and
   * converged with none crossing itself, within a tenth of the faces cut and the distance goal.
   */
  foldsAllowed?: boolean;
  /** The solver the result comes from (the one asked for). */
  method?: 'local' | 'planes' | 'volumes';
  /** Largest node distance to the surface over its bounding-box diagonal, before and after that shift. */
  surfaceDistanceBefore: number;
  surfaceDistanceAfter: number;
  /**
   * Nodes on fewer than three face planes (at the boundary, or among the triangles of cuts) then put nearest
   * to the surface along the directions those planes leave free: the faces stay exactly as planar.
   */
  freeNodesSettled: number;
  /** Boundary nodes then put on the surface's boundary curve as seen along the surface's normal (a node on two
   * planes along their line, to where it meets the curve's normal strip): the faces stay exactly as planar. */
  boundaryNodesPlaced: number;
  log: IterationLog[];
}

/** Wall time of each stage, in milliseconds. */
export interface Timings {
  triangulate: number;
  dualize: number;
  planarize: number;
  measure: number;
  /** The whole run, including conversions. */
  total: number;
}

/** What {@link PHex.run} resolves with. */
export interface Result {
  /** The P-Hex mesh: mostly hexagons with planar faces. */
  hex: Mesh;
  /** The dual mesh before the planarity optimization. */
  initial: Mesh;
  /** The triangulation the dual was taken of. */
  triangulation: Triangulation;
  /** Quality measures of `hex`. */
  metrics: Metrics;
  solve: SolveReport;
  timings: Timings;
  /** Number of dual vertices placed at their triangle's centroid because the duality was ill-posed there (near parabolic points). */
  dualFallbacks: number;
  /** Dual points placed by the tangent planes or at the centroid instead of the Dupin centre, where interior
   * faces crossed themselves across a parabolic curve. */
  dualUntangled: number;
  /** The duality the initial mesh came from: the one asked for; under 'auto', 'tangent' where the solve from the
   * Dupin dual stalled or left faces crossing themselves and the tangent dual did better. */
  duality: 'dupin' | 'tangent';
  /** The triangulation method used ('auto' resolved). */
  method: Exclude<Method, 'auto'>;
  /** The direction field the conjugate methods laid along ('auto' resolved); '' for lattice and subdivision. */
  field: string;
  /** The uploaded mesh's surface (its estimated curvature and search structures) came from the previous run or
   * preview on the same upload: see {@link PHex.clearUploadCache}. Always false for analytic surfaces. A coarse
   * upload laid finer than its triangles is laid on its smooth refinement (a note says so), kept with it. */
  surfaceReused: boolean;
  /** P-Hex nodes off the surface by over 1 % of the diagonal (five times the goal) and a mean edge: a shortfall
   * the notes name (the farthest, where), for which the command line exits 2. 0 for a good result. */
  farNodes: number;
  /** The largest distance from the surface (the upload's vertices, or samples of an analytic surface) to the
   * P-Hex mesh, in mean panel edges: over 1 means a hole or a strip left bare. */
  coverageGap: number;
  /** How far the P-Hex mesh's boundary nodes lie from the surface's boundary curve across the surface (their
   * height over it left out), in mean panel edges: 0 where the boundary panels end at the curve. Over `nodes`
   * boundary nodes (0 on a closed surface). */
  boundaryOffset: { max: number; median: number; nodes: number };
  /** The boundary panels clipped to the boundary curve (`clipBoundary: 'on'`): `panels` clipped, `skipped`
   * (their clipped outline would cross itself), nodes moved along their shared edge onto the curve, curve
   * points added and one-panel boundary nodes they replaced, and `gapMax`: the edge as drawn, the largest distance
   * from the curve to the mesh's outline (the curve's height over the clipped panels' planes; where panels could
   * not be clipped, how far their edges stay from it), in mean panel edges, at most 2; `removed`: boundary panels
   * lying wholly outside the curve (a sliver of a panel cut against a fold), taken away before the panels then on
   * the boundary were clipped. All 0 on a closed surface. */
  boundaryClip: { panels: number; skipped: number; nodesMoved: number; nodesAdded: number; nodesRemoved: number; fillers: number; removed: number; cutDropped: number; gapMax: number };
  /** A second lay (`relay: 'on'`): whether it ran, whether this result is its, and how the first lay ended: whether
   * it reached a P-Hex mesh, the nodes of four faces its cuts made (two per interior face cut, one per boundary
   * panel) and its coverage gap (mean panel edges). Either method 'global''s lay again following the Dupin metric
   * further (the anisotropy and curvature floor it followed), or (`globally`) an upload under 'auto' that Method 2's
   * rows left partly bare (coverage gap over 1), brought to a P-Hex mesh only by cutting faces, or left unsolved,
   * tiled by the global method. `tried` false: one lay. `trials`: where the lay kept still had nodes of four faces
   * from cuts (`trialNodesOfFour`) at up to 5000 faces, how many trial lays for 3 % fewer and more faces ran, and the
   * share of the faces asked (or the cell's scale as for it) of the one kept (`trialShare`; 0: the lay before them).
   * A noisy upload whose first lay did not reach a P-Hex mesh is laid again with the repairs of a smooth upload (the
   * solver's fairness, the changes at folded boundary panels, the dislocation glides, the relay and the trials):
   * `noisyRepairs`, and whether that lay was kept (`noisyRepairsKept`: it reached one). */
  relay: { tried: boolean; kept: boolean; globally: boolean; anisotropy: number; curvatureFloor: number; firstReached: boolean; firstNodesOfFour: number; firstCoverageGap: number; trials: number; trialNodesOfFour: number; trialShare: number; noisyRepairs: boolean; noisyRepairsKept: boolean };
  /** An upload far from the origin (more than ten times its size: site coordinates) is computed about the
   * centre of its box, this point, where its coordinates keep their digits; every mesh and note here is in the
   * file's coordinates all the same. [0, 0, 0] otherwise. */
  origin: [number, number, number];
}

/** A triangulation method (§5): see {@link RunParams.method}. */
export type Method = 'auto' | 'lattice' | 'progressive' | 'prespecified' | 'subdivision' | 'global';

/** A direction field for pre-specified conjugation (§5.3): see {@link RunParams.field}. */
export type Field = 'principal' | `angle:${number}` | 'param' | 'param:u' | 'param:v' | 'radial' | 'diverging' | `diverging:${number}` | 'spiral' | `spiral:${number}` | 'section' | `section:${number}`;

/** A mesh file format accepted as input. */
export type MeshFormat = 'obj' | 'off' | 'ply' | 'stl';

/**
 * Parameters of {@link PHex.run}. Exactly one of `surface` (an analytic surface) or `mesh` (the bytes
 * of a triangle-mesh file) is required; the rest take the defaults shown.
 */
export interface RunParams {
  /** Name of an analytic surface, e.g. "torus" (see {@link PHex.surfaces}). */
  surface?: string;
  /**
   * The bytes of a triangle mesh file to tile instead of an analytic surface. Needs
   * `capabilities().meshInput`; rejected with code 'unsupported' otherwise, 'invalid_input' for a bad file.
   */
  mesh?: Uint8Array | ArrayBuffer;
  /** Format of `mesh`; sniffed from the content when missing. */
  meshFormat?: MeshFormat;
  /** Name of `mesh` (e.g. its file name), used in error messages. */
  meshName?: string;
  /** Parameters of that surface by name; missing ones take their defaults (see {@link SurfaceParameter}). */
  surfaceParams?: Record<string, number>;
  /** Wanted number of hexagons, an integer in 12 .. 1 000 000. Default 2000. Ignored when `cell` > 0. */
  faces?: number;
  /** Wanted edge length of the triangulation, in model units; 0 means: derive it from `faces`. Default 0. */
  cell?: number;
  /** Planarity goal, relative to edge length (dimensionless), in (0, 0.1]. Default 1e-9. */
  tolerance?: number;
  /** Initial closeness weight, in [0, 1e6], divided by 10 every round. Default 1. */
  lambda?: number;
  /** Weight of the distance to the surface, in [0, 1e6]. Default 0. */
  mu?: number;
  /** Cap on solver iterations, an integer in 1 .. 10 000. Default 100. */
  maxIterations?: number;
  /**
   * Initial dual mesh of the optimization: 'dupin' averages the centres of the Dupin conics of each
   * triangle; 'tangent' intersects the tangent planes at its three vertices; 'auto' (default) starts from
   * 'dupin' and tries 'tangent' as well where that solve stalls or leaves faces crossing themselves, keeping
   * the better (result.duality says which).
   */
  duality?: 'auto' | 'dupin' | 'tangent';
  /**
   * Planarity solver. 'local' (default): per-face planes and vertices updated in turn, one small solve
   * per vertex, the fastest. 'planes': the same energy by Gauss-Newton with Schur elimination (Ceres).
   * 'volumes': the paper's tetrahedron-volume objective by Gauss-Newton (Ceres), the reference.
   */
  solver?: 'local' | 'planes' | 'volumes';
  /**
   * 'prevent' (default): the local solver never turns a simple face into a self-intersecting one; where a
   * triangulation leaves that as the only way to planarity it stops short (`solve.converged` false).
   * 'allow': faces may fold to reach the planarity goal.
   */
  /** Where the conjugate methods start their base curve L0: a point near the surface (default: chosen by trial lays). */
  start?: [number, number, number] | null;
  /** Which way L0 runs at the start, projected onto the tangent plane (default: along the smaller normal curvature). */
  direction?: [number, number, number] | null;
  folds?: 'prevent' | 'allow';
  /**
   * 'on' (default): once planar, every face plane is shifted along its normal (each node following to the
   * intersection of its planes, so faces stay exactly planar) to bring the nodes closer to the surface;
   * kept only where the largest distance drops without folding a face (`solve.surfaceFitted`); then nodes on
   * fewer than three face planes are put nearest to the surface along the directions those planes leave free
   * (`solve.freeNodesSettled`), and the boundary nodes onto the surface's boundary curve
   * (`solve.boundaryNodesPlaced`, `boundaryOffset`). 'off': none of these.
   */
  surfaceFit?: 'on' | 'off';
  /**
   * 'on' (default): a boundary panel the solve leaves off planar, while every face away from it is planar
   * (where a boundary meets a parabolic curve a panel can have no planar shape that does not fold), or one
   * that crosses itself, is cut in two along its best diagonal and the solve goes on
   * (`solve.boundaryPanelsSplit`); so are interior faces left off planar where only folding would make
   * them planar (`solve.interiorFacesSplit`): a few (at most 8), or all of them where the solve stalled
   * (up to 1 in 20 faces) or on a surface laid in several systems of rows or by the global method (up to
   * `cutShare` of them, by default 1 in 10). 'off': not.
   */
  splitBoundary?: 'on' | 'off';
  /** The largest share of the interior faces, in [0, 1], that may be cut in two so that the mesh comes out planar (default 0.1; each cut makes two nodes of four faces). */
  cutShare?: number;
  /**
   * 'on' (default): once solved, the boundary panels are clipped to the surface's boundary curve: their boundary
   * edges follow the curve projected onto each panel's plane (so they stay planar), the nodes shared with their
   * neighbours move along the shared edge onto it (`boundaryClip`). 'off': the boundary as the dual ends it.
   */
  clipBoundary?: 'on' | 'off';
  /**
   * Method 'global': where the dual, solved with folds allowed, has faces crossing themselves (next to parabolic
   * curves; at most 8 % of the faces, so not on a coarse or noisy upload), each such face's vertex is merged
   * with its neighbour along the flatter principal direction (else an edge of its star is flipped) and the solve
   * run again, three rounds at most ('on', default): fewer faces cut later, each cut making two nodes of four
   * faces (on analytic surfaces at a point or two of hexagons). 'off': the triangulation as the field gives it.
   */
  foldFlips?: 'on' | 'off';
  /**
   * Method 'global': the lattice's dislocations (a vertex of five next to one of seven, where the position field
   * adds or drops a half row) cancelled before the triangle mesh is extracted, each joined with one of the
   * opposite sense or moved into a singular point of the field ('cancel', default:
   * more hexagons, rows that run on unbroken); 'keep': the lattice as the position field leaves it.
   */
  dislocations?: 'cancel' | 'keep';
  /**
   * Method 'global': also solve the direction field held to the principal directions wherever the curvature is
   * anisotropic, and lay it where it has at most three quarters of the singular points of the field smoothest in
   * the Dupin metric ('try', default: on surfaces without umbilics, such as a cyclide, fewer singular points and
   * more hexagons); 'off': the smoothest field alone.
   */
  principalField?: 'try' | 'off';
  /**
   * Triangulation method: 'auto' (default: the surface's recommended method, `SurfaceSpec.method`;
   * for an uploaded mesh 'prespecified' where trial lays find one system of rows covering it and its lay leaves no part bare, else 'global'; §7's geodesic route for a closed convex one, 'subdivision' for a closed convex polyhedron of fewer vertices than the faces asked for), 'progressive' conjugation (§5.2 Method 1), 'prespecified'
   * conjugation along `field` (Method 2), 'subdivision' (Loop subdivision of a convex control mesh, §7:
   * `surface` names a built-in control or `mesh` is the control), 'lattice' (parameter rows), 'global' (any
   * surface, uploaded or analytic, of any genus and boundary: a 6-fold direction field in the Dupin metric, a
   * lattice along it and the triangle mesh extracted from it; every node of the P-Hex mesh joins three faces,
   * pentagons and heptagons stand at the field's singular points, `triangulation.singularities`; options
   * `anisotropy`, `alignment`, `curvatureSizing`).
   */
  method?: Method;
  /** Direction field of the conjugate methods. Default 'principal'. */
  field?: Field;
  /** §5.3 lower bound b on the step ratio |CM|/|AB| near parabolic curves, in [0, 2]. Default 0.3; 0 turns it off. */
  lowerBound?: number;
  /**
   * Method 'global': the largest ratio of the Dupin metric's two axes the field follows, in [1, 8]. Default 2;
   * 1 gives triangles equilateral in space (an isotropic field), larger values follow the Dupin indicatrix further
   * where it is elongated. Needs `capabilities().globalOptions`.
   */
  anisotropy?: number;
  /**
   * Method 'global': weight of the field's alignment with the principal direction of least |curvature| (where the
   * curvature is anisotropic) against its smoothness, in [0, 10]. Default 1; 0 leaves the field free but along
   * the boundary.
   */
  alignment?: number;
  /**
   * Method 'global': how far the cell follows the curvature, in [0, 1]. Default 0 (panels of one size); 1 shrinks
   * the cells as the square root of the largest |curvature| relative to the surface's median (within a factor 3
   * either way).
   */
  curvatureSizing?: number;
  /**
   * Method 'global': where |curvature| is small the Dupin metric tends to the isotropic one: each principal
   * |curvature| gets this share of the surface's median largest one added before their ratio is taken, in
   * [0.01, 1]. Default 0.25; smaller values follow a near-developable surface's elongated indicatrix further (up
   * to `anisotropy`).
   */
  curvatureFloor?: number;
  /**
   * Method 'global': where the lay does not reach a P-Hex mesh (not converged, faces crossing themselves or nodes
   * far off), or its cuts make nodes of four faces at over 5 % of its faces, it is laid again following the Dupin
   * metric further (anisotropy 2.5, curvature floor 0.05) and the better kept ('on', default). A noisy upload's first
   * lay is laid without the repairs that trade hexagons for cuts there (the fairness, the changes at folded boundary
   * panels, the dislocation glides) and not again this way; where it does not reach a P-Hex mesh, it is laid again
   * with them, as a smooth upload is (this relay and the trials included), and that lay kept where it reaches one.
   * Under 'auto', an upload whose Method 2 rows leave a point of it over a mean panel edge from any panel,
   * cut faces, or reach no P-Hex mesh is tiled by the global method, kept where it reaches one covering the upload
   * more closely or, both within a panel edge, with fewer nodes of four faces from cuts. Then, at up to 5000 faces,
   * where the global lay kept still has nodes of four faces from cuts, it is laid again for 3 % fewer and 3 % more
   * faces (its lattice falls otherwise around the places where it had to cut) and the best kept: reaching a P-Hex
   * mesh, then covering the surface within a mean panel edge, then fewer nodes of four, then more hexagons, its face
   * count within 10 % of the count asked.
   * `result.relay` says what ran. 'off': the first lay stands.
   */
  relay?: 'on' | 'off';
  /**
   * Method 'global': the local solver pulls each interior node towards its neighbours' mean with this weight times
   * the square root of `lambda`, gone with it, in [0, 1]. Default 0.03: the faces' planes follow a smooth mesh
   * instead of folding (fewer faces cut). Not on a noisy upload's first lay (see `relay`); 0 turns it off.
   */
  fairness?: number;
}

/** A run parameter as listed in {@link PARAMETERS}. */
export interface ParameterSpec {
  name: 'faces' | 'cell' | 'tolerance' | 'lambda' | 'mu' | 'maxIterations' | 'duality' | 'solver' | 'folds' | 'surfaceFit' | 'splitBoundary' | 'cutShare' | 'clipBoundary' | 'foldFlips' | 'dislocations' | 'principalField' | 'start' | 'direction' | 'method' | 'field' | 'lowerBound' | 'anisotropy' | 'alignment' | 'curvatureSizing' | 'curvatureFloor' | 'relay' | 'fairness';
  /** 'point': an [x, y, z] array, or null for the default. */
  type: 'integer' | 'number' | 'enum' | 'field' | 'point';
  default: number | string | null;
  /** Range of a number (inclusive). */
  min?: number;
  max?: number;
  /** Accepted values of an enum (for 'field', 'angle:DEG' stands for any angle in degrees). */
  values?: readonly string[];
  /** The {@link Capabilities} entry the parameter needs, if any. */
  requires?: 'methods' | 'fields' | 'lowerBound' | 'globalOptions';
  description: string;
}

/** Type, default, range and meaning of every run parameter besides `surface` and `mesh` (for UIs). */
export const PARAMETERS: readonly ParameterSpec[];

/** The mesh file formats phex reads. */
export const MESH_FORMATS: readonly MeshFormat[];

/** What this build of the core can do beyond analytic surfaces. */
export interface Capabilities {
  /** run() accepts `mesh` (uploaded files). */
  meshInput: boolean;
  /** Formats accepted as `mesh`. */
  meshFormats: MeshFormat[];
  /** Triangulation methods accepted as `method` (empty: the parameter is not supported). */
  methods: Method[];
  /** Direction fields accepted as `field` ('angle:DEG' stands for any angle). */
  fields: string[];
  /** `lowerBound` is accepted. */
  lowerBound: boolean;
  /** The options of method 'global' (`anisotropy`, `alignment`, `curvatureSizing`, `curvatureFloor`, `foldFlips`, `dislocations`, `principalField`, `relay`, `fairness`) are accepted. */
  globalOptions: boolean;
  /** {@link PHex.surfacePreview} is available. */
  surfacePreview: boolean;
  /** {@link PHex.memory} is available (always true). */
  memory: boolean;
}

/** The surface as a triangle mesh with principal curvatures per vertex, for a curvature view. */
export interface SurfacePreview {
  /** Vertex coordinates: length 3 × vertex count. */
  positions: Float64Array;
  /** Vertex indices, three per triangle. */
  triangles: Uint32Array;
  /** Principal curvatures per vertex (1 / model units); Gaussian curvature is k1·k2, mean (k1 + k2) / 2. */
  k1: Float64Array;
  k2: Float64Array;
}

/** The wasm heap: see {@link PHex.memory}. */
export interface MemoryUse {
  /** Size of the wasm heap in bytes (grows, never shrinks). */
  heapBytes: number;
  /** Bytes handed out by malloc and not freed, where the core can tell; else null. */
  usedBytes: number | null;
}

/** One progress report of a run. */
export interface Progress {
  /** The stage: "triangulate", "dualize", "planarize", "clip", "measure" or "done". */
  stage: string;
  /** Progress within the stage, 0 .. 1. */
  fraction: number;
  /** A human-readable line, e.g. "round 2, iteration 5, planarity 3.1e-07". */
  message: string;
}

export interface RunOptions {
  /** Called with each progress report (in browsers, forwarded from the worker). */
  onProgress?: (progress: Progress) => void;
  /**
   * Aborting rejects the run with a PHexError of code 'cancelled'. In a worker the computation is
   * stopped at once; in the calling thread a run that already started completes and is discarded.
   */
  signal?: AbortSignal;
}

/** A parameter of an analytic surface. */
export interface SurfaceParameter {
  name: string;
  /** Value used when the parameter is not given. */
  default: number;
  /** Smallest accepted value. */
  min: number;
  /** Largest accepted value. */
  max: number;
  description: string;
}

/** An analytic surface phex can tile. */
export interface SurfaceSpec {
  /** The name to pass as {@link RunParams.surface}. */
  name: string;
  description: string;
  parameters: SurfaceParameter[];
  /** The triangulation method `method: 'auto'` uses for this surface. */
  method: Exclude<Method, 'auto'>;
  /** The direction field `method: 'auto'` lays a conjugate method along (when `field` is left at 'principal'). */
  field: string;
}

/** How {@link PHex.panels} writes the panels. */
export interface PanelOptions {
  /** 'svg' (default): a cut sheet; 'csv': the panel schedule, one row per face. */
  format?: 'svg' | 'csv';
  /** Space between panels on the sheet, in the mesh's units (default a quarter of the mean edge length). */
  gap?: number;
  /** Width of the sheet in the mesh's units (default about square; never narrower than the widest panel). */
  width?: number;
  /** The mesh's length unit: the sheet then gets its true size in millimetres (default none: viewers fit it). */
  unit?: 'mm' | 'cm' | 'm' | 'in';
  /** Each panel's label at its centre (default true). */
  labels?: boolean;
}

/**
 * Options of {@link PHex.structure} (and of the structure's schedules and OBJ): face distances in the mesh's units.
 * Missing (or null) ones take their defaults; out of range (0, negative where not allowed, not finite, or farther
 * than the offset can take before an edge vanishes) rejects with 'invalid_parameter' naming the option.
 */
export interface StructureOptions {
  /** Face distance of the offset mesh (either side, not 0; > 0 towards the normals). Default: no offset mesh. */
  offset?: number | null;
  /** Height of the beams behind the panels (> 0): the face distance of their back layer. Default a fifth of the mean edge. */
  beamHeight?: number | null;
  /** Width of the beams in the solid model (> 0). Default a quarter of the beam height. */
  beamWidth?: number | null;
  /** Thickness of the panels in the solid model (> 0), towards the normal side. Default a fiftieth of the mean edge. */
  panelThickness?: number | null;
}

/** One option of {@link StructureOptions}: its default (null: derived from the mesh) and meaning, for forms and tooltips. */
export interface StructureOptionSpec {
  name: keyof StructureOptions;
  type: 'number';
  default: null;
  min?: number;
  description: string;
}
export const STRUCTURE_OPTIONS: readonly StructureOptionSpec[];

/**
 * How a node's axis is found (the `kind` codes of {@link StructureNodes}): 0 cone (three panels: the axis of the
 * cone of revolution touching their planes, exact), 1 boundary (two panels: the axis turned within their bisector
 * plane by the boundary rule), 2 corner (one panel), 3 best fit (four or more panels, or three whose planes are
 * parallel to one line: least squares), 4 folded (panels folded onto each other: the mean axis of the nodes around),
 * 5 free (no panel).
 */
export type NodeKindCode = 0 | 1 | 2 | 3 | 4 | 5;

/** The structure's nodes, in the mesh's vertex order. */
export interface StructureNodes {
  /** Each node where its panels' planes meet (moved from the mesh's vertex by about its planarity): 3 × node count. */
  positions: Float64Array;
  /**
   * Each node's axis a, scaled so that n · a = 1 for each of its panels' unit normals n: the offset at face distance
   * d puts the node at position + d a. |a| = 1 / sin(angle between axis and panels). 3 × node count.
   */
  axes: Float64Array;
  /** How each axis was found ({@link NodeKindCode}). */
  kind: Uint8Array;
  /** Nodes of four or more panels (least-squares axes), ascending. */
  bestFit: Uint32Array;
  /** Nodes where panels fold onto each other (no usable axis), ascending. */
  folded: Uint32Array;
  /** Per node, the largest |n · a − 1| over its panels: 0 but at best-fit and folded nodes. */
  residual: Float64Array;
}

/** One planar quad per edge of the mesh, in the beam schedule's order (beam B<k> is index k − 1). */
export interface StructureBeams {
  /** The edge's two nodes (0-based): 2 × beam count. */
  nodes: Uint32Array;
  /** The panels either side (0-based face ids; −1 at the boundary): 2 × beam count. */
  faces: Int32Array;
  /** The quad's corners: node a, node b, then b and a on the back layer (x, y, z each): 12 × beam count. */
  quads: Float64Array;
  /** The quad's plane: unit normal and offset (normal · x = offset): 4 × beam count. */
  planes: Float64Array;
  /** The back corners' distances from the edge, at a and at b: 2 × beam count. */
  heights: Float64Array;
  /** Largest corner distance from the quad's plane over its mean edge: 0 for a planar beam. */
  planarity: Float64Array;
  /** Angle in degrees between the planes through the edge and each end's axis: 0 for a planar beam. */
  twist: Float64Array;
}

/** A solid part for a THREE.BufferGeometry: its positions relative to {@link StructureSolid.origin}. */
export interface SolidPart {
  /** Vertex coordinates in single precision, relative to the origin: 3 × vertex count. */
  positions: Float32Array;
  /** Vertex indices, three per triangle, turning outwards. */
  index: Uint32Array;
  /** For each triangle, the panel (face id) or beam (beam index) it belongs to. */
  element: Uint32Array;
  /** Panels or beams in the part. */
  count: number;
}

/** The structure as solids, ready for three.js: place each object at `origin`. */
export interface StructureSolid {
  /** [x, y, z]: the mesh's box centre where that lies more than ten box diagonals from the origin (site coordinates), else zeros. */
  origin: [number, number, number];
  /** Each panel between its face plane and that plane shifted by panelThickness; sides in the bisector planes. */
  panels: SolidPart;
  /** Each beam's quad thickened by beamWidth across its plane (12 triangles per beam). */
  beams: SolidPart;
  /** Each node's axis from the beams' back layer to the panels' top, as line segments (pairs of points). */
  axes: { positions: Float32Array };
}

/** What the core reports about a structure. */
export interface StructureReport {
  /** Nodes by how their axes were found. */
  nodesByKind: { cone: number; boundary: number; corner: number; 'best-fit': number; folded: number; free: number };
  /** Nodes with panels (the connectors to make). */
  nodeCount: number;
  beamCount: number;
  /** Sum of the beams' lengths. */
  beamLength: number;
  /** The distances used (defaults filled in). */
  beamHeight: number;
  beamWidth: number;
  panelThickness: number;
  offset: number | null;
  /** Face distances within which no offset edge vanishes: [against the normals (< 0), towards them (> 0)]; ±Infinity where none does. */
  offsetRange: [number, number];
  /** Edges of one panel, and those the boundary rule made planar. */
  boundaryBeams: number;
  boundaryBeamsPlanar: number;
  /** Runs of boundary edges, and those solved planar. */
  boundaryRuns: number;
  boundaryRunsPlanar: number;
  /** The largest twist of a boundary beam, in degrees (0 where all are planar). */
  boundaryTwistMaxDeg: number;
  /** The largest turn of a boundary axis from the surface normal, in degrees. */
  boundaryTurnMaxDeg: number;
  beamPlanarityMax: number;
  /** Over beams of two panels between exact nodes: round-off. */
  interiorBeamPlanarityMax: number;
  /** How far nodes moved onto their planes, over the mean edge. */
  nodesMovedOntoPlanesMax: number;
  /** What a designer should know: best-fit and folded nodes by name, the boundary rule's outcome, pinched panels. */
  notes: string[];
}

/** The structure on a P-Hex mesh: {@link PHex.structure}. */
export interface Structure {
  /** The offset at face distance `offset`, in the mesh's vertex and face order (present when `offset` was given). */
  offset?: Mesh;
  nodes: StructureNodes;
  beams: StructureBeams;
  solid: StructureSolid;
  report: StructureReport;
}

/** A loaded phex instance. */
export interface PHex {
  /**
   * Computes a P-Hex mesh. Runs are done one after another in call order. Rejects with a
   * PHexError: 'invalid_parameter' (the message names the parameter), 'cannot_tile', 'cancelled', ...
   * The instance keeps working after any rejection.
   */
  run(params: RunParams, options?: RunOptions): Promise<Result>;
  /** The analytic surfaces and their parameters. */
  surfaces(): Promise<SurfaceSpec[]>;
  /** What this core build supports (mesh input, methods, fields ...); the caller gets its own copy. */
  capabilities(): Capabilities;
  /**
   * The surface of `params` (surface or mesh) as a triangle mesh with principal curvatures. Rejects
   * with code 'unsupported' when `capabilities().surfacePreview` is false. Queued like run().
   */
  surfacePreview(params: RunParams, options?: { signal?: AbortSignal }): Promise<SurfacePreview>;
  /** Memory of the wasm instance (in the worker, if any), measured between runs. */
  memory(): Promise<MemoryUse>;
  /**
   * Lets go of the last uploaded mesh's surface. Runs and previews on the same upload (the same bytes, format
   * and name) reuse it instead of reading the file and estimating its curvature again (a second or more for a
   * million triangles); one upload is kept at a time. Call it when the design is closed to free its memory.
   * Queued like run().
   */
  clearUploadCache(): Promise<void>;
  /**
   * The faces of a polygon mesh (a run's `hex`) laid flat, true to size, for cutting: with format 'svg' (the
   * default) a cut sheet of outlines labelled P1..Pn (face n, seen from its normal side), with 'csv' the panel
   * schedule (corners, area, perimeter, planarity, plane, edge lengths, corner angles, flat outline). Rejects
   * with 'invalid_input' naming the face for a malformed or degenerate mesh, 'invalid_parameter' for bad
   * options. Queued like run().
   */
  panels(mesh: Mesh, options?: PanelOptions): Promise<string>;
  /**
   * The beam schedule of a polygon mesh (a run's `hex`) as CSV, one row per edge: label B<k>, its nodes (1-based
   * vertex ids) and their positions, length, the panels on its left and right (empty at the boundary) and the
   * fold between them in degrees (positive at a ridge seen from the normal side, negative in a valley). With
   * `beamHeight` (and the other structure options), each row gains the structure's beam: its heights at either end,
   * plane (normal, offset), planarity, twist and the quad's four corners. Rejects with 'invalid_input' for a
   * malformed mesh or an edge of more than two faces. Queued like run().
   */
  beams(mesh: Mesh, options?: StructureOptions): Promise<string>;
  /**
   * The structure on a polygon mesh (a run's `hex`): every P-Hex mesh is conical (§1), so its faces can be offset
   * at a constant distance, each node has an axis equidistant from its panels' planes, and the beam spanned by an
   * edge and its two axes is a planar quad. Resolves to the nodes, the beams, the solid model (typed arrays for
   * three.js) and a report; with `offset`, also the offset mesh. Nodes of four or more panels and folded ones get a
   * stated best fit and are named in the report's notes; boundary axes turn for planar boundary beams where that
   * keeps them within 30° of the surface normal. Rejects with 'invalid_parameter' naming the option for a bad
   * distance (the message also names the panel that collapses and the range that can be taken), 'invalid_input'
   * for a malformed mesh. Queued like run(); the instance keeps working after a rejection.
   */
  structure(mesh: Mesh, options?: StructureOptions): Promise<Structure>;
  /**
   * The node schedule as CSV, one row per node (1-based, as in OBJ and the beam schedule): kind, faces, position,
   * unit axis, scale |a|, the panels at it, the angles between the axis and each panel's plane in degrees (equal at
   * a cone node), the axis' angle to the mean normal, the residual. Queued like run().
   */
  nodes(mesh: Mesh): Promise<string>;
  /** The structure's solid model as OBJ text: an object per panel (P<n>) and per beam (B<k>). Queued like run(). */
  structureOBJ(mesh: Mesh, options?: StructureOptions): Promise<string>;
  /** Version of the phex core, e.g. "0.1.0". */
  readonly version: string;
  /** Stops the worker and frees the wasm instance; pending runs reject with code 'cancelled' and later calls fail. */
  dispose(): void;
}

export interface CreateOptions {
  /**
   * Run the core in a module Web Worker, so computations never block the page. Default true where
   * `Worker` exists (browsers); Node always runs in the calling thread.
   */
  worker?: boolean;
}

/**
 * Loads the wasm core (next to this file) and resolves when it is ready. Rejects with code 'io' if it cannot be
 * loaded, and with code 'unsupported' where the engine lacks WebAssembly exception handling (before Chrome and
 * Edge 95, Firefox 100, Safari 15.2, node 17).
 */
export function createPHex(options?: CreateOptions): Promise<PHex>;

/** A polygon mesh split into triangles for rendering. */
export interface TriangulatedFaces {
  /** Vertex coordinates in single precision: length 3 × vertex count (same vertices as the mesh). */
  positions: Float32Array;
  /** Vertex indices, three per triangle. */
  index: Uint32Array;
  /** For each triangle, the face of the mesh it belongs to. */
  faceOfTriangle: Uint32Array;
}

/**
 * Triangulates each face (n corners → n − 2 triangles turning as the face does), for THREE.BufferGeometry: a
 * convex face as a fan from its first corner, a non-convex one (saddle-shaped hexagons, clipped boundary panels)
 * by ear clipping in its plane, so that no triangle covers what lies outside the face.
 */
export function triangulateFaces(mesh: Mesh): TriangulatedFaces;

/** The mesh (or a triangulation) as Wavefront OBJ text with full double precision, in the format of `phex run --out`. */
export function meshToOBJ(mesh: Mesh | Triangulation): string;

/**
 * The mesh (or a triangulation) as ASCII PLY text with full double precision; `faceValues` adds named
 * per-face double properties, each of length face count (e.g. `{planarity: result.metrics.planarity}`).
 */
export function meshToPLY(mesh: Mesh | Triangulation, faceValues?: Record<string, ArrayLike<number>>): string;

/** Area of each face in model units squared (length face count). */
export function faceAreas(mesh: Mesh | Triangulation): Float64Array;
