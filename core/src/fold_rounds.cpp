// phex — the global method's rounds against folds: where the Dupin dual, solved with folds allowed, has faces
// crossing themselves, vertices aligned, merged or dropped and edges flipped, round after round (fold_rounds.hpp).
#include "fold_rounds.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "phex/dupin.hpp"
#include "phex/metrics.hpp"
#include "phex/parallel.hpp"

namespace phex::detail {
namespace {

// Rounds of changes against the faces a solve could make planar only by folding (flipFoldsAway); they stop earlier
// where a round leaves no fold or gains too little (kFoldGain). With the merges choosing among the neighbours about
// as well along (kMergeAlongSlack), more rounds pay: on the 40-run sweep 3, 4, 5, 6 and 8 rounds cut 251, 179,
// 147, 122 and 114 interior faces (nodes of four 542, 405, 348, 297, 284; hexagons 93.51, 93.57, 93.60, 93.62,
// 93.61 %), the 48 perturbed runs 637 -> 475 at 5 (91.70 -> 91.78 %); the 20k-triangle bumps upload at 10k faces
// 19, 9 and 8 in 1.36, 1.50 and 1.62 s (3, 5, 6). (Before that choice, 3, 4 and 5 rounds cut 301, 280 and 279.)
// Once the rounds after the first solved only around their changes (solveAround), each costs less and leaves fewer
// folds behind: 5, 7 and 9 rounds cut 89, 66 and 66 faces on the 40-run sweep (nodes of four 220, 176, 176), 189,
// 155 and 155 on the 48 perturbed runs; kept while the folds drop by 3 % (kFoldGain) instead of a tenth, 7 and 9
// rounds cut 54 and 54 (nodes of four 153), the perturbed runs 101 and 101 (259), hexagons 93.67 and 92.10 % (93.65
// and 92.08 % at 5 rounds), for 10-15 % more time over the sweeps. The uploaded bumps at 100k faces: folds 2080,
// 998, 655, 616 (less than a tenth fewer: round 2 kept), then 452, 329, 248, 181, 130, ... 71 at 12 rounds; cut
// 695 faces at 3 rounds, 184 at 7 and 73 at 12 (95.7, 96.4, 96.6 % hexagons; 15, 25, 27 s). (Repairing only the
// stars within two rings of a round's changes saved little, 26.4 against 28.2 s at 100k, and cut more: 69 and 133
// faces on the two sweeps.)
// (Stop 19: with the first round's alignments below, 11 rounds: the 48 perturbed runs 96 -> 87 faces cut against 7,
// the bumps upload at 100k 202 -> 97; at 10k the rounds end before either.)
constexpr int kFoldRounds = 11;
constexpr double kFoldGain = 0.97;  // a round is kept where it leaves at most this share of the folds before
// A round that gains too little ends the rounds, but for once (kFoldPatience): where interior folds are left, the next
// round goes on from it, its interior folds changed in turn, and the best round is kept. A round's changes can
// unfold most faces and fold a few new ones next to them, which the next round mends: the generated genus 1 at
// 10000 faces went 92, 37, 22, 16, 6 folds, then 9 (the rounds stopped: 6 faces cut, 12 nodes of four), and goes on
// to 2 (4 nodes of four; 2 with a patience of two). On the 40 clean runs with defaults nodes of four faces 21 -> 1,
// interior faces cut 10 -> 0 (the torus at 2000 and 5000 faces, the cyclide at 5000, the paraboloid 1/30 at 2000),
// hexagons at 3000 faces and more 94.82 -> 94.85 %; laid once 67 -> 36; the generated genus 0-3 25 -> 6. Not where
// the interior had no fold left (the helicoid's rounds, going on from a round that folded one face, flipped its
// asymptotic boundary's fans further: 54 -> 25 nodes of four at 2000 faces, but its boundary nodes 0.89 -> 1.42 mean
// edges off the curve, past the clean-edge goal of one, and hexagons 93.0 -> 89.9 %). A patience of two: the same
// 40 runs, the genus runs a tenth of a point fewer hexagons.
constexpr int kFoldPatience = 1;
// The first round aligns before it merges: a folded face's vertex's neighbour nearest the flatter principal direction
// moves onto the line through the vertex along it (in its tangent plane, then onto the surface), where that moves it
// by at most kAlignMost of their edge, turns no triangle of its star over, and it lies off that line by more than
// kAligned of the edge (else it folds though aligned: merged). No valence changes, where a merge leaves a vertex of
// eight and two of five: on the 40 clean runs hexagons at 3000 faces and more 94.72 -> 94.90 %, faces cut 64 -> 60,
// nodes of four 172 -> 159; the 48 perturbed runs 93.45 -> 93.87 %, 81 -> 87, 226 -> 228; the bumps upload at 10k
// 93.97 -> 94.71 % with no face cut (1 before), at 100k 96.40 -> 96.55 %, 203 -> 97 cut, 14.1 -> 12.9 s. Aligning in
// every round (merging only what an alignment left folded) gave 94.98 % but cut 114 and 247 faces; in the first two,
// 83 and 121; only moves of at most 0.15 of the edge, 100 and 142; 0.5, 61 and 88; merged only where within 2 % of
// the line, 63 and 185. Since the metric's bound is 2 (stop 28) the rounds align in the first three: on the 40 clean
// and 12 genus runs (`sweep.sh`) hexagons at 3000 faces and more 97.75 -> 97.95 % and 97.58 -> 97.67 %, no face cut
// either way, runs under 95 % 3 -> 1 (the genus 3 at 5000 faces 94.98 %); the 10 noisy runs 85.15 -> 86.88 %, 102 ->
// 110 cut; the six shared models at 1000-10000 faces 87.24 -> 87.61 % (at 3000 and more 88.27 -> 89.17 %), nodes of
// four 364 -> 362; the bench's upload at 100k faces 95 + 14 -> 77 + 11 cut, the generated genus 2 at 100k 302 -> 183.
// In the first two rounds: 97.92 / 97.89 % with 1 + 3 cut; in every round: 97.88 / 97.88 % with 4 + 3 cut.
// (kAlignRounds is in pipeline.hpp, the default of PipelineParams::foldAlignRounds.)
constexpr double kAlignMost = 0.3, kAligned = 0.05;
// Not where more faces than kFoldFlipShare fold (pipeline.hpp; PipelineParams::foldRoundsShare): a coarse or noisy
// upload (the shared models: a fifth to a third), whose flips took its hexagons from 94 % to 54 % (the car at 3000
// faces), and whose collapses (below) 92 to 61 %. Where nothing else reaches a P-Hex mesh, runPipeline lays again
// with kFoldRescueShare.
// Collapses remove a vertex of the triangulation (a face of the P-Hex mesh) each: at most this share of the
// vertices, and where a face count was asked for, not below kCollapseFloor of it (the goal is within 10 %, and
// the global method's own count misses by up to 5 %). On the 40-run sweep (five rounds) a share of 3 % cut 295 faces, 5 %
// 236, any number 233 (and the count then fell 7.4 % below the one asked).
constexpr double kCollapseShare = 0.05, kCollapseFloor = 0.93;
// The merged vertex's neighbours at most (its face an octagon): with nine the torus laid globally at 3000 faces
// ended with a face crossing itself.
constexpr std::size_t kMergedMost = 8;
// Of the neighbours within this (cosine) of the one best along the flatter direction — both ways along a row —
// the merge takes the one that leaves the fewest irregular vertices. Against always the best along: the 40-run
// sweep cut 274 -> 251 interior faces, nodes of four faces or more 585 -> 542, hexagons 93.29 -> 93.51 % (>= 3000
// faces 94.38 -> 94.49 %); the 48 perturbed runs 701 -> 637 cut, 1391 -> 1275 nodes of four, 91.41 -> 91.70 %;
// the uploaded bumps at 10k faces 31 -> 19 cut, 93.35 -> 93.75 %. A slack of 0.05 gave the same, 0.2 and 0.3
// cut 288 and 293 faces.
constexpr double kMergeAlongSlack = 0.1;
// Boundary panels folded too (stop 22): the solve with folds allowed folds the fan of a boundary vertex (a middle
// triangle's point past the vertex), and each such panel was cut after the solve, a node of four faces. Their
// vertices are neither merged nor aligned (the boundary stays); the flip applies to them, down to a fan of
// kBoundaryFlipFewest triangles (interior vertices: four), and where no dual edge of the panel runs against its
// triangles' centroids (the fold is the chain of triangle points passing the vertex, not a dual edge turned back) the
// one that runs least along them is taken. A round is kept where the interior folds drop as before, or the folded
// panels drop with no more interior folds. On the 40 clean runs laid once (`--relay off`): nodes of four faces 122 ->
// 78, faces cut 39 -> 34, hexagons at 3000 faces and more 95.08 -> 95.07 %; with the trial lays (the default) 47 ->
// 22 nodes of four, hexagons 94.99 -> 94.82 % (fewer runs take trial lays, whose choice among three lays had raised
// them). With fans of three at least: 84 and 27. Judging the rounds on all folds alike: 25 nodes of four (fans of
// three) but 94.83 %, with the bumps at 5000 faces (no boundary fold) changed too; so judged, flipping only at fans
// of four triangles or more left 40 (the fans that fold are mostly of three), and choosing among the fan's edges by
// the valences the flip leaves 26.
// Not on noisy uploads: a saddle with heights jittered by 12 % of an edge at 1500 faces went 91.5 -> 89.5 % hexagons,
// 5 -> 12 interior faces cut (28 -> 26 boundary panels).
constexpr int kBoundaryFlipFewest = 2;
// A fan of two flipped to one leaves its vertex one triangle with its two boundary neighbours: not where that is a
// sliver, under kEarHeight of its longest edge high. Without that rule (fans of two flipped wherever the flip
// allows) the 40 clean runs laid once kept 74 nodes of four instead of 84, but the helicoid at 2000 faces then
// left a boundary node 1.05 mean edges off its curve (0.89 with fans of three only; 57 instead of 68 boundary
// panels cut along its asymptotic edges). The flips that pay make thin triangles: at 0.3 or 0.1 of the edge none
// passes (84 nodes of four, as with three); at 0.03, 78, and the helicoid the same mesh as with three.
constexpr double kEarHeight = 0.03;
// A folded fan of two whose flip would leave that sliver: where folded panels are left when the rounds are done (the
// last gained too little, or kFoldRounds ran), one round more drops those fans' vertices alone, from the triangulation
// kept. Such a vertex lies nearly on the chord between its two boundary neighbours (the sliver's height), so it is
// merged into the nearer of them, which stays on the boundary where it is, and its two triangles become one. Not
// where the boundary there runs along an asymptotic direction (normal curvature along the chord under
// kAsymptoticBoundary of the largest: a helicoid's helices and end rulings, whose panels fold all along them and
// whose boundary would be thinned out), nor where one of its two boundary edges is over kDropEven times the other
// (a boundary edge left long by a drop nearby). The round is kept where it gains as any round does (panels fewer,
// interior folds no more) or leaves fewer nodes of four in all (fewerNodes: its repairs may leave an interior fold
// more). On the 40 clean runs laid once: nodes of four faces 78 -> 67, boundary panels cut 17 -> 9; with the trial
// lays (the default) 22 -> 21 and 4 -> 3; no run more; the bubble at 10000 faces 3 -> 0 (its boundary nodes 0.12 ->
// 0.00 mean edges off the curve), at 2000 1 -> 0; the bench's upload at 100k faces 91 + 21 -> 92 + 10 faces cut
// (11 vertices dropped, one interior fold more: kept by fewerNodes), at 10k the same mesh. Dropped in every round
// instead, as flips are (no round of their own), the runs laid once went 78 -> 71 but the bubble at 1000 faces 2 ->
// 4 and the rounds' course changed elsewhere (the paraboloid 1/30 at 1000 faces with defaults 0 -> 2); at 1000 faces
// the drop round does not gain and is not kept. Run only where the rounds left no interior fold, 75 laid once.
constexpr double kAsymptoticBoundary = 0.3, kDropEven = 1.5;

// A round against folds changes the triangulation here and there (its collapses, flips and the repairs around
// them); the rest of its dual is the dual solved the round before, bit for bit. So the rounds after the first
// solve only the faces within kResolveRings faces of the dual's new points, their rim held where the solve before
// left it, and the rest keeps that solve's points: where that is more than kResolveShare of the points, all of
// it is solved again.
constexpr int kResolveRings = 2;
constexpr double kResolveShare = 0.5;
// The stars a round's repair mends: those within this many edges of a vertex its changes touched (the rest were
// mended, or resisted, the round before; mending them all again each round cost 0.3 s a round at 100k faces). Over
// the 40 + 48 runs of the sweeps the same faces cut within a few (149 -> 145) and the same hexagons.
constexpr int kRepairRings = 2;

// The Dupin dual `hex` of a triangulation, solved (folds allowed) as above from `before`, the dual of the
// triangulation the round before, and `solved`, that dual as solved then; nullopt where the region is most of the
// mesh (`hex` is then as it came).
std::optional<PlanarizeReport> solveAround(PolyMesh& hex, const PolyMesh& before, const PolyMesh& solved,
                                           const PlanarizeOptions& po, const CancelFlag* cancel) {
  const int nv = static_cast<int>(hex.V.rows()), nf = hex.faceCount();
  if (before.V.rows() != solved.V.rows()) return std::nullopt;
  const PointIndex old(before.V);
  std::vector<char> region(static_cast<std::size_t>(nv), 0);
  const Points dupin = hex.V;
  Points start = hex.V;  // the old solve's points where the Dupin points are the old ones
  parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const int j = old.find(hex.V(i, 0), hex.V(i, 1), hex.V(i, 2));
      if (j < 0) region[i] = 1;
      else start.row(i) = solved.V.row(j);
    }
  });
  auto touches = [&](int f) {  // a face with a point of the region
    const int* ids = hex.face(f);
    return std::any_of(ids, ids + hex.faceSize(f), [&](int v) { return region[v] != 0; });
  };
  for (int ring = 0; ring < kResolveRings; ++ring) {
    std::vector<char> grown = region;
    for (int f = 0; f < nf; ++f)
      if (touches(f))
        for (int i = 0; i < hex.faceSize(f); ++i) grown[hex.face(f)[i]] = 1;
    region.swap(grown);
  }
  const auto free = std::count(region.begin(), region.end(), char(1));
  if (free > kResolveShare * nv) return std::nullopt;
  hex.V = std::move(start);
  PlanarizeReport report;
  if (free > 0) {
    // The faces at a free point, over the free points and their rim (held).
    PolyMesh part;
    std::vector<int> id(static_cast<std::size_t>(nv), -1), of;
    std::vector<char> fixed;
    for (int f = 0; f < nf; ++f) {
      if (!touches(f)) continue;
      const int n = hex.faceSize(f);
      const int* ids = hex.face(f);
      std::vector<int> face(n);
      for (int i = 0; i < n; ++i) {
        if (id[ids[i]] < 0) {
          id[ids[i]] = static_cast<int>(of.size());
          of.push_back(ids[i]);
          fixed.push_back(!region[ids[i]]);
        }
        face[i] = id[ids[i]];
      }
      part.addFace(face);
    }
    part.V.resize(static_cast<Eigen::Index>(of.size()), 3);
    for (std::size_t k = 0; k < of.size(); ++k) part.V.row(static_cast<Eigen::Index>(k)) = hex.V.row(of[k]);
    PlanarizeOptions o = po;
    o.fixedVertices = &fixed;
    report = planarize(part, o, {}, cancel);
    for (std::size_t k = 0; k < of.size(); ++k)
      if (!fixed[k]) hex.V.row(of[k]) = part.V.row(static_cast<Eigen::Index>(k));
  }
  report.planarityMax = maxPlanarity(hex);
  report.converged = report.planarityMax <= po.tolerance;
  // From the Dupin points, as a solve of all of it measures it.
  const double h = hex.meanEdgeLength();
  report.displacementMax = h > 0 && nv > 0 ? (hex.V - dupin).rowwise().norm().maxCoeff() / h : 0.0;
  return report;
}

}  // namespace

FoldFlips flipFoldsAway(Triangulation& t, const Surface& surface, const PipelineParams& params, const ProgressFn& progress,
                        const CancelFlag* cancel, std::optional<DualMesh>& keptDual, std::optional<SolvedDual>& keptSolve) {
  PlanarizeOptions po = planarizeOptions(params, TriangulationMethod::Global, surface);
  po.method = PlanarizeMethod::LocalGlobal;  // folds allowed, no fit: only which faces fold is asked
  po.preventFolds = false;
  po.fitSurface = false;
  Triangulation best = t;
  std::size_t bestFolds = std::numeric_limits<std::size_t>::max(), bestPanels = bestFolds;
  FoldFlips done, kept;  // the changes so far, and those of the round kept
  // Collapses move a vertex; on a triangulation laid in the parameter domain its parameters would go stale.
  const double vertices = static_cast<double>(t.mesh.V.rows());
  const double floor = params.cell > 0 ? 0.0 : kCollapseFloor * params.faces;
  const int budget = t.uv.empty() ? static_cast<int>(std::max(0.0, std::min(kCollapseShare * vertices, vertices - floor))) : 0;
  GeometryCache geometry;  // the vertices' closest points, from one look-up to the next (most vertices stay)
  const bool panelsToo = smoothRepairs(params, surface);  // folded boundary panels as well (kBoundaryFlipFewest)
  bool dropping = false;       // the last round: boundary vertices dropped alone (kDropEven)
  std::vector<int> keptPanels;  // the folded panels of the round kept, by face of keptDual
  // A round not kept that the next goes on from (kFoldPatience), else (fromKept) the round kept.
  std::optional<DualMesh> lastDual;
  std::optional<SolvedDual> lastSolve;
  bool fromKept = true;
  int worse = 0;  // rounds not kept since the last kept
  for (int round = 0;; ++round) {
    checkCancel(cancel);
    if (progress)
      progress({"triangulate", 0.9 + 0.015 * round, "edge collapses and flips against folds, solve " + std::to_string(round + 1)});
    DualMesh dual = dupinDual(t, surface, true, &geometry);
    PolyMesh hex = dual.mesh;
    std::optional<PlanarizeReport> around;
    if (round > 0)
      around = solveAround(hex, (fromKept ? *keptDual : *lastDual).mesh, (fromKept ? *keptSolve : *lastSolve).hex, po, cancel);
    if (around && !around->converged) hex = dual.mesh, around.reset();
    PlanarizeReport solved = around ? std::move(*around) : planarize(hex, po, {}, cancel);
    const std::vector<char> crosses = selfIntersectingFaces(hex);
    std::vector<int> folded, foldedPanels;  // interior faces and boundary panels crossing themselves
    for (int f = 0; f < hex.faceCount(); ++f)
      if (crosses[f] && hex.faceSize(f) >= 4 && (!dual.boundaryFace[f] || panelsToo))
        (dual.boundaryFace[f] ? foldedPanels : folded).push_back(f);
    if (round == 0 && folded.size() > params.foldRoundsShare * double(dual.mesh.faceCount())) {
      keptDual = std::move(dual);  // of `best`, which is `t` as it came
      keptSolve = SolvedDual{std::move(hex), std::move(solved)};
      kept.folded = static_cast<int>(folded.size());
      break;
    }
    // Gained too little (the round before stands): the interior folds dropped by less than kFoldGain, and the
    // folded panels did not drop with no more interior folds.
    const bool fewerFolds = bestFolds > 0 && folded.size() <= kFoldGain * double(bestFolds);
    const bool fewerPanels = folded.size() <= bestFolds && foldedPanels.size() < bestPanels;
    // The round of drops: fewer nodes of four in all (an interior fold cut makes two, a panel cut one); its repairs
    // around the drops can leave an interior fold more.
    const bool fewerNodes = dropping && 2 * folded.size() + foldedPanels.size() < 2 * bestFolds + bestPanels;
    const bool gained = fewerFolds || fewerPanels || fewerNodes;
    // Not kept, but the rounds go on from it (kFoldPatience): where interior folds were left to mend.
    const bool goOn = !gained && !dropping && worse < kFoldPatience && round < kFoldRounds && bestFolds > 0 && !folded.empty();
    if (gained) {
      best = t, bestFolds = folded.size(), bestPanels = foldedPanels.size(), kept = done;
      kept.folded = static_cast<int>(folded.size());
      keptDual = std::move(dual);
      keptSolve = SolvedDual{hex, std::move(solved)};
      keptPanels = foldedPanels;
      fromKept = true, worse = 0;
      if (folded.empty() && foldedPanels.empty()) break;
    }
    if (goOn) {  // its interior folds alone changed in turn
      ++worse;
      lastDual = std::move(dual);
      lastSolve = SolvedDual{hex, std::move(solved)};
      fromKept = false;
    } else if (!gained || round >= kFoldRounds || dropping) {
      // The rounds done (the last gained too little, or kFoldRounds ran): folded panels left get one round of drops
      // alone, from the triangulation kept, itself kept where it gains as a round does.
      if (dropping || keptPanels.empty() || !panelsToo) break;
      dropping = true;
      t = best, done = kept;
      folded = keptPanels;
      fromKept = true;
    } else {
      folded.insert(folded.end(), foldedPanels.begin(), foldedPanels.end());
    }
    const DualMesh& d = fromKept ? *keptDual : *lastDual;
    TriMesh& T = t.mesh;
    const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
    auto key = [nv](int a, int b) { return std::uint64_t(std::min(a, b)) * std::uint64_t(nv) + std::uint64_t(std::max(a, b)); };
    // Each vertex's triangles in order (`incident`, also its star), its neighbours sorted (`ring`), flattened; an
    // interior vertex is one whose fan closes: as many neighbours as triangles (the triangulation is a manifold
    // here: the dual was just built from its fans). (Lists of lists and vertexRings' fans took 0.09 s a round at
    // 100k faces.)
    struct Span {
      const int *first, *last;
      const int* begin() const { return first; }
      const int* end() const { return last; }
      std::size_t size() const { return static_cast<std::size_t>(last - first); }
      bool empty() const { return first == last; }
      int operator[](std::size_t i) const { return first[i]; }
    };
    std::vector<int> triangleStart(nv + 1, 0), triangleList(3 * static_cast<std::size_t>(nf));
    std::vector<int> neighbourStart(nv + 1, 0), neighbourList(6 * static_cast<std::size_t>(nf));
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) ++triangleStart[T.F(f, k) + 1];
    for (int v = 0; v < nv; ++v) triangleStart[v + 1] += triangleStart[v];
    {
      std::vector<int> fill(triangleStart.begin(), triangleStart.end() - 1), fillNeighbours(nv);
      for (int f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) triangleList[fill[T.F(f, k)]++] = f;
      for (int v = 0; v < nv; ++v) fillNeighbours[v] = 2 * triangleStart[v];
      for (int f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) {
          const int a = T.F(f, k), b = T.F(f, (k + 1) % 3);
          neighbourList[fillNeighbours[a]++] = b, neighbourList[fillNeighbours[b]++] = a;
        }
      for (int v = 0, at = 0; v < nv; ++v) {  // each vertex's 2 x triangles entries sorted, unique, compacted
        const auto b = neighbourList.begin() + 2 * triangleStart[v], e = neighbourList.begin() + 2 * triangleStart[v + 1];
        std::sort(b, e);
        const auto u = std::unique(b, e);
        neighbourStart[v] = at;
        at = static_cast<int>(std::copy(b, u, neighbourList.begin() + at) - neighbourList.begin());
        neighbourStart[v + 1] = at;
      }
    }
    std::vector<int> triangles(nv);
    for (int v = 0; v < nv; ++v) triangles[v] = triangleStart[v + 1] - triangleStart[v];
    auto incident = [&](int v) { return Span{triangleList.data() + triangleStart[v], triangleList.data() + triangleStart[v + 1]}; };
    auto star = incident;
    auto ringOf = [&](int v) { return Span{neighbourList.data() + neighbourStart[v], neighbourList.data() + neighbourStart[v + 1]}; };
    // The triangles as the round found them, and the edges its flips made (true) or took away (false): an edge's
    // triangles are those it had then (a flip's own are used up, so no other change reads them), and whether an
    // edge exists, as then but for the flips. (A hash map of every edge's triangles took 0.13 s a round at 100k.)
    const Triangles F0 = T.F;
    std::unordered_map<std::uint64_t, bool> flippedEdges;
    auto edgeTriangles = [&](int a, int b) {
      std::vector<int> both;  // in order, as `incident` lists them
      for (int f : incident(a))
        if (F0(f, 0) == b || F0(f, 1) == b || F0(f, 2) == b) both.push_back(f);
      return both;
    };
    auto edgeExists = [&](int a, int b) {
      const auto it = flippedEdges.find(key(a, b));
      return it != flippedEdges.end() ? it->second : std::binary_search(ringOf(a).begin(), ringOf(a).end(), b);
    };
    auto interior = [&](int v) { return triangleStart[v + 1] > triangleStart[v] && neighbourStart[v + 1] - neighbourStart[v] == triangleStart[v + 1] - triangleStart[v]; };
    auto point = [&](int v) { return Vec3(T.V.row(v).transpose()); };
    auto centroid = [&](int f) { return Vec3((point(T.F(f, 0)) + point(T.F(f, 1)) + point(T.F(f, 2))) / 3); };
    std::vector<char> usedTriangle(nf, 0), usedVertex(nv, 0), dropped(nf, 0), touched(nv, 0);
    std::vector<int> mergeInto(nv, -1);
    // The flatter principal direction at v, and how well each of v's neighbours lies along it (|cosine| of the
    // edge's tangential part); `best` the first of the best.
    struct AlongFlat {
      Vec3 flat;
      std::vector<double> cosines;  // in the order of ringOf(v)
      int best = -1;
      double along = -1;
    };
    auto alongFlat = [&](int v) {
      const LocalGeometry g = surface.closestPoint(point(v));
      AlongFlat a{(std::abs(g.k1) <= std::abs(g.k2) ? g.d1 : g.d2).normalized(), std::vector<double>(ringOf(v).size())};
      for (std::size_t i = 0; i < ringOf(v).size(); ++i) {
        Vec3 e = point(ringOf(v)[i]) - point(v);
        e -= e.dot(g.normal) * g.normal;
        a.cosines[i] = e.norm() > 0 ? std::abs(e.dot(a.flat)) / e.norm() : 0.0;
        if (a.cosines[i] > a.along) a.along = a.cosines[i], a.best = ringOf(v)[i];
      }
      return a;
    };
    // v merged into its neighbour along the flatter principal direction, where that keeps the mesh sound.
    auto collapse = [&](int v) {
      if (done.collapses + done.drops >= budget || usedVertex[v] || !interior(v)) return false;
      const AlongFlat a = alongFlat(v);
      const std::vector<double>& cosines = a.cosines;
      int w = a.best;
      const double along = a.along;
      // Of the neighbours about as well along it (both ways along a row), the one whose merge leaves the fewest
      // irregular vertices: the merged vertex has the two's neighbours less four, the two common ones one fewer.
      auto commonWith = [&](int u) {
        std::vector<int> c;
        std::set_intersection(ringOf(v).begin(), ringOf(v).end(), ringOf(u).begin(), ringOf(u).end(), std::back_inserter(c));
        return c;
      };
      auto irregularity = [&](int u) {
        const std::vector<int> c = commonWith(u);
        int cost = std::abs(static_cast<int>(ringOf(v).size() + ringOf(u).size()) - 10);
        for (int x : c) cost += std::abs(static_cast<int>(ringOf(x).size()) - 7) - std::abs(static_cast<int>(ringOf(x).size()) - 6);
        return cost;
      };
      if (w >= 0) {
        int bestCost = irregularity(w);
        for (std::size_t i = 0; i < ringOf(v).size(); ++i) {
          const int u = ringOf(v)[i];
          if (u == w || cosines[i] < along - kMergeAlongSlack || usedVertex[u] || !interior(u)) continue;
          const int cost = irregularity(u);
          if (cost < bestCost) bestCost = cost, w = u;
        }
      }
      if (w < 0 || usedVertex[w] || !interior(w)) return false;
      const std::vector<int> common = commonWith(w);
      if (common.size() != 2 || ringOf(common[0]).size() < 5 || ringOf(common[1]).size() < 5 ||
          ringOf(v).size() + ringOf(w).size() - 4 > kMergedMost)
        return false;
      for (int f : star(v))
        if (usedTriangle[f]) return false;
      for (int f : star(w))
        if (usedTriangle[f]) return false;
      const LocalGeometry middle = surface.closestPoint(0.5 * (point(v) + point(w)));
      const Vec3& merged = middle.point;
      // No triangle left around the merged vertex turns over (seen along the normal there).
      const Vec3& normal = middle.normal;
      for (int x : {v, w})
        for (int f : star(x)) {
          Vec3 c[3];
          bool both = false;
          for (int k = 0; k < 3; ++k) {
            const int a = T.F(f, k);
            both |= (a == v || a == w) && a != x;
            c[k] = a == v || a == w ? merged : point(a);
          }
          if (!both && !((c[1] - c[0]).cross(c[2] - c[0]).dot(normal) > 0)) return false;
        }
      for (int x : {v, w}) {
        usedVertex[x] = 1;
        for (int u : ringOf(x)) usedVertex[u] = 1;
        for (int f : star(x)) usedTriangle[f] = 1;
      }
      for (int f : star(v))
        for (int k = 0; k < 3; ++k)
          if (T.F(f, k) == w) dropped[f] = 1;
      T.V.row(w) = merged.transpose();
      mergeInto[v] = w;
      ++done.collapses;
      return true;
    };
    // v's neighbour nearest the flatter direction moved onto the line through v along it (kAlignMost, kAligned).
    auto align = [&](int v) {
      if (usedVertex[v] || !interior(v)) return false;
      const AlongFlat a = alongFlat(v);
      const int w = a.best;
      if (w < 0 || usedVertex[w] || !interior(w)) return false;
      const Vec3 e = point(w) - point(v), target = point(v) + e.dot(a.flat) * a.flat;
      const double off = (target - point(w)).norm();
      if (off > kAlignMost * e.norm() || off < kAligned * e.norm()) return false;
      for (int f : star(w))
        if (usedTriangle[f]) return false;
      const LocalGeometry moved = surface.closestPoint(target);
      for (int f : star(w)) {  // no triangle of w's star turns over (seen along the normal there)
        Vec3 c[3];
        for (int k = 0; k < 3; ++k) c[k] = T.F(f, k) == w ? moved.point : point(T.F(f, k));
        if (!((c[1] - c[0]).cross(c[2] - c[0]).dot(moved.normal) > 0)) return false;
      }
      T.V.row(w) = moved.point.transpose();
      usedVertex[v] = usedVertex[w] = 1;
      for (int u : ringOf(w)) usedVertex[u] = 1;
      for (int f : star(w)) usedTriangle[f] = 1;
      touched[v] = touched[w] = 1;
      ++done.aligned;
      return true;
    };
    const PolyMesh& H = (fromKept ? *keptSolve : *lastSolve).hex;
    for (int f : folded) {
      const int v = d.faceVertex[f], n = H.faceSize(f);
      if (!dropping && round < params.foldAlignRounds && align(v)) continue;
      if (!dropping && collapse(v)) continue;
      const int* ids = H.face(f);
      double worst = 0, least = std::numeric_limits<double>::infinity();
      int w = -1, leastAgainst = -1;
      for (int i = 0; i < n; ++i) {
        const int Ti = d.vertexTriangle[ids[i]], Tj = d.vertexTriangle[ids[(i + 1) % n]];
        if (Ti < 0 || Tj < 0) continue;
        int shared = -1;  // the triangles' common vertex other than v
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            if (T.F(Ti, a) == T.F(Tj, b) && T.F(Ti, a) != v) shared = T.F(Ti, a);
        if (shared < 0) continue;
        const Vec3 g = centroid(Tj) - centroid(Ti);
        const double against = (H.vertex(ids[(i + 1) % n]) - H.vertex(ids[i])).dot(g) / g.squaredNorm();
        if (against < worst) worst = against, w = shared;
        if (against < least) least = against, leastAgainst = shared;
      }
      if (w < 0 && d.boundaryFace[f]) w = leastAgainst;
      if (w < 0) continue;
      if (!edgeExists(v, w)) continue;
      const std::vector<int> both = edgeTriangles(v, w);
      auto fewest = [&](int x) { return interior(x) || !panelsToo ? 4 : kBoundaryFlipFewest; };
      if (both.size() != 2 || triangles[v] < fewest(v) || triangles[w] < fewest(w)) continue;
      const int t1 = both[0], t2 = both[1];
      if (usedTriangle[t1] || usedTriangle[t2]) continue;
      // t1 = (x, y, c) and t2 = (y, x, d) become (c, x, d) and (d, y, c).
      int k1 = 0;
      while (k1 < 3 && !((T.F(t1, k1) == v || T.F(t1, k1) == w) && (T.F(t1, (k1 + 1) % 3) == v || T.F(t1, (k1 + 1) % 3) == w))) ++k1;
      if (k1 == 3) continue;
      const int x = T.F(t1, k1), y = T.F(t1, (k1 + 1) % 3), c = T.F(t1, (k1 + 2) % 3);
      int o = -1;
      for (int k = 0; k < 3; ++k)
        if (T.F(t2, k) != x && T.F(t2, k) != y) o = T.F(t2, k);
      if (o < 0 || o == c || edgeExists(c, o)) continue;
      if (usedVertex[x] || usedVertex[y] || usedVertex[c] || usedVertex[o]) continue;  // next to a collapse
      const Vec3 X = point(x), Y = point(y), C = point(c), D = point(o);
      if (!interior(v) && triangles[v] == 2) {  // the fan of two left one: no sliver (kEarHeight)
        const Vec3 V = point(v), P = point(c), Q = point(o);
        const double longest = std::max({(P - V).squaredNorm(), (Q - V).squaredNorm(), (Q - P).squaredNorm()});
        if (!((P - V).cross(Q - V).norm() > kEarHeight * longest)) {
          // In the round of drops, v (nearly on the chord between its boundary neighbours c and o) is dropped
          // instead: merged into the nearer of them, which stays where it is, its two triangles one, (w, c, o).
          auto curved = [&] {  // the boundary there is not along an asymptotic direction (kAsymptoticBoundary)
            const LocalGeometry g = surface.closestPoint(V);
            const Vec2 along = tangentVector(g, Q - P);
            if (!(along.norm() > 0)) return false;
            const Vec2 unit = along.normalized();
            return std::abs(secondFundamentalForm(g, unit, unit)) > kAsymptoticBoundary * g.largestCurvature();
          };
          const double toP = (P - V).norm(), toQ = (Q - V).norm();
          const bool even = std::max(toP, toQ) <= kDropEven * std::min(toP, toQ);
          if (dropping && done.collapses + done.drops < budget && !usedVertex[v] && !usedVertex[w] && even && curved()) {
            const int keep = toP <= toQ ? c : o;
            const int gone = keep == c ? t1 : t2;  // t1 holds c, t2 holds o
            const int stays = gone == t1 ? t2 : t1;
            Vec3 corner[3];
            for (int k = 0; k < 3; ++k) corner[k] = T.F(stays, k) == v ? point(keep) : point(T.F(stays, k));
            const Vec3 n = surface.closestPoint((corner[0] + corner[1] + corner[2]) / 3).normal;
            if ((corner[1] - corner[0]).cross(corner[2] - corner[0]).dot(n) > 0) {
              dropped[gone] = 1;
              mergeInto[v] = keep;
              usedTriangle[t1] = usedTriangle[t2] = 1;
              for (int u : {v, w, c, o}) {
                usedVertex[u] = 1;
                for (int z : ringOf(u)) usedVertex[z] = 1;
              }
              ++done.drops;
            }
          }
          continue;
        }
      }
      if (dropping) continue;
      const Vec3 normal = surface.closestPoint(0.25 * (X + Y + C + D)).normal;
      if (!((X - C).cross(D - C).dot(normal) > 0) || !((D - C).cross(Y - C).dot(normal) > 0)) continue;
      T.F.row(t1) << c, x, o;
      T.F.row(t2) << o, y, c;
      usedTriangle[t1] = usedTriangle[t2] = 1;
      touched[x] = touched[y] = touched[c] = touched[o] = 1;
      flippedEdges[key(c, o)] = true;
      flippedEdges[key(x, y)] = false;
      --triangles[x], --triangles[y], ++triangles[c], ++triangles[o];
      ++done.flips;
    }
    if (dropping && done.drops == kept.drops) break;  // no vertex to drop: no round to solve (t is `best`)
    // The vertices a change touched (a merge's two and their neighbours, a flip's four corners, an alignment's two
    // and the moved one's neighbours), by their ids after the merges.
    std::vector<int> id(nv);
    std::iota(id.begin(), id.end(), 0);
    // The merged vertices' ids given up, the triangles on the collapsed edges dropped.
    if (std::any_of(mergeInto.begin(), mergeInto.end(), [](int m) { return m >= 0; })) {
      id.assign(nv, -1);
      int count = 0;
      for (int v = 0; v < nv; ++v)
        if (mergeInto[v] < 0) id[v] = count++;
      Points V(count, 3);
      for (int v = 0; v < nv; ++v)
        if (id[v] >= 0) V.row(id[v]) = T.V.row(v);
      Triangles F(nf - std::count(dropped.begin(), dropped.end(), char(1)), 3);
      for (int f = 0, row = 0; f < nf; ++f) {
        if (dropped[f]) continue;
        for (int k = 0; k < 3; ++k) {
          const int a = T.F(f, k);
          F(row, k) = id[mergeInto[a] >= 0 ? mergeInto[a] : a];
        }
        ++row;
      }
      T.V = std::move(V);
      T.F = std::move(F);
      for (int v = 0; v < nv; ++v)
        if (mergeInto[v] >= 0) id[v] = id[mergeInto[v]];
    }
    // The stars to mend: those within kRepairRings of a change. The others were mended (or resisted) the round
    // before and are as they were: the mesh elsewhere is the same, bit for bit.
    std::vector<char> near(static_cast<std::size_t>(T.V.rows()), 0);
    for (int v = 0; v < nv; ++v)
      if (usedVertex[v] || touched[v]) near[id[v]] = 1;
    markWithinEdges(T, near, kRepairRings);
    // Its note is said once, with the changes' (the caller's).
    const std::size_t notes = t.notes.size();
    const RepairResult r = repairStars(t, surface, kRepairSweeps, &geometry, &near);
    t.notes.resize(notes);
    done.repair.moved += r.moved, done.repair.flips += r.flips;
  }
  t = std::move(best);
  return kept;
}

}  // namespace phex::detail
