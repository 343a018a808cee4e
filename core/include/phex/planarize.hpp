// phex — planarity optimization (§6).
#pragma once
#include <string>
#include <vector>

#include "phex/mesh.hpp"
#include "phex/progress.hpp"
#include "phex/surface.hpp"

namespace phex {

// How the planarity condition enters the optimization.
enum class PlanarizeMethod {
  // §6 as published: F(f) = sum of squared tetrahedron volumes of consecutive vertex quadruples; the
  // unknowns are the vertices only (the reference method).
  Volumes,
  // Each face gets its own plane (unit normal n_f, offset d_f) as extra unknowns and the residuals are
  // the vertex-to-plane distances n_f . x - d_f. Zero residual means exactly the same thing (planar faces),
  // but every residual touches one vertex and one plane, so Ceres eliminates the vertices by a Schur
  // complement and factorizes a much smaller and sparser system over the planes.
  Planes,
  // The same per-face-plane energy minimized by block coordinate descent: least-squares planes for fixed
  // vertices, then one 3x3 solve per vertex for fixed planes. No global factorization at all.
  LocalGlobal
};
const char* methodName(PlanarizeMethod m);
// "volumes" / "planes"; throws Error(InvalidParameter) for other names.
PlanarizeMethod parseMethod(const std::string& name);

struct PlanarizeOptions {
  PlanarizeMethod method = PlanarizeMethod::LocalGlobal;
  double lambda = 1.0;        // closeness weight of F_s at the first round; divided by 10 each round (§6)
  double mu = 0.0;            // weight of F_d, the squared distance to the surface (needs `surface`)
  // The local solver's fairness: each interior node (not on the mesh's boundary) pulled towards the mean of its
  // neighbours with weight fairness * sqrt(λ) per squared mean edge. It fades with λ, more slowly than the
  // closeness term, and is gone with it, so the end is as planar as without it: meanwhile the faces' planes
  // follow a smooth mesh instead of chasing the intersections of nearly parallel planes (flat parts, parabolic
  // curves, noise) into folds.
  double fairness = 0.0;
  double tolerance = 1e-9;    // stop when max face planarity (relative to edge length) is at most this
  int maxIterations = 100;    // cap on Gauss-Newton iterations over all rounds
  const Surface* surface = nullptr;
  // The local solver never turns a simple face into a self-intersecting one: a vertex step that would is
  // shortened (halved, up to four times) or not taken. Where a triangulation leaves no fold-free planar
  // mesh nearby (faces across parabolic curves of an invalid laying) planarity then stops short of the
  // tolerance, and the report says so; false lets such faces fold to reach planarity. The Ceres solvers
  // do not guard.
  bool preventFolds = true;
  // Once planar, shift every face plane along its normal (each vertex following to the intersection of
  // its faces' planes, so the faces stay exactly planar) to bring the vertices closer to the surface
  // (needs `surface`). Kept only where it lowers the largest distance without folding a face.
  bool fitSurface = true;
  // The local solver only: vertices (#V, 1 = fixed) that keep their place, and the faces at them the plane their
  // corners give at the start (they should be planar then), for a solve of part of a mesh with its rim held (the
  // pipeline's rounds against folds solve only around their changes).
  const std::vector<char>* fixedVertices = nullptr;
};

struct IterationLog {
  int round = 0;
  int iteration = 0;        // counted over all rounds, from 1
  double lambda = 0.0;
  double objective = 0.0;   // value of the scaled objective after the iteration
  double planarityMax = 0.0;
  double milliseconds = 0.0;
};

// The goal for the largest node distance to the surface, over its bounding-box diagonal (0.2 %): past it the
// surface fit tries other ways (planarize) and the pipeline the other dual (runPipeline).
inline constexpr double kSurfaceDistanceGoal = 0.002;

struct PlanarizeReport {
  int iterations = 0;
  int rounds = 0;
  bool converged = false;   // planarityMax <= tolerance
  double initialPlanarityMax = 0.0;
  double planarityMax = 0.0;
  double displacementMax = 0.0;  // largest vertex move from the initial mesh, over the mean edge length
  // The plane shift towards the surface (PlanarizeOptions::fitSurface): whether it was kept, and the
  // largest vertex distance to the surface before and after it, over the surface's bounding-box diagonal.
  bool surfaceFitted = false;
  double surfaceDistanceBefore = 0.0;
  double surfaceDistanceAfter = 0.0;
  // Nodes on fewer than three face planes then put nearest to the surface along the directions those planes
  // leave free (part of fitSurface; the faces stay exactly as planar).
  int freeNodesSettled = 0;
  // Boundary nodes then put on the surface's boundary curve, or nearest to it, along the directions their
  // planes leave free (part of fitSurface, after the free nodes; the faces stay exactly as planar).
  int boundaryNodesPlaced = 0;
  std::vector<IterationLog> log;
};

// Moves the vertices of `mesh` so that its faces become planar, minimizing
//   Σ_f F(f) + λ F_s + μ F_d
// with F(f) the sum of the squared volumes of the tetrahedra of consecutive vertex quadruples of f
// (six for a hexagon), F_s the squared distances to the initial positions and F_d the squared distances
// to the surface. Volumes are scaled by the cube of the mean edge length and distances by the mean edge
// length, so λ and μ do not depend on the size of the model. Each round is a Gauss-Newton
// (Levenberg-Marquardt) solve with Ceres; λ is divided by 10 after each round.
PlanarizeReport planarize(PolyMesh& mesh, const PlanarizeOptions& options, const ProgressFn& progress = {},
                          const CancelFlag* cancel = nullptr);

// The largest planarity over the faces of `mesh` (facePlanarity, relative to each face's edge length).
double maxPlanarity(const PolyMesh& mesh);

// The surface fit of PlanarizeOptions::fitSurface alone (whatever that flag says), on a mesh the solve left planar
// to the tolerance (report.converged; else nothing is done): the face planes shifted towards the surface, then
// the free and boundary nodes placed; fills the report's surface fields. planarize() ends with it.
void fitPlanarMeshToSurface(PolyMesh& mesh, const PlanarizeOptions& options, PlanarizeReport& report,
                            const ProgressFn& progress = {}, const CancelFlag* cancel = nullptr);

}  // namespace phex
