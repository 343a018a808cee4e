// phex — the global method's rounds against folds (flipFoldsAway: edge collapses, flips, alignments and drops where
// the Dupin dual, solved with folds allowed, has faces crossing themselves), and what pipeline.cpp shares with them.
#pragma once
#include <optional>

#include "phex/duality.hpp"
#include "phex/pipeline.hpp"
#include "phex/planarize.hpp"
#include "phex/progress.hpp"
#include "phex/surface.hpp"
#include "phex/triangulation.hpp"

namespace phex::detail {

// Of pipeline.cpp, which says more: whether the repairs that trade hexagons for cuts on a noisy upload apply on
// `surface`, and the solver's options as the run's parameters ask for them, for a triangulation laid by `method`.
bool smoothRepairs(const PipelineParams& params, const Surface& surface);
PlanarizeOptions planarizeOptions(const PipelineParams& params, TriangulationMethod method, const Surface& surface);

// A dual mesh as the local solver left it, with its report.
struct SolvedDual {
  PolyMesh hex;
  PlanarizeReport report;
};

// The global method's triangulation where its dual, solved with folds allowed, has faces crossing themselves
// (next to parabolic curves, where Props. 4 and 5 judge nothing). In each round, for each such face:
//  - its vertex is merged with the neighbour along the flatter principal direction (an edge collapse, the two
//    at the edge's middle; of the neighbours about as well along it, the one that leaves the fewest irregular
//    vertices: kMergeAlongSlack): near a parabolic curve a planar hexagon must be long along that direction, the
//    ruling (where no edge of its star runs within about |k_min / k_max| radians of it, every edge of the dual
//    face runs along the ruling: the face folds), and two faces merged along it are twice as long. Not at the
//    boundary, where the two share more than two neighbours (the mesh would not stay a manifold), where a
//    neighbour is left with fewer than five, the merged vertex with more than kMergedMost, or a triangle of the
//    star would turn over; at most kCollapseShare of the vertices in all;
//  - else the edge of its star whose dual edge runs most against the centroids of its two triangles is flipped
//    (not at a vertex of three triangles, not where the quad is not convex in the tangent plane or its other
//    diagonal is an edge already); a folded boundary panel's vertex is flipped only (kBoundaryFlipFewest,
//    kEarHeight);
// then the stars are repaired and the solve runs again (around the changes alone: solveAround); kept while the
// folds drop by 3 % or more (kFoldGain). Every node stays one of three faces (the dual of a triangulation), where a
// cut of a folded face makes two nodes of four.
// Measured on the uploaded bumps at 10k faces: folds 382 -> 190 -> 94 -> 64 -> 52 -> 20 over five rounds of
// collapses, 382 -> 185 -> 153 with flips alone; merged along the steeper direction instead, or along the
// shortest edge, the 40-run sweep cut 1115 and 859 faces, against 230 along the flatter one (METHOD.md).
// Returns the changes kept and the repairs of the stars around them; `keptDual` gets the Dupin dual of the
// triangulation kept, and `keptSolve` that dual as solved here (folds allowed, no fit).
struct FoldFlips {
  int collapses = 0, flips = 0, aligned = 0;
  int drops = 0;  // boundary vertices dropped (kDropEven)
  int folded = -1;  // interior faces crossing themselves in the kept triangulation's dual solved with folds allowed
  RepairResult repair;  // the repairs after the changes kept (moves, and edges flipped where moves did not do)
};
FoldFlips flipFoldsAway(Triangulation& t, const Surface& surface, const PipelineParams& params, const ProgressFn& progress,
                        const CancelFlag* cancel, std::optional<DualMesh>& keptDual, std::optional<SolvedDual>& keptSolve);

}  // namespace phex::detail
