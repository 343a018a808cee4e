// phex — planarity optimization (§6).
#pragma once
#include <vector>

#include "phex/mesh.hpp"
#include "phex/progress.hpp"
#include "phex/surface.hpp"

namespace phex {

struct PlanarizeOptions {
  double lambda = 1.0;        // closeness weight of F_s at the first round; divided by 10 each round (§6)
  double mu = 0.0;            // weight of F_d, the squared distance to the surface (needs `surface`)
  double tolerance = 1e-9;    // stop when max face planarity (relative to edge length) is at most this
  int maxIterations = 100;    // cap on Gauss-Newton iterations over all rounds
  const Surface* surface = nullptr;
};

struct IterationLog {
  int round = 0;
  int iteration = 0;        // counted over all rounds, from 1
  double lambda = 0.0;
  double objective = 0.0;   // value of the scaled objective after the iteration
  double planarityMax = 0.0;
  double milliseconds = 0.0;
};

struct PlanarizeReport {
  int iterations = 0;
  int rounds = 0;
  bool converged = false;   // planarityMax <= tolerance
  double initialPlanarityMax = 0.0;
  double planarityMax = 0.0;
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

}  // namespace phex
