// phex — one call from parameters to a P-Hex mesh: surface → triangulate → dualize → planarize → measure.
#pragma once
#include <string>
#include <vector>

#include "phex/duality.hpp"
#include "phex/metrics.hpp"
#include "phex/planarize.hpp"
#include "phex/progress.hpp"
#include "phex/surfaces.hpp"
#include "phex/triangulation.hpp"

namespace phex {

constexpr int kMaxFaces = 1000000;  // the largest face count phex accepts

struct PipelineParams {
  std::string surface = "torus";   // an analytic surface name (see analyticSurfaces())
  SurfaceParams surfaceParams;     // its parameters; missing ones take their defaults
  int faces = 2000;                // wanted number of hexagons, 12 .. kMaxFaces (ignored when cell > 0)
  double cell = 0.0;               // wanted edge length of the triangulation, in model units (0: use faces)
  double tolerance = 1e-9;         // planarity goal, relative to edge length, in (0, 0.1]
  double lambda = 1.0;             // initial closeness weight, in [0, 1e6]
  double mu = 0.0;                 // surface-distance weight, in [0, 1e6]
  int maxIterations = 100;         // Gauss-Newton iteration cap, 1 .. 10000
  Duality duality = Duality::Dupin;  // initializer of the optimization: Dupin (§6) or tangent (§4.1)
  PlanarizeMethod solver = PlanarizeMethod::LocalGlobal;  // planarity solver (see planarize.hpp)
};

// "dupin" / "tangent" <-> Duality; parseDuality throws Error(InvalidParameter) for other names.
Duality parseDuality(const std::string& name);
const char* dualityName(Duality d);

struct StageTiming {
  std::string stage;
  double milliseconds = 0.0;
};

struct PipelineResult {
  Triangulation triangulation;
  PolyMesh initial;            // the dual mesh before optimization (H0)
  PolyMesh hex;                // the P-Hex mesh
  DualMesh dual;               // bookkeeping of the dual (which vertex / triangle each element comes from)
  MeshMetrics metrics;         // of `hex`
  PlanarizeReport solve;
  std::vector<StageTiming> timings;
  double totalMilliseconds = 0.0;
};

// Throws Error(InvalidParameter) naming the first parameter that is wrong.
void validate(const PipelineParams& params);

PipelineResult runPipeline(const PipelineParams& params, const ProgressFn& progress = {},
                           const CancelFlag* cancel = nullptr);

}  // namespace phex
