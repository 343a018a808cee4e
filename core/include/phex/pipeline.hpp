// phex — one call from parameters to a P-Hex mesh: surface → triangulate → dualize → planarize → measure.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "phex/boundary_curve.hpp"
#include "phex/duality.hpp"
#include "phex/global_triangulation.hpp"
#include "phex/metrics.hpp"
#include "phex/planarize.hpp"
#include "phex/progress.hpp"
#include "phex/surfaces.hpp"
#include "phex/triangulation.hpp"

namespace phex {

constexpr int kMaxFaces = 1000000;  // the largest face count phex accepts
// A P-Hex node farther off the surface than this share of the bounding-box diagonal (five times the 0.2 %
// goal) and than the mesh's mean edge is a shortfall (PipelineResult::farNodes) the notes name and the
// command line exits 2 for. The mean edge spares coarse meshes, whose panels bulge that far by their size
// (12 hexagons on a torus).
constexpr double kFarNodeDistance = 0.01;
// The goal for PipelineResult::coverageGap: every point of the surface within one mean panel edge of the P-Hex
// mesh. Beyond it the notes name the place.
constexpr double kCoverageGapGoal = 1.0;
// The global method's second lay (PipelineParams::relay): the metric it follows, and the share of the faces beyond
// which the first lay's cuts (two nodes of four faces per interior face cut, one per boundary panel) call for it.
constexpr double kRelayAnisotropy = 2.5, kRelayFloor = 0.05, kRelayNodesOfFour = 0.05;
// The rounds against folds that align before they merge (PipelineParams::foldAlignRounds; see fold_rounds.cpp).
constexpr int kAlignRounds = 3;
// The rounds against folds run where at most kFoldFlipShare of the faces fold (PipelineParams::foldRoundsShare), and
// where no lay reached a P-Hex mesh, or the lay kept reached one only with nodes of four faces from cuts at over
// kRelayNodesOfFour of its faces, all is laid again with kFoldRescueShare (runPipeline; see pipeline.cpp).
constexpr double kFoldFlipShare = 0.08, kFoldRescueShare = 0.25;
// The global method's trial lays (PipelineParams::relay): where the lay kept still has nodes of four faces from
// cuts, at up to kTrialMostFaces faces, it is laid again for kTrialShares of the faces (its lattice then falls
// otherwise around the few places where the solve had to cut) and the best is kept; at up to kTrialLargeFaces where
// those nodes are more than kTrialLargeShare of the faces (since stop 30: six_s0 at 10000 faces 79 -> 7 nodes of
// four, the car 36 -> 10; the bench's upload at 10k faces, 3 from boundary panels cut, is laid once).
constexpr int kTrialMostFaces = 5000, kTrialLargeFaces = 10000;
constexpr double kTrialLargeShare = 0.0025;
constexpr double kTrialShares[] = {0.97, 1.03};

// How the triangulation is laid (§5, §7).
enum class TriangulationMethod {
  Auto,          // the analytic surface's recommended method (SurfaceSpec::method); uploaded meshes: Prespecified,
                 // or Subdivision's route for a closed convex one (geodesicTriangulation), or Subdivision
                 // itself for a closed convex polyhedron of fewer vertices than the faces asked for (a control mesh)
  Lattice,       // rows of the parameter domain, every other one shifted (analytic surfaces only)
  Progressive,   // Method 1, progressive conjugation (§5.2)
  Prespecified,  // Method 2, pre-specified conjugation along a direction field (§5.2)
  Subdivision,   // Loop subdivision of a convex control mesh (§7): closed convex surfaces, 12 pentagons
  Global         // a 6-fold field in the Dupin metric with singular vertices, its lattice, extracted: any surface
                 // (phex/global_triangulation.hpp)
};
// "auto" | "global" | "lattice" | "progressive" | "prespecified" | "subdivision"; parseTriangulationMethod throws
// Error(InvalidParameter) for other names.
TriangulationMethod parseTriangulationMethod(const std::string& name);
const char* triangulationMethodName(TriangulationMethod m);

// The built-in control meshes of the subdivision method (the `surface` names it accepts).
const std::vector<std::string>& subdivisionControls();

// An uploaded triangle mesh: the file's bytes and format ("obj", "off", "ply", "stl" or "" to sniff).
struct MeshInput {
  std::vector<std::uint8_t> bytes;
  std::string format;
  std::string name;  // for messages, e.g. the file name
};

struct PipelineParams {
  std::string surface = "torus";   // an analytic surface (analyticSurfaces()), or a subdivisionControls() name
  SurfaceParams surfaceParams;     // its parameters; missing ones take their defaults
  std::optional<MeshInput> mesh;   // an uploaded mesh instead of `surface` (for subdivision: the control mesh)
  TriangulationMethod method = TriangulationMethod::Auto;
  std::string field = "principal"; // direction field of the conjugate methods (see parseFieldSpec, resolveField)
  double lowerBound = 0.3;         // §5.3 step-ratio lower bound b, in [0, 2]; 0 disables it
  // Where the conjugate methods start their base curve L0 (a point near the surface; default: the middle of
  // its bounds, projected) and which way L0 runs there (a vector, projected onto the tangent plane: the
  // family of the network closest to it; default: the family of smaller normal curvature).
  std::optional<Vec3> start;
  std::optional<Vec3> direction;
  int faces = 2000;                // wanted number of hexagons, 12 .. kMaxFaces (ignored when cell > 0)
  double cell = 0.0;               // wanted edge length of the triangulation, in model units (0: use faces)
  double tolerance = 1e-9;         // planarity goal, relative to edge length, in (0, 0.1]
  double lambda = 1.0;             // initial closeness weight, in [0, 1e6]
  double mu = 0.0;                 // surface-distance weight, in [0, 1e6]
  // The local solver's fairness (PlanarizeOptions::fairness), in [0, 1]: interior nodes pulled towards their
  // neighbours' mean with fairness * sqrt(λ), gone with λ. On 20 runs of clean surfaces (the bubble, the bumps
  // upload, three analytic surfaces laid globally, 1000-5000 faces) 0.03 left nodes of four faces from cuts
  // 576 -> 145 and hexagons 90.0 -> 92.1 % (METHOD.md, Planarity).
  double fairness = 0.03;
  int maxIterations = 100;         // Gauss-Newton iteration cap, 1 .. 10000
  // Initializer of the optimization: Dupin (§6), tangent (§4.1), or auto: Dupin, and tangent as well where
  // the solve from Dupin stalls or leaves faces crossing themselves (PipelineResult::duality says which won).
  Duality duality = Duality::Auto;
  PlanarizeMethod solver = PlanarizeMethod::LocalGlobal;  // planarity solver (see planarize.hpp)
  bool preventFolds = true;        // the local solver keeps simple faces simple (PlanarizeOptions::preventFolds)
  bool fitSurface = true;          // once planar, shift the face planes towards the surface (PlanarizeOptions::fitSurface)
  // A boundary panel the solve leaves off planar (while every face away from it is planar), or one that
  // crosses itself, is cut in two along its best diagonal and the solve goes on where that can reach the
  // tolerance; PipelineResult::boundaryPanelsSplit counts them. Where a few interior faces (at most 8) are
  // left off planar away from such panels too (only folding would make them planar), those are cut the
  // same way (PipelineResult::interiorFacesSplit); on a surface laid in several systems of rows (its seams
  // and rows along parabolic rings leave more such faces: round bumps) every interior face left off is.
  bool splitBoundaryPanels = true;
  // The largest share of the interior faces (before any cut) that may be cut so that the mesh comes out planar, in
  // [0, 1]: on a surface laid in several systems of rows or by the global method, faces the solve leaves off planar
  // are cut within it, and a solve with folds allowed that cuts every face it folds is kept within it. Each cut makes
  // two nodes of four faces. Where a surface folds more (near-developable or coarse uploads: the noisy shared models
  // fold 11-28 % of their faces), a larger share gives a planar mesh with that many nodes of four instead of a mesh
  // the solve leaves off planar.
  double cutShare = 0.1;
  // Once solved, the boundary panels are clipped to the surface's boundary curve (clipBoundaryPanels): their
  // boundary edges follow the curve, projected onto each panel's plane, and the nodes they share with their
  // neighbours move along the shared edge onto it. PipelineResult::boundaryClip counts them.
  bool clipBoundary = true;
  // The global method's field (GlobalOptions): the Dupin metric's largest anisotropy followed, in [1, 8]; the
  // weight of the principal alignment, in [0, 10]; how far the cell follows the curvature, in [0, 1] (0: uniform);
  // the curvature floor under which the metric tends to the isotropic one, as a share of the surface's median
  // largest |curvature|, in [0.01, 1].
  double anisotropy = 2.0;
  double alignment = 3.0;  // GlobalOptions::alignment
  double curvatureSizing = 0.0;
  double curvatureFloor = 0.25;
  // The global method laid again, following the Dupin metric further (anisotropy kRelayAnisotropy, curvature floor
  // kRelayFloor), where the first lay did not reach a P-Hex mesh (not converged, faces crossing themselves or nodes
  // far off) or its cuts made nodes of four faces at over kRelayNodesOfFour of its faces; the better of the two is
  // kept (PipelineResult::relay). Not on noisy uploads, whose curvature ratios are unreliable (MeshSurface::noise).
  // On a near-developable surface the flatter curvature decides which triangles are valid (Props. 4, 5), and the
  // regularized metric follows too little of it: a shallow elliptic paraboloid (radii 1 and 30) laid globally
  // stalls at 1000 and 5000 faces or cuts 273 faces at 3000, and converges with 3-22 cut laid again (METHOD.md).
  // Then, at up to kTrialMostFaces faces (kTrialLargeFaces where they are over kTrialLargeShare of the faces), where
  // the lay kept still has nodes of four faces from cuts: laid again
  // for kTrialShares of the faces (or the cell scaled so), and the best kept (PipelineResult::Relay::trials).
  bool relay = true;
  // The global method's triangulation: where its dual, solved with folds allowed, has faces crossing themselves
  // (at most 8 % of them: not on a coarse or noisy upload), each such face's vertex merged with its neighbour
  // along the flatter principal direction (or, where that cannot be done, an edge of its star flipped) and the
  // solve run again, three rounds at most: fewer faces cut later (each cut makes two nodes of four faces). On the
  // uploaded bumps at 3000-20000 faces 80-83 % fewer cuts, as many hexagons or more, 2-6 % fewer faces; on the
  // torus and the analytic bumps laid globally 23-88 % fewer cuts, a point or two of hexagons less (METHOD.md).
  bool foldFlips = true;
  // How many of those rounds first move a folded face's neighbour in line along the flatter principal direction
  // before they merge (fold_rounds.cpp, kAlignRounds: 3). Not an option of the command line or the library: the tests
  // of cases chosen when it was 1 keep 1.
  int foldAlignRounds = kAlignRounds;
  // The largest share of the faces folded (in the dual solved with folds allowed) at which those rounds run; more
  // folded, the run cuts them instead (kFoldFlipShare; runPipeline raises it to kFoldRescueShare where no lay reached
  // a P-Hex mesh, or only with many nodes of four from cuts). Not an option of the command line or the library.
  double foldRoundsShare = kFoldFlipShare;
  // The global method's position field with its dislocations cancelled before the extraction
  // (GlobalOptions::cancelDislocations): each lattice dislocation (a vertex of five next to one of seven) joined
  // with one of the opposite sense or moved into a singular point. On the 40 clean runs hexagons at 3000 faces and
  // more 95.65 -> 97.3 %, the generated genus 0-3 94.7 -> 96.9 % (METHOD.md).
  bool cancelDislocations = true;
  // The global method's field also solved held to the principal directions wherever the curvature is anisotropic,
  // and laid where that has at most three quarters of the singular points (GlobalOptions::principalTrial): the
  // cyclide at 1000-5000 faces 85.5-91.5 -> 91.3-95.2 % hexagons; surfaces with umbilics are not tried.
  bool principalTrial = true;
  // A noisy upload (MeshSurface::noise over kNoisyMesh: a scan, a coarse mesh whose facets turn sharply) is first
  // solved without the solver's fairness, the rounds' changes at folded boundary panels, the dislocation glides and
  // the lay again above: on such meshes they trade hexagons for cuts. Where that first lay does not reach a P-Hex
  // mesh and `relay` is on, runPipeline lays it again with them (this set), as a smooth upload is laid, and keeps
  // the one that reached it (PipelineResult::Relay::noisyRepairs). Set, they apply from the first lay. On the five
  // noisy shared models at 1000-10000 faces, 0 -> 15 of 20 runs reach a P-Hex mesh (METHOD.md).
  bool noisyRepairs = false;
  // Why auto chose the global method for an upload (PipelineResult::globalBecause), on the pipeline's own re-lays of
  // such a run (the relay, the trial lays, the noisy repairs' lay): they lay globally at once, with this in their
  // notes, instead of choosing again (the intersection shell at 10k faces: Method 2's trial lays took 2.5 s of each
  // 3.8 s lay). Empty: the method is chosen as `method` says.
  std::string globalBecause;
};

// The global method's options of `params`, at `cell` (0: calibrated to params.faces), for `surface` where given
// (its dislocations glided unless it is a noisy upload laid without PipelineParams::noisyRepairs).
GlobalOptions globalOptions(const PipelineParams& params, double cell, const Surface* surface = nullptr);

// "dupin" / "tangent" / "auto" <-> Duality; parseDuality throws Error(InvalidParameter) for other names.
Duality parseDuality(const std::string& name);
const char* dualityName(Duality d);

struct StageTiming {
  std::string stage;
  double milliseconds = 0.0;
};

struct PipelineResult {
  TriangulationMethod method;  // the triangulation method used (Auto resolved)
  std::string field;           // the direction field of a conjugate method (Auto resolved), else empty
  std::string globalBecause;   // an upload under auto tiled globally: why (as the notes say), else empty
  SurfacePtr surface;          // the surface tiled (analytic, uploaded mesh, or subdivision limit surface)
  Triangulation triangulation;
  TriangulationCheck check;    // Propositions 4/5 on every star, valences, edge lengths
  PolyMesh initial;            // the dual mesh before optimization (H0)
  PolyMesh hex;                // the P-Hex mesh
  DualMesh dual;               // bookkeeping of the dual (which vertex / triangle each element comes from)
  // The duality `initial` comes from (never Auto): under Duality::Auto the tangent one where the solve from
  // the Dupin dual stalled or left faces crossing themselves and the tangent dual did better.
  Duality duality = Duality::Dupin;
  MeshMetrics metrics;         // of `hex`
  int farNodes = 0;            // nodes of `hex` off the surface by over kFarNodeDistance and a mean edge
  // The largest distance of the surface's points (an upload's vertices, at most about 10000; some 2000 samples of an
  // analytic surface) to `hex`, in its mean edges: over kCoverageGapGoal where a part of the surface has no panel
  // over it (a hole), which the notes then name with the place.
  double coverageGap = 0.0;
  // How far the boundary nodes of `hex` lie from the surface's boundary curve across the surface (leaving out
  // their height over it), in mean edges: a clean edge has them on it, so the boundary panels end at the curve.
  BoundaryOffset boundaryOffset;
  BoundaryClip boundaryClip;  // the boundary panels clipped to the curve (PipelineParams::clipBoundary)
  double interiorHexagonFraction = 0.0;  // hexagons among the faces not on the boundary (dual.boundaryFace)
  PlanarizeReport solve;
  int boundaryPanelsSplit = 0;  // boundary panels cut in two to become planar (PipelineParams::splitBoundaryPanels)
  int interiorFacesSplit = 0;   // interior faces cut in two the same way (only folding would make them planar)
  // The solve that was kept ran without the fold guard (PipelineParams::preventFolds): the guarded one stalled
  // short of the tolerance, and without it the mesh converged with no face crossing itself — the way to
  // planarity passed through steps the guard refused (Method 1 on cyclide patches past the parabolic circles);
  // or, on the global method's triangulation, the guarded one converged only by cutting more interior faces than
  // fold without the guard, or a quarter of the boundary panels, and the unguarded one (its far nodes put back on
  // the surface and solved again, where that brought them nearer) made fewer nodes of four faces by its cuts.
  bool foldsAllowed = false;
  // The solver the kept result comes from (the one asked for).
  PlanarizeMethod solverUsed = PlanarizeMethod::LocalGlobal;
  // The uploaded mesh's MeshSurface came from the previous run on the same upload (clearUploadCache).
  bool surfaceReused = false;
  // An upload far from the origin (more than 10 times its size: site coordinates) is computed about the centre
  // of its box, `origin`, where its coordinates keep their digits; the meshes here and the notes are in the
  // file's coordinates, `surface` in the local frame (its points plus origin are the file's). Zero otherwise.
  Vec3 origin = Vec3::Zero();
  // A second lay (PipelineParams::relay, on by default): the global method's again, following the Dupin metric
  // further, where its first lay fell short; or (`globally`) an upload under auto that Method 2's rows left partly
  // bare (coverage gap over the goal), brought to a P-Hex mesh only by cuts, or did not bring to one, tiled by the
  // global method. Whether it ran, whether its result is the one here (`kept`), the metric it followed, and how the
  // first lay ended (a P-Hex mesh or not, the nodes of four faces its cuts made, its coverage gap). The stages'
  // timings are both lays'.
  struct Relay {
    bool tried = false, kept = false;
    bool globally = false;
    double anisotropy = 0, curvatureFloor = 0;
    bool firstReached = false;
    int firstNodesOfFour = 0;
    double firstCoverageGap = 0;  // (globally) the rows' coverage gap, in mean panel edges
    // Trial lays for other face counts (kTrialShares) where the lay kept had nodes of four from cuts: how many
    // ran, the nodes of four the lay before them left, and the share of the faces (or the cell's scale as for
    // that share) of the one kept (0: none of them, the lay before stands).
    int trials = 0;
    int trialNodesOfFour = 0;
    double trialShare = 0;
    // A noisy upload's first lay fell short and it was laid again with PipelineParams::noisyRepairs; whether that
    // lay (and what followed it) was kept.
    bool noisyRepairs = false, noisyRepairsKept = false;
  } relay;
  std::vector<StageTiming> timings;
  double totalMilliseconds = 0.0;
};

// The surface of `params` as a triangle mesh with the principal curvatures at its vertices, for display:
// an analytic surface sampled on its parameter lattice (exact curvature), an uploaded mesh as it is
// (estimated curvature), a subdivision control's limit surface.
struct SurfacePreview {
  TriMesh mesh;
  std::vector<double> k1, k2;  // #V
};
SurfacePreview surfacePreview(const PipelineParams& params);

// The method `params` asks for, with Auto resolved.
TriangulationMethod resolveMethod(const PipelineParams& params);
// The direction field of the conjugate methods: under Auto, an analytic surface's recommended field
// (SurfaceSpec::field) when `params.field` is the default "principal"; otherwise `params.field`.
std::string resolveField(const PipelineParams& params);

// An uploaded mesh's MeshSurface (its estimated curvature and closest-point structures: 1.3 s natively for a
// million triangles, most of a run on a big upload) is kept after the run, and the next run or surfacePreview
// on the same upload (the same bytes, format and name) reuses it: editing the parameters of one design pays for
// it once. One upload is kept at a time, released before another is read. This lets it go (its memory: some 40 MB
// for a 120k-triangle upload), as an app does when the design is closed. Safe to call from any thread.
void clearUploadCache();

// Far nodes (kFarNodeDistance): the share of the diagonal beyond which a node of `hex` is one, the larger of
// kFarNodeDistance and the mesh's mean edge over `diagonal` (the surface's bounding-box diagonal); and how many
// of the nodes' `distance`s (shares of the diagonal, as MeshMetrics::surfaceDistance) exceed `farOff`, the
// farthest node's index in `farthest` (0 for none).
double farNodeDistance(const PolyMesh& hex, double diagonal);
int countFarNodes(const std::vector<double>& distance, double farOff, int* farthest = nullptr);

// Throws Error(InvalidParameter) naming the first parameter that is wrong.
void validate(const PipelineParams& params);

// The first stage alone: the surface of `params` and its triangulation, checked.
struct TriangulationStage {
  TriangulationMethod method;  // the method used (Auto resolved)
  std::string field;           // the field a conjugate method laid along (Auto resolved), else empty
  std::string globalBecause;   // PipelineResult::globalBecause
  SurfacePtr surface;           // in the local frame: see PipelineResult::origin
  bool surfaceReused = false;  // PipelineResult::surfaceReused
  Vec3 origin = Vec3::Zero();  // PipelineResult::origin (the triangulation is in the file's coordinates)
  Triangulation triangulation;
  TriangulationCheck check;
};
TriangulationStage triangulate(const PipelineParams& params, const ProgressFn& progress = {},
                               const CancelFlag* cancel = nullptr);

// `triangulate` lays again (at most twice) where a lay misses the faces asked for by more than 10 %; the
// third lay's cell follows the exponent e of vertices ~ cell^-e that the first two measured. This returns
// that exponent (clamped to [0.5, 4]), or nullopt where a third lay is a gamble: the two counts hardly
// follow the cell (e below 1, where a covering gives 2: the lays covered the surface in different ways, and
// the secant reaches far beyond both) and the closer lay misses by at most 15 % already (`closestMiss`, a
// ratio >= 1).
std::optional<double> thirdLayExponent(double cell0, double count0, double cell1, double count1, double closestMiss);
// The cell of a lay again after one at `cell` gave `count` vertices for `faces` asked: scaled by
// (count / faces)^(1 / exponent), and kept within a factor 2 of the area estimate's cell `estimateCell`.
double relayCell(double cell, double count, int faces, double exponent, double estimateCell);

PipelineResult runPipeline(const PipelineParams& params, const ProgressFn& progress = {},
                           const CancelFlag* cancel = nullptr);

}  // namespace phex
