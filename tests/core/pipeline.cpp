#include <catch.hpp>

#include "phex/error.hpp"
#include "phex/pipeline.hpp"

using namespace phex;

TEST_CASE("pipeline: the torus default reaches planarity 1e-9 with no invalid face") {
  PipelineParams p;  // torus, 2000 faces
  int progressCalls = 0;
  const PipelineResult r = runPipeline(p, [&](const Progress&) { ++progressCalls; });
  CHECK(progressCalls > 3);
  CHECK(r.metrics.faceCount > 1600);
  CHECK(r.metrics.faceCount < 2400);
  CHECK(r.metrics.facesBySize.at(6) == r.metrics.faceCount);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.solve.converged);
  CHECK(r.solve.initialPlanarityMax > 1e-6);  // there was something to optimize
  REQUIRE(r.timings.size() == 4);
  CHECK(r.timings[0].stage == "triangulate");
}

TEST_CASE("pipeline: sphere band with a cell size") {
  PipelineParams p;
  p.surface = "sphere";
  p.cell = 0.15;
  const PipelineResult r = runPipeline(p);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.metrics.faceCount > 100);
}

TEST_CASE("pipeline: bad parameters are named") {
  PipelineParams p;
  p.surface = "nope";
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("unknown surface 'nope'"));
  p = {};
  p.faces = 0;
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("faces"));
  p.faces = 2000000000;
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("faces"));
  p = {};
  p.cell = 1e-6;
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("more than the limit"));
  p = {};
  p.tolerance = 0;
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("tolerance"));
  // The pipeline still works after errors.
  p = {};
  p.faces = 200;
  CHECK(runPipeline(p).metrics.planarityMax <= 1e-9);
}

TEST_CASE("pipeline: a raised cancel flag stops the run") {
  PipelineParams p;
  CancelFlag cancel{false};
  try {
    runPipeline(p, [&](const Progress& pr) { if (pr.stage == "planarize") cancel = true; }, &cancel);
    FAIL("expected Cancelled");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::Cancelled);
  }
}
