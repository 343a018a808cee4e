#include "phex/pipeline.hpp"

#include <chrono>
#include <cmath>
#include <sstream>

#include "phex/error.hpp"

namespace phex {
namespace {

class StageClock {
 public:
  explicit StageClock(std::vector<StageTiming>& out) : out_(out) {}
  void done(const std::string& stage) {
    const auto now = std::chrono::steady_clock::now();
    out_.push_back({stage, std::chrono::duration<double, std::milli>(now - last_).count()});
    last_ = now;
  }

 private:
  std::vector<StageTiming>& out_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

Duality parseDuality(const std::string& name) {
  if (name == "dupin") return Duality::Dupin;
  if (name == "tangent") return Duality::Tangent;
  throw Error(ErrorCode::InvalidParameter, "duality must be 'dupin' or 'tangent' (got '" + name + "')");
}

const char* dualityName(Duality d) { return d == Duality::Dupin ? "dupin" : "tangent"; }

void validate(const PipelineParams& p) {
  auto fail = [](const std::string& m) { throw Error(ErrorCode::InvalidParameter, m); };
  if (!std::isfinite(p.cell) || p.cell < 0) fail("cell must be a positive length (got " + number(p.cell) + ")");
  if (p.cell == 0 && (p.faces < 12 || p.faces > kMaxFaces))
    fail("faces must be between 12 and " + std::to_string(kMaxFaces) + " (got " + std::to_string(p.faces) + ")");
  if (!(p.tolerance > 0 && p.tolerance <= 0.1)) fail("tolerance must be in (0, 0.1] (got " + number(p.tolerance) + ")");
  if (!(p.lambda >= 0 && p.lambda <= 1e6)) fail("lambda must be in [0, 1e6] (got " + number(p.lambda) + ")");
  if (!(p.mu >= 0 && p.mu <= 1e6)) fail("mu must be in [0, 1e6] (got " + number(p.mu) + ")");
  if (p.maxIterations < 1 || p.maxIterations > 10000)
    fail("maxIterations must be between 1 and 10000 (got " + std::to_string(p.maxIterations) + ")");
}

PipelineResult runPipeline(const PipelineParams& params, const ProgressFn& progress, const CancelFlag* cancel) {
  validate(params);
  const ParametricSurfacePtr surface = makeSurface(params.surface, params.surfaceParams);
  const auto t0 = std::chrono::steady_clock::now();
  PipelineResult r;
  StageClock clock(r.timings);
  auto report = [&](const char* stage, double fraction, const std::string& msg) {
    checkCancel(cancel);
    if (progress) progress({stage, fraction, msg});
  };

  report("triangulate", 0, "laying the triangulation");
  double cell = params.cell > 0 ? params.cell : cellForFaceCount(*surface, params.faces);
  if (params.cell > 0) {
    const double expected = std::pow(cellForFaceCount(*surface, 1) / cell, 2);
    if (expected > kMaxFaces)
      throw Error(ErrorCode::InvalidParameter, "cell " + number(cell) + " would give about " + number(std::round(expected)) +
                                                   " faces, more than the limit of " + std::to_string(kMaxFaces));
  }
  r.triangulation = latticeTriangulation(*surface, cell);
  clock.done("triangulate");

  report("dualize", 0, std::string(dualityName(params.duality)) + " duality");
  r.dual = params.duality == Duality::Dupin ? dupinDual(r.triangulation, *surface) : tangentDual(r.triangulation, *surface);
  r.initial = r.dual.mesh;
  clock.done("dualize");

  report("planarize", 0, "planarity optimization");
  r.hex = r.initial;
  PlanarizeOptions po;
  po.method = params.solver;
  po.lambda = params.lambda;
  po.mu = params.mu;
  po.tolerance = params.tolerance;
  po.maxIterations = params.maxIterations;
  po.surface = surface.get();
  r.solve = planarize(r.hex, po, progress, cancel);
  clock.done("planarize");

  report("measure", 0, "measuring");
  r.metrics = measure(r.hex, *surface);
  clock.done("measure");
  r.totalMilliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (progress) progress({"done", 1, "done"});
  return r;
}

}  // namespace phex
