#include <catch.hpp>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>

#include "notes.hpp"
#include "phex/error.hpp"
#include "phex/mesh_io.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/pipeline.hpp"
#include "phex/subdivision.hpp"
#include "phex/surfaces.hpp"

using namespace phex;
using test::allNotes;

namespace {

constexpr double kPi = 3.14159265358979323846;

// An analytic surface sampled by its lattice at about `faces` hexagons (two triangles each), as uploaded OBJ bytes.
MeshInput sampledUpload(const std::string& surface, int faces, const SurfaceParams& params = {}) {
  const ParametricSurfacePtr s = makeSurface(surface, params);
  const std::string obj = toObj(latticeTriangulation(*s, cellForFaceCount(*s, faces)).mesh);
  return MeshInput{std::vector<std::uint8_t>(obj.begin(), obj.end()), "obj", surface + ".obj"};
}

// A developable's P-Hex mesh as §3 has it: quad-shaped hexagons planar as laid (no solver iteration), none
// crossing itself, near the surface.
void checkPlanarAsLaid(const PipelineResult& r) {
  CHECK(r.solve.converged);
  CHECK(r.solve.iterations == 0);
  CHECK(r.metrics.planarityMax <= 1e-12);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.interiorHexagonFraction >= 0.99);
  CHECK(r.metrics.surfaceDistanceMax < 0.002);
}

// Method 1 on half a cyclide ring (uSpan 180), reaching `vSpan` degrees around its tube (360: closed).
PipelineParams progressiveCyclidePatch(double vSpan, int faces) {
  PipelineParams p;
  p.surface = "cyclide";
  p.surfaceParams = {{"uSpan", 180.0}, {"vSpan", vSpan}};
  p.method = TriangulationMethod::Progressive;
  p.faces = faces;
  return p;
}

// A grid over [-1, 1]^2 as uploaded OBJ bytes ("name.obj"): an n x n grid whose vertex at (x, y) is placed at
// point(x, y), each square cut along one diagonal, of the triangles whose centroid (in x, y) `keep` accepts
// (all by default; a hole where it does not); coordinates written with `digits` significant digits.
template <typename Point, typename Keep = bool (*)(double, double)>
MeshInput gridUpload(const std::string& name, int n, Point point, Keep keep = [](double, double) { return true; },
                     int digits = 12) {
  std::ostringstream obj;
  obj.precision(digits);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const Vec3 p = point(-1 + 2.0 * i / n, -1 + 2.0 * j / n);
      obj << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 2, d = a + n + 1;
      const double x = -1 + (2.0 * i + 1) / n, y = -1 + (2.0 * j + 1) / n, third = 1.0 / (3 * n);
      if (keep(x + third, y - third)) obj << "f " << a << ' ' << b << ' ' << c << '\n';
      if (keep(x - third, y + third)) obj << "f " << a << ' ' << c << ' ' << d << '\n';
    }
  const std::string text = obj.str();
  return MeshInput{std::vector<std::uint8_t>(text.begin(), text.end()), "obj", name + ".obj"};
}

// A height field z(x, y) over [-1, 1]^2 as uploaded OBJ bytes (gridUpload).
template <typename Height, typename Keep = bool (*)(double, double)>
MeshInput heightFieldUpload(const std::string& name, int n, Height z, Keep keep = [](double, double) { return true; }) {
  return gridUpload(name, n, [&](double x, double y) { return Vec3(x, y, z(x, y)); }, keep);
}

}  // namespace

TEST_CASE("pipeline: the torus default reaches planarity 1e-9 with no invalid face") {
  PipelineParams p;  // torus, 2000 faces, progressive conjugation, Dupin duality, local solver
  int progressCalls = 0;
  const PipelineResult r = runPipeline(p, [&](const Progress&) { ++progressCalls; });
  CHECK(progressCalls > 3);
  CHECK(r.metrics.faceCount > 1200);
  CHECK(r.metrics.faceCount < 3200);
  CHECK(r.metrics.facesBySize.at(6) >= 0.9 * r.metrics.faceCount);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.solve.converged);
  CHECK(r.solve.initialPlanarityMax > 1e-6);  // there was something to optimize
  REQUIRE(r.timings.size() == 4);
  CHECK(r.timings[0].stage == "triangulate");
}

TEST_CASE("pipeline: the lattice on the torus gives only hexagons") {
  PipelineParams p;
  p.method = TriangulationMethod::Lattice;
  const PipelineResult r = runPipeline(p);
  CHECK(r.metrics.faceCount > 1600);
  CHECK(r.metrics.faceCount < 2400);
  CHECK(r.metrics.facesBySize.at(6) == r.metrics.faceCount);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.check.regularFraction == 1.0);
}

TEST_CASE("pipeline: auto rings the hyperboloid and the catenoid with the parameter lattice, its count laid to the faces asked") {
  // Their boundary circles are parameter lines: every ring of panels alike, no zip seam, every boundary node on a
  // circle. Method 2's fronts met in a seam whose ends stood up to 5 mean edges off the circles (the catenoid at
  // 300, 500, 3000 and 10000 faces; the embed example's tower, a hyperboloid, at 500: 2.17), with panels 25-100
  // times smaller than the largest. The extreme hyperboloid (waist 0.2, rims 1.35) left Method 2 unconverged, and
  // the lattice's first lay 27 % short of the count (732 faces for 1000): laid again at a smaller cell.
  struct Case {
    const char* surface;
    SurfaceParams params;
    int faces;
  };
  for (const Case& c : {Case{"catenoid", {}, 3000}, Case{"catenoid", {}, 500},
                        Case{"hyperboloid", {{"a", 5.0}, {"c", 7.0}, {"height", 20.0}}, 500},
                        Case{"hyperboloid", {{"a", 0.2}, {"c", 0.3}, {"height", 4.0}}, 1000}}) {
    INFO(c.surface << " at " << c.faces << " faces");
    PipelineParams p;
    p.surface = c.surface;
    p.surfaceParams = c.params;
    p.faces = c.faces;
    const PipelineResult r = runPipeline(p);
    CHECK(r.method == TriangulationMethod::Lattice);
    CHECK(r.solve.converged);
    CHECK(r.metrics.planarityMax <= 1e-9);
    CHECK(r.interiorFacesSplit + r.boundaryPanelsSplit == 0);
    CHECK(r.interiorHexagonFraction == 1.0);
    CHECK(r.boundaryOffset.max <= 0.01);  // in mean edges: every boundary node on a circle
    CHECK(r.boundaryClip.skipped == 0);
    CHECK(r.coverageGap <= 0.1);
    CHECK(std::abs(r.metrics.faceCount - c.faces) <= 0.1 * c.faces);
    double smallest = std::numeric_limits<double>::infinity(), largest = 0;
    for (double a : r.metrics.faceArea) smallest = std::min(smallest, a), largest = std::max(largest, a);
    INFO("panel areas " << smallest << " to " << largest);
    CHECK(smallest >= 0.01 * largest);
  }
}

TEST_CASE("pipeline: subdivision of the icosahedron control gives 12 pentagons (§7)") {
  PipelineParams p;
  p.method = TriangulationMethod::Subdivision;
  p.surface = "icosahedron";
  p.faces = 600;
  const PipelineResult r = runPipeline(p);
  CHECK(r.metrics.facesBySize.at(5) == 12);
  CHECK(r.metrics.facesBySize.at(6) == r.metrics.faceCount - 12);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.metrics.vertexValence.size() == 1);  // a closed P-Hex mesh: every node joins three faces
  CHECK(r.metrics.vertexValence.count(3) == 1);
  p.surface = "teapot";
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("control mesh"));
}

TEST_CASE("pipeline: an uploaded mesh is tiled, a broken one is named") {
  // A torus patch sampled as OBJ text, uploaded as bytes.
  PipelineParams p;
  p.mesh = sampledUpload("torus", 6000);
  p.faces = 800;
  const PipelineResult r = runPipeline(p);
  CHECK(r.metrics.faceCount > 400);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.surfaceDistanceMax < 0.01);

  p.mesh->bytes = {'v', ' ', '0', '\n', 'f', ' ', '1', '\n'};
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("torus.obj"));
  p.mesh->bytes.clear();
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("empty"));
  p.mesh = sampledUpload("torus", 6000);
  p.method = TriangulationMethod::Lattice;
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("lattice"));
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
  p = {};
  p.lowerBound = 5;
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("lowerBound"));
  p = {};
  p.field = "sideways";
  CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("sideways"));
  CHECK_THROWS_WITH(parseTriangulationMethod("random"), Catch::Contains("method"));
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

TEST_CASE("pipeline: method auto tiles every analytic surface validly (the free-form surface aside)") {
  for (const SurfaceSpec& spec : analyticSurfaces()) {
    if (spec.name == "plane") continue;  // planar points: nothing to check
    INFO(spec.name << " by " << spec.method << " along " << spec.field);
    PipelineParams p;
    p.surface = spec.name;
    p.faces = 2000;
    const PipelineResult r = runPipeline(p);
    INFO("invalid stars " << r.check.invalidStars.size() << ", valence 6 " << r.check.regularFraction << ", coverage "
                          << r.check.coverage << ", self-intersecting " << r.metrics.selfIntersectingCount);
    if (spec.name == "freeform") {
      // Laid globally, with singular vertices at the bump tops (umbilics inside parabolic rings, where no regular
      // conjugate network exists): planar, no face crossing itself and no hole, but faces next to the rings reach
      // planarity only by folding, and are cut (docs/METHOD.md), so fewer hexagons.
      CHECK(r.method == TriangulationMethod::Global);
      CHECK(r.metrics.planarityMax <= 1e-9);
      CHECK(r.metrics.selfIntersectingCount == 0);
      CHECK(r.coverageGap <= 1);
      CHECK(r.interiorHexagonFraction >= 0.8);
      continue;
    }
    if (spec.name == "helicoid") {
      // Laid globally so that no strip is left bare (its rows stopped short of its asymptotic edges: 2.9 mean panel
      // edges bare at 1000 faces); boundary panels along those edges are cut in two (Prop. 5: no planar panel there
      // without folding), the interior is not.
      CHECK(r.method == TriangulationMethod::Global);
      CHECK(r.metrics.planarityMax <= 1e-9);
      CHECK(r.metrics.selfIntersectingCount == 0);
      CHECK(r.interiorFacesSplit == 0);
      CHECK(r.interiorHexagonFraction >= 0.9);
      CHECK(r.coverageGap <= 0.5);
      CHECK(r.boundaryOffset.max <= 1.0);
      continue;
    }
    if (spec.method == "global") {
      // The elliptic paraboloid: laid globally for a clean edge, its lattice's few invalid stars (of the bounded
      // Dupin metric) mended or merged by the rounds against folds; no face cut, hexagons but at the boundary.
      CHECK(r.method == TriangulationMethod::Global);
      CHECK(r.metrics.planarityMax <= 1e-9);
      CHECK(r.metrics.selfIntersectingCount == 0);
      CHECK(r.interiorFacesSplit + r.boundaryPanelsSplit == 0);
      CHECK(r.interiorHexagonFraction >= 0.95);
      CHECK(r.boundaryOffset.max <= 0.01);  // every boundary node on the curve
      CHECK(r.boundaryClip.skipped == 0);
      CHECK(r.coverageGap <= 0.1);
      continue;
    }
    CHECK(r.metrics.planarityMax <= 1e-9);
    CHECK(r.check.invalidStars.empty());
    // No interior face crosses itself; a boundary panel may where the laying ends in skinny triangles whose
    // dual points fall outside them (the helicoid: 1 of 1989).
    int interiorFolds = 0;
    for (int f = 0; f < r.metrics.faceCount; ++f) interiorFolds += r.metrics.selfIntersecting[f] && !r.dual.boundaryFace[f];
    CHECK(interiorFolds == 0);
    CHECK(r.metrics.selfIntersectingCount <= 0.001 * r.metrics.faceCount);
    CHECK(r.metrics.surfaceDistanceMax <= 0.002);
    CHECK(r.check.regularFraction >= 0.95);
    CHECK(r.interiorHexagonFraction >= 0.9);
    CHECK(r.check.coverage >= 0.8);
    CHECK(r.metrics.faceCount >= 0.75 * p.faces);
    CHECK(r.metrics.faceCount <= 1.25 * p.faces);
  }
}

TEST_CASE("pipeline: the start point and laying direction can be set, and are checked") {
  PipelineParams p;
  p.surface = "torus";
  p.method = TriangulationMethod::Prespecified;
  p.faces = 800;
  // By default the start is chosen by trial lays: on the torus a parabolic circle, from where rows along the
  // parallels are never resampled (the test below).
  const TriangulationStage chosen = triangulate(p);
  REQUIRE(!chosen.triangulation.notes.empty());
  CHECK(chosen.triangulation.notes.front().find("start chosen among") != std::string::npos);
  {
    // With a coarse cell given (about 290 faces by the area estimate) and the count left at its default (2000),
    // the trials are laid at about half the size the cell gives (146 faces), not at 1000 faces (lays
    // bigger than the one asked for; on the uploaded bumps at cell 0.0101 they took 59 % of the run).
    PipelineParams coarse = p;
    coarse.faces = 2000;
    coarse.cell = 0.25;
    const TriangulationStage sized = triangulate(coarse);
    REQUIRE(!sized.triangulation.notes.empty());
    const std::string& note = sized.triangulation.notes.front();
    INFO(note);
    const std::string key = "trial lays at about ";
    const std::size_t at = note.find(key);
    REQUIRE(at != std::string::npos);
    const int trialFaces = std::stoi(note.substr(at + key.size()));
    CHECK(trialFaces >= 50);
    // About half of what the cell gives by the area estimate (the lay itself depends on the start chosen).
    const double estimate = std::pow(cellForFaceCount(*sized.surface, 1) / coarse.cell, 2);
    CHECK(trialFaces <= 0.55 * estimate);
    CHECK(trialFaces >= 0.45 * estimate);
  }
  p.start = Vec3(1.4, 0, 0);
  p.direction = Vec3(0, 1, 0);  // along the outer equator
  const TriangulationStage given = triangulate(p);
  CHECK(given.triangulation.notes.front().find("L0 closed") != std::string::npos);
  CHECK(given.check.invalidStars.empty());
  p.direction = Vec3(0, 0, 1);  // along the meridian: the infeasible laying direction of Fig. 19
  const PipelineResult across = runPipeline(p);
  p.direction = Vec3(0, 1, 0);
  const PipelineResult along = runPipeline(p);
  CHECK(along.metrics.selfIntersectingCount == 0);
  CHECK(along.interiorFacesSplit == 0);
  CHECK(across.metrics.selfIntersectingCount + (across.solve.converged ? 0 : 1) > 0);
  p.start = Vec3(std::nan(""), 0, 0);
  CHECK_THROWS_WITH(triangulate(p), Catch::Contains("start"));
  p.start.reset();
  p.direction = Vec3::Zero();
  CHECK_THROWS_WITH(triangulate(p), Catch::Contains("direction"));
}

TEST_CASE("pipeline: on a ring, Method 2 starts on a parabolic circle and lays every interior vertex of valence 6") {
  // From the candidates before (the middle, the most elliptic and the most hyperbolic sample) the rows along
  // the parallels started on the inner or the outer equator and were resampled twice as they grew or shrank
  // by 2.3 times around the tube: two rings of pentagons and heptagons, 92 % valence 6 at 1000 and 2000
  // faces, and at 300 faces the inner start left 12 invalid stars. From a parabolic circle (radius R, between
  // R - r and R + r) they stay within the resampling bounds. The same on an uploaded sampled torus, where the
  // P-Hex meshes had 91-97 % hexagons over twelve sizes from 1000 to 13000 faces, and now 100 %.
  for (const bool uploaded : {false, true}) {
    for (const int faces : {300, 1000, 2000}) {
      PipelineParams p;
      if (uploaded) p.mesh = sampledUpload("torus", 30000);
      else p.surface = "torus";
      p.method = TriangulationMethod::Prespecified;
      p.faces = faces;
      const TriangulationStage t = triangulate(p);
      INFO((uploaded ? "uploaded, " : "analytic, ") << faces << " faces: " << t.triangulation.notes.front());
      INFO("valence 6: " << t.check.regularFraction << ", invalid stars " << t.check.invalidStars.size());
      CHECK(t.triangulation.notes.front().find("among 4 candidates") != std::string::npos);
      CHECK(t.check.regularFraction >= 0.99);
      CHECK(t.check.invalidStars.empty());
      CHECK(t.check.coverage > 0.97);
    }
  }
}

TEST_CASE("pipeline: a guarded solve that stalls is run unguarded, and kept where no face crosses itself") {
  // Method 1 on a cyclide patch past its parabolic circles: the fold guard stalls the solve from both duals
  // (the faces there only pass through crossed shapes on their way to planar ones); unguarded it converges
  // with no face crossing itself.
  const PipelineResult r = runPipeline(progressiveCyclidePatch(260, 1500));
  INFO("planarity " << r.metrics.planarityMax << ", crossing " << r.metrics.selfIntersectingCount);
  CHECK(r.foldsAllowed);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  // A solve the guard does not stall keeps it.
  PipelineParams torus;
  torus.faces = 500;
  CHECK_FALSE(runPipeline(torus).foldsAllowed);
}

TEST_CASE("pipeline: a face far nearer planar than the worst is left to the next solve, not cut") {
  // The bumps at 2500 faces: after the first solve the faces off planar range from 1e-9 to 1e-3. Cutting them
  // all cut 81 interior faces (80.5 % hexagons); cutting those at least 1/100 as far off as the worst, and
  // solving again, cuts 39 and reaches the tolerance the same (83.4 %).
  PipelineParams p;
  p.surface = "freeform";
  p.method = TriangulationMethod::Prespecified;  // Method 2's systems of rows (auto lays the bumps globally)
  p.faces = 2500;
  const PipelineResult r = runPipeline(p);
  INFO(r.interiorFacesSplit << " interior faces cut, hexagons " << r.interiorHexagonFraction);
  REQUIRE(r.triangulation.systems > 1);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.interiorFacesSplit < 60);
  CHECK(r.interiorHexagonFraction > 0.82);
}

TEST_CASE("pipeline: on a surface laid in several systems, every face only folding would make planar is cut") {
  // The bumps at 1000 faces: along the seams and where rows run along the parabolic rings, some 30 interior
  // faces stall off planar (the solve stopped at planarity 1e-3 before); each is cut along its best diagonal,
  // and the mesh reaches the tolerance with no face crossing itself. Without the cuts it stalls.
  PipelineParams p;
  p.surface = "freeform";
  p.method = TriangulationMethod::Prespecified;  // Method 2's systems of rows (auto lays the bumps globally)
  p.faces = 1000;
  const PipelineResult r = runPipeline(p);
  INFO("planarity " << r.metrics.planarityMax << ", " << r.interiorFacesSplit << " interior faces and "
                    << r.boundaryPanelsSplit << " panels cut, hexagons " << r.interiorHexagonFraction);
  REQUIRE(r.triangulation.systems > 1);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.interiorFacesSplit > 8);  // more than the few cut on a surface of one system
  CHECK(r.interiorFacesSplit < 0.05 * r.hex.faceCount());
  CHECK(r.interiorHexagonFraction > 0.7);
  // This coarse the distance goal is met narrowly: 0.161 % of the diagonal (at 800 faces the bumps' panels
  // stay 0.203 % off, the farthest node where the surface fit's shifts fold faces; docs/METHOD.md). Whether
  // the fit applies here turns on round-off: which faces are cut depends on their planarity against 1/100 of
  // the worst (kCutBelowWorst), and native code cuts 12 interior faces, whose mesh the fit brings from 0.164 %
  // to 0.161 %, where WebAssembly cuts 14, whose mesh is at 0.161 % unfitted.
  CHECK(r.metrics.surfaceDistanceMax <= 0.002);
  p.splitBoundaryPanels = false;
  const PipelineResult whole = runPipeline(p);
  CHECK_FALSE(whole.solve.converged);
  CHECK(whole.metrics.planarityMax > 1e-6);
  // At 3000 faces the fit folds faces too and is kept once the shifts around them are undone: 0.056 % ->
  // 0.034 % of the diagonal. The same natively and in wasm.
  p.splitBoundaryPanels = true;
  p.faces = 3000;
  const PipelineResult finer = runPipeline(p);
  CHECK(finer.solve.converged);
  CHECK(finer.solve.surfaceFitted);
  CHECK(finer.solve.surfaceDistanceAfter < 0.7 * finer.solve.surfaceDistanceBefore);
  CHECK(finer.metrics.surfaceDistanceMax <= 0.002);
}

TEST_CASE("pipeline: a surface fit left past the distance goal takes a node's planes from its polygons alone") {
  // The bumps at 1200 faces (at 1500 before the analytic surfaces' trigonometry was made portable, see
  // portable_math.hpp): the farthest nodes sit among the triangles that cuts leave. Counted among its planes,
  // those triangles gave a node four or more and held it and its polygons' planes; the last try takes a node's
  // planes from its faces of four corners or more and keeps its triangles from turning over: 0.245 % -> 0.190 %.
  PipelineParams p;
  p.surface = "freeform";
  p.method = TriangulationMethod::Prespecified;  // Method 2's systems of rows (auto lays the bumps globally)
  p.faces = 1200;
  const PipelineResult r = runPipeline(p);
  INFO("distance " << r.metrics.surfaceDistanceMax << ", " << r.interiorFacesSplit << " interior faces cut");
  REQUIRE(r.triangulation.systems > 1);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.solve.surfaceFitted);
  CHECK(r.metrics.surfaceDistanceMax <= 0.002);
}

TEST_CASE("pipeline: a surface with umbilics is laid in several systems, and the note names one") {
  // The free-form bumps: their tops are umbilics inside parabolic rings, where no regular conjugate
  // network exists (§7). The rows from L0 cover about half of it (45 % at 2000 faces); further systems
  // seeded in what they left uncovered, and the seams between them, cover the rest. The note says where and why.
  PipelineParams p;
  p.surface = "freeform";
  p.method = TriangulationMethod::Prespecified;  // Method 2's systems of rows (auto lays the bumps globally)
  p.faces = 1000;
  const TriangulationStage t = triangulate(p);
  CHECK(t.triangulation.systems > 1);
  CHECK(t.check.coverage > 0.85);  // 0.89 (the first system alone: 0.46)
  CHECK(t.check.invalidStars.size() < 10);
  CHECK_NOTHROW(vertexRings(t.triangulation.mesh));
  // The systems and the seams between them do not overlap: over the square (the bumps are a height field) no
  // triangle's centroid lies inside another triangle, and every triangle keeps its orientation.
  const TriMesh& T = t.triangulation.mesh;
  auto xy = [&](int f, int c) { return Eigen::Vector2d(T.V(T.F(f, c), 0), T.V(T.F(f, c), 1)); };
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
  int flipped = 0, overlapping = 0;
  for (int f = 0; f < T.F.rows(); ++f) {
    flipped += cross(xy(f, 1) - xy(f, 0), xy(f, 2) - xy(f, 0)) <= 0;
    const Eigen::Vector2d c = (xy(f, 0) + xy(f, 1) + xy(f, 2)) / 3;
    for (int g = 0; g < T.F.rows(); ++g) {
      if (g == f) continue;
      bool inside = true;
      for (int k = 0; k < 3; ++k) inside = inside && cross(xy(g, (k + 1) % 3) - xy(g, k), c - xy(g, k)) > 0;
      overlapping += inside;
    }
  }
  CHECK(flipped == 0);
  CHECK(overlapping == 0);
  bool named = false;
  for (const std::string& n : t.triangulation.notes) named |= n.find("umbilic") != std::string::npos;
  CHECK(named);
  // The wave roof's curvature lines are regular: covered, and no such note.
  p.surface = "wave-roof";
  const TriangulationStage roof = triangulate(p);
  CHECK(roof.check.coverage > 0.9);
  CHECK(roof.triangulation.systems == 1);
  for (const std::string& n : roof.triangulation.notes) CHECK(n.find("umbilic") == std::string::npos);
}

TEST_CASE("pipeline: the uploaded bumps are laid without rows fanned across a region or stacked on each other") {
  // Sampled as 120k triangles (as the benchmark does), the bumps' rings around an umbilic shrink onto it: a
  // shrunk loop was zipped all around to the ring outside it, and a row resampled onto a fitted loop traced
  // around another region, so triangles spanned the region between (planarity 0.14 and a vertex 6.5 % of the
  // diagonal off the surface at 1000 faces).
  PipelineParams p;
  p.mesh = sampledUpload("freeform", 60000);
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  p.faces = 1000;
  const PipelineResult r = runPipeline(p);
  INFO("planarity " << r.metrics.planarityMax << ", distance " << r.metrics.surfaceDistanceMax << ", edges "
                    << r.check.edgeMean << " .. " << r.check.edgeMax);
  CHECK(r.triangulation.systems > 1);
  CHECK(r.check.coverage > 0.85);
  CHECK(r.check.edgeMax < 4 * r.check.edgeMean);
  CHECK(r.metrics.planarityMax < 0.02);
  CHECK(r.metrics.surfaceDistanceMax < 0.005);
}

TEST_CASE("pipeline: a clean solve left past the distance goal is solved from the other dual too") {
  // The uploaded bumps at 1000 faces, laid in several systems, start from the tangent dual; its solve converges
  // with no face crossing itself, but every surface fit folds faces at its farthest node, 0.211 % of the
  // diagonal off. From the Dupin dual the panels meet in other nodes: 0.188 %, within the goal (33 interior
  // faces cut against 29); under auto that one is kept.
  PipelineParams p;
  p.mesh = sampledUpload("freeform", 60000);
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  p.faces = 1000;
  p.duality = Duality::Tangent;
  const PipelineResult tangent = runPipeline(p);
  INFO("tangent: distance " << tangent.metrics.surfaceDistanceMax << ", " << tangent.interiorFacesSplit << " cut");
  REQUIRE(tangent.triangulation.systems > 1);
  REQUIRE(tangent.solve.converged);
  REQUIRE(tangent.metrics.selfIntersectingCount == 0);
  CHECK(tangent.metrics.surfaceDistanceMax > kSurfaceDistanceGoal);
  p.duality = Duality::Auto;
  const PipelineResult r = runPipeline(p);
  INFO("auto: " << dualityName(r.duality) << ", distance " << r.metrics.surfaceDistanceMax << ", "
                << r.interiorFacesSplit << " cut");
  CHECK(r.duality == Duality::Dupin);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.metrics.surfaceDistanceMax <= kSurfaceDistanceGoal);
  CHECK(r.interiorFacesSplit < 0.05 * r.hex.faceCount());
  CHECK(r.hex.faceCount() > 900);
}

TEST_CASE("pipeline: a boundary panel left off planar is cut in two, and the solve reaches the tolerance") {
  // On the helicoid laid at cell 0.043 (about 3800 faces; globally under auto, whose edges run along its asymptotic
  // helices and rulings) boundary panels have no planar shape that does not fold; every interior face becomes
  // planar. (Laid by Method 2's rows, a few where the rows reach the rims did so too.)
  PipelineParams p;
  p.surface = "helicoid";
  p.cell = 0.043;
  p.splitBoundaryPanels = false;
  p.relay = false;  // one lay, the same for both (trial lays would lay each again where its cuts left nodes of four)
  const PipelineResult whole = runPipeline(p);
  INFO("whole: planarity " << whole.metrics.planarityMax);
  REQUIRE_FALSE(whole.solve.converged);
  CHECK(whole.boundaryPanelsSplit == 0);
  p.splitBoundaryPanels = true;
  const PipelineResult cut = runPipeline(p);
  INFO("cut: " << cut.boundaryPanelsSplit << " panels, planarity " << cut.metrics.planarityMax);
  CHECK(cut.solve.converged);
  CHECK(cut.metrics.planarityMax <= 1e-9);
  CHECK(cut.metrics.selfIntersectingCount == 0);
  CHECK(cut.boundaryPanelsSplit >= 1);
  // (The clip's fillers, appended after the panels, are counted apart: where they go depends on the planes; so
  // are the boundary panels it removed, lying wholly outside the curve.)
  const int fillersWhole = whole.boundaryClip.fillers - whole.boundaryClip.removed,
            fillersCut = cut.boundaryClip.fillers - cut.boundaryClip.removed;
  CHECK(cut.hex.faceCount() - fillersCut == whole.hex.faceCount() - fillersWhole + cut.boundaryPanelsSplit);
  // The bookkeeping follows the pieces: one entry per face, the extra faces on the boundary.
  REQUIRE(cut.dual.boundaryFace.size() == static_cast<std::size_t>(cut.hex.faceCount()));
  REQUIRE(cut.dual.faceVertex.size() == static_cast<std::size_t>(cut.hex.faceCount()));
  CHECK(cut.initial.faceCount() == cut.hex.faceCount() - fillersCut);
  int boundaryWhole = 0, boundaryCut = 0;
  for (auto b : whole.dual.boundaryFace) boundaryWhole += b;
  for (auto b : cut.dual.boundaryFace) boundaryCut += b;
  CHECK(boundaryCut - fillersCut == boundaryWhole - fillersWhole + cut.boundaryPanelsSplit);
  CHECK(cut.interiorHexagonFraction == Approx(whole.interiorHexagonFraction));
}

TEST_CASE("pipeline: where the solve from the Dupin dual stalls, the tangent dual is solved from as well") {
  // The cyclide's lattice runs along its curvature lines, a conjugate network: the tangent dual's faces lie in
  // their vertices' tangent planes, planar as they stand, while the solve from the Dupin dual stalls at 2e-7
  // near the parabolic circles (and reaches the tolerance only by cutting the faces left off). Under auto
  // the tangent dual wins, uncut, and says so; asked for, Dupin stays.
  PipelineParams p;
  p.surface = "cyclide";
  p.cell = cellForFaceCount(*makeSurface("cyclide"), 3000);  // the lattice at this cell (at 3000 faces asked the
                                                             // count's second lay takes a finer one, which converges)
  p.duality = Duality::Dupin;
  p.splitBoundaryPanels = false;
  const PipelineResult stalled = runPipeline(p);
  INFO("dupin uncut: planarity " << stalled.metrics.planarityMax);
  REQUIRE_FALSE(stalled.solve.converged);
  p.splitBoundaryPanels = true;
  const PipelineResult dupin = runPipeline(p);
  INFO("dupin: planarity " << dupin.metrics.planarityMax << ", " << dupin.interiorFacesSplit << " faces cut");
  CHECK(dupin.duality == Duality::Dupin);
  CHECK((!dupin.solve.converged || dupin.interiorFacesSplit > 0));
  p.duality = Duality::Auto;
  const PipelineResult r = runPipeline(p);
  INFO("auto: " << dualityName(r.duality) << ", planarity " << r.metrics.planarityMax);
  CHECK(r.duality == Duality::Tangent);
  CHECK(r.interiorFacesSplit == 0);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.metrics.surfaceDistanceMax < 0.002);
  CHECK(r.hex.faceCount() == stalled.hex.faceCount());
  // Where the solve from the Dupin dual reaches the tolerance, auto is Dupin.
  p.cell = 0;
  p.faces = 2000;
  const PipelineResult small = runPipeline(p);
  CHECK(small.solve.converged);
  CHECK(small.duality == Duality::Dupin);
  CHECK(std::string(dualityName(Duality::Auto)) == "auto");
  CHECK(parseDuality("auto") == Duality::Auto);
  try {  // a bad name is named, with the choices
    parseDuality("dupn");
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::InvalidParameter);
    CHECK(std::string(e.what()).find("'dupn'") != std::string::npos);
    CHECK(std::string(e.what()).find("'auto'") != std::string::npos);
  }
}

TEST_CASE("pipeline: a few interior faces left off planar away from the boundary are cut in two as well") {
  // A Dupin cyclide sampled as 56k triangles (open along its parameter seams), uploaded and tiled at 2500
  // faces: the solve stops short with two interior faces off planar, away from every boundary panel, where
  // only folding would make them planar. They are cut along their best diagonals, and the solve goes on to
  // the tolerance without folding a face. (At 1500 faces five were off until the Dupin dual was untangled
  // where faces crossed themselves; now that size converges whole.)
  PipelineParams p;
  p.mesh = sampledUpload("cyclide", 30000);
  p.faces = 2500;
  p.duality = Duality::Dupin;  // the cut alone (under auto the tangent dual converges whole here)
  p.splitBoundaryPanels = false;
  const PipelineResult whole = runPipeline(p);
  INFO("whole: planarity " << whole.metrics.planarityMax);
  REQUIRE_FALSE(whole.solve.converged);
  int interiorOff = 0;
  for (int f = 0; f < whole.hex.faceCount(); ++f)
    interiorOff += !whole.dual.boundaryFace[f] && whole.metrics.planarity[f] > p.tolerance;
  REQUIRE(interiorOff >= 1);
  REQUIRE(interiorOff <= 8);
  p.splitBoundaryPanels = true;
  const PipelineResult cut = runPipeline(p);
  INFO("cut: " << cut.interiorFacesSplit << " interior faces, " << cut.boundaryPanelsSplit << " panels, planarity "
               << cut.metrics.planarityMax);
  CHECK(cut.solve.converged);
  CHECK(cut.metrics.planarityMax <= 1e-9);
  CHECK(cut.metrics.selfIntersectingCount == 0);
  CHECK(cut.interiorFacesSplit >= 1);
  CHECK(cut.hex.faceCount() == whole.hex.faceCount() + cut.boundaryPanelsSplit + cut.interiorFacesSplit);
  // The pieces of an interior face are interior faces of the same vertex.
  REQUIRE(cut.dual.boundaryFace.size() == static_cast<std::size_t>(cut.hex.faceCount()));
  REQUIRE(cut.dual.faceVertex.size() == static_cast<std::size_t>(cut.hex.faceCount()));
  int boundaryWhole = 0, boundaryCut = 0;
  for (auto b : whole.dual.boundaryFace) boundaryWhole += b;
  for (auto b : cut.dual.boundaryFace) boundaryCut += b;
  CHECK(boundaryCut == boundaryWhole + cut.boundaryPanelsSplit);
  CHECK(cut.interiorHexagonFraction < whole.interiorHexagonFraction);
}

TEST_CASE("pipeline: a solve that stalls with more than a few interior faces off planar has them cut") {
  // The sampled cyclide laid coarsely (cell 0.23, about 900 faces): the lay leaves a dozen invalid stars,
  // and the solve stalls near 1e-4 with more interior faces off planar than the few-faces rule cuts. Having
  // stalled, it cuts every one of them and converges without folding a face.
  PipelineParams p;
  p.mesh = sampledUpload("cyclide", 30000);
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  p.cell = 0.23;
  p.duality = Duality::Dupin;
  p.splitBoundaryPanels = false;
  const PipelineResult whole = runPipeline(p);
  INFO("whole: planarity " << whole.metrics.planarityMax << ", iterations " << whole.solve.iterations);
  REQUIRE_FALSE(whole.solve.converged);
  REQUIRE(whole.solve.iterations < p.maxIterations);  // stalled, not capped
  int interiorOff = 0;
  for (int f = 0; f < whole.hex.faceCount(); ++f)
    interiorOff += !whole.dual.boundaryFace[f] && whole.metrics.planarity[f] > p.tolerance;
  INFO("interior faces off planar: " << interiorOff);
  REQUIRE(interiorOff > 8);
  REQUIRE(interiorOff <= whole.hex.faceCount() / 20);
  p.splitBoundaryPanels = true;
  const PipelineResult cut = runPipeline(p);
  INFO("cut: " << cut.interiorFacesSplit << " interior faces, planarity " << cut.metrics.planarityMax);
  CHECK(cut.solve.converged);
  CHECK(cut.metrics.selfIntersectingCount == 0);
  CHECK(cut.interiorFacesSplit > 8);
  CHECK(cut.interiorFacesSplit <= cut.hex.faceCount() / 20);
}

TEST_CASE("pipeline: an interior face crossing itself next to a cut boundary panel is cut too") {
  // The sampled cyclide at about 120 faces: a planar interior pentagon crossing itself touched a boundary
  // panel that was cut, and was left whole (it was cut only where some face off planar lay away from the
  // panels). Every face crossing itself is now cut, again where its pieces still cross.
  PipelineParams p;
  p.mesh = sampledUpload("cyclide", 30000);
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  p.faces = 122;
  const PipelineResult r = runPipeline(p);
  INFO("planarity " << r.metrics.planarityMax << ", cuts " << r.interiorFacesSplit << " + " << r.boundaryPanelsSplit);
  CHECK(r.solve.converged);
  CHECK(r.metrics.selfIntersectingCount == 0);
}

TEST_CASE("pipeline: rows ending on an uploaded mesh's boundary keep its P-Hex vertices on the mesh") {
  // The wave roof sampled by its lattice (60k vertices) has a zigzag boundary polyline along two of its sides:
  // every other lattice row ends half a lattice step short, about 0.2 cell at 10000 faces. Method 2's rows end
  // on the boundary there; an edge between two row ends joined along the boundary has its P-Hex vertex at about
  // its midpoint, which between two teeth of the zigzag lies off the mesh. Such ends stay unjoined (measured:
  // distance 6.0e-5 of the diagonal, 3.6e-5 with rows ending short of the boundary, 1.3e-3 with every end
  // joined; coverage 0.980, was 0.968; shortest triangulation edge 0.51 of the mean, no interior face cut —
  // at the cell the area estimate gave. The cell the start trial predicts lays 9800 vertices, not 10700:
  // shortest edge 0.45 of the mean.) Method 2 named: its rows leave a spot 2.2 mean panel edges bare here, so auto
  // tiles this upload by the global method now.
  PipelineParams p;
  p.mesh = sampledUpload("wave-roof", 60000);
  p.method = TriangulationMethod::Prespecified;
  p.faces = 10000;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes << "coverage " << r.check.coverage << ", distance " << r.metrics.surfaceDistanceMax << ", edges "
             << r.check.edgeMin / r.check.edgeMean << " of the mean, interior faces cut " << r.interiorFacesSplit);
  CHECK(r.solve.converged);
  CHECK(r.metrics.selfIntersectingCount == 0);
  // (Up to 2.1e-4 where the clip's filler corners stand on the curve, projected onto their panels' planes.)
  CHECK(r.metrics.surfaceDistanceMax < 3e-4);
  CHECK(r.check.coverage > 0.975);
  CHECK(r.check.edgeMin >= 0.4 * r.check.edgeMean);
  CHECK(r.interiorFacesSplit == 0);
  CHECK(notes.find("row ends moved onto the boundary") != std::string::npos);
}

TEST_CASE("pipeline: the count loop's third lay follows the counts only where they follow the cell") {
  // Counts that scale like a covering (vertices ~ cell^-2): the measured exponent, lay again.
  const double c0 = 0.02, n0 = 12000;
  const double c1 = c0 * std::sqrt(12000.0 / 10000.0), n1 = n0 * std::pow(c1 / c0, -2.1);
  const std::optional<double> smooth = phex::thirdLayExponent(c0, n0, c1, n1, 1.12);
  REQUIRE(smooth);
  CHECK(*smooth == Approx(2.1));
  // The uploaded bumps at 100k faces: 117k then 111k vertices, exponent 0.8, the closer lay 10.5 % over.
  CHECK_FALSE(phex::thirdLayExponent(0.010104, 117453, 0.0109214, 110503, 1.105));
  // The same lays missing by more than 15 %: a third lay, with the exponent kept within [0.5, 4].
  const std::optional<double> far = phex::thirdLayExponent(0.010104, 117453, 0.0109214, 110503, 1.19);
  REQUIRE(far);
  CHECK(*far == Approx(0.78).margin(0.01));
  // Steep counts lie on both sides of the count asked for, and the third lay falls between them, however
  // close the closer lay: the analytic bumps at 4000 faces, 4553 then 2828 vertices (exponent 7.4), 14 % off.
  const std::optional<double> steep = phex::thirdLayExponent(0.0541574, 4553, 0.0577799, 2828, 1.138);
  REQUIRE(steep);
  CHECK(*steep == 4.0);
}

TEST_CASE("pipeline: a lay again keeps its cell within a factor 2 of the area estimate's") {
  // Scaled by the square root of the count's ratio where the exponent is 2.
  CHECK(phex::relayCell(0.1, 12000, 10000, 2.0, 0.1) == Approx(0.1 * std::sqrt(1.2)));
  // A lay that stopped short (6 vertices for 64 asked) with a flat exponent (0.5) would send the cell down by
  // the square of the ratio, 1/114, and lay 350k triangles (an uploaded cyclide): half the estimate's at most.
  CHECK(phex::relayCell(0.3, 6, 64, 0.5, 0.25) == Approx(0.125));
  CHECK(phex::relayCell(0.1, 1e6, 64, 2.0, 0.1) == Approx(0.2));
}

TEST_CASE("pipeline: an uploaded dome is laid along plane sections, not around its umbilic") {
  // A paraboloid of revolution: its apex is an umbilic, and its curvature lines (meridians and parallels) turn
  // around it. Laid along them, the rows need several systems, whose seams leave irregular vertices and
  // invalid stars. The sections by parallel planes standing on the dome, with their conjugate lines, are a
  // conjugate network without a singularity: method auto picks them there.
  PipelineParams p;
  p.mesh = sampledUpload("elliptic-paraboloid", 20000, {{"ra", 1.0}, {"rb", 1.0}});
  p.faces = 1500;
  const TriangulationStage chosen = triangulate(p);
  CHECK(chosen.field == "section");
  CHECK(chosen.triangulation.systems == 1);
  CHECK(chosen.check.invalidStars.empty());
  CHECK(chosen.check.regularFraction >= 0.95);
  CHECK(chosen.check.coverage > 0.85);
  bool named = false;
  for (const std::string& n : chosen.triangulation.notes)
    named |= n.find("plane sections") != std::string::npos && n.find("umbilic") != std::string::npos;
  CHECK(named);
  // Asked for by name, the curvature lines are laid as asked, and show why.
  p.method = TriangulationMethod::Prespecified;
  const TriangulationStage principal = triangulate(p);
  CHECK(principal.field == "principal");
  CHECK(principal.triangulation.systems > 1);
  CHECK(principal.check.regularFraction < chosen.check.regularFraction);
  // The whole pipeline on the sections: planar, all hexagons inside.
  p.method = TriangulationMethod::Auto;
  const PipelineResult r = runPipeline(p);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.interiorHexagonFraction >= 0.95);
  CHECK(r.metrics.surfaceDistanceMax <= 0.002);
}

TEST_CASE("pipeline: a hill laid from its top grows its rows from a ring, not a loop of a few cells") {
  // A Gaussian hill: an umbilic at the top (the middle of the bounds, where L0 starts), hyperbolic around.
  // Its curvature lines close into rings around the top; at 5000 faces the one through the start was a loop
  // of three samples, whose first layers folded onto each other ("the layers fold ... ask for more faces").
  PipelineParams p;
  p.mesh = heightFieldUpload("hill", 80, [](double x, double y) { return 0.6 * std::exp(-1.2 * (x * x + y * y)); });
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  p.faces = 5000;
  const TriangulationStage t = triangulate(p);
  const std::string notes = allNotes(t.triangulation);
  INFO(notes);
  CHECK(notes.find("L0 moved") != std::string::npos);
  CHECK(t.check.coverage > 0.9);
  CHECK(t.check.invalidStars.size() <= 5);
  CHECK(t.triangulation.mesh.V.rows() > 4000);
  CHECK(t.triangulation.mesh.V.rows() < 6000);
}

TEST_CASE("pipeline: Method 2 keeps its rows along the zero-curvature direction on a surface without umbilics") {
  // The whole cyclide at 1000 faces: the trial lays of the family along the parabolic circles scored poorly,
  // and the other family's trial, across both circles (Fig. 19's infeasible way), scored higher; its full lay
  // stopped at 6e-3 (exit 2). The other family is for surfaces with an umbilic in their curved part (bumps).
  PipelineParams p;
  p.surface = "cyclide";
  p.method = TriangulationMethod::Prespecified;
  p.faces = 1000;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK(notes.find("across the zero-curvature direction") == std::string::npos);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
}

TEST_CASE("pipeline: a start choice does not take overlapping triangles for coverage") {
  // Half a cyclide ring, closed around its tube, by Method 1: one family's trial laid triangles over each
  // other (coverage 1.39 at 2500 faces), scored higher than a lay that covers less without overlap, and won;
  // its P-Hex mesh did not converge and lay 20 % of the diagonal off the surface.
  const TriangulationStage t = triangulate(progressiveCyclidePatch(360, 2500));
  CHECK(t.check.coverage < 1.05);
  CHECK(t.check.coverage > 0.8);
}

TEST_CASE("pipeline: a cushion with saddle corners is laid along plane sections too") {
  // An umbilic in the middle, saddles at the corners: the curvature lines need four systems of rows (79 %
  // hexagons at 1500 faces); the sections still bend mostly one way, and lay it whole.
  PipelineParams p;
  p.mesh = heightFieldUpload("cushion", 80, [](double x, double y) {
    return 0.5 * std::cos(3.14159265358979 * x / 2.2) * std::cos(3.14159265358979 * y / 2.2);
  });
  p.faces = 1500;
  const TriangulationStage t = triangulate(p);
  CHECK(t.field.rfind("section", 0) == 0);
  CHECK(t.triangulation.systems == 1);
  CHECK(t.check.invalidStars.empty());
  CHECK(t.check.regularFraction >= 0.95);
  CHECK(t.check.coverage > 0.85);
}

TEST_CASE("pipeline: a noisy upload is laid from curvature fitted over wider rings, and the notes say so") {
  // A saddle whose heights are jittered by up to 12 % of an edge (a rough scan). Fitted over 2-rings its
  // curvature was mostly noise, and the lay failed ("a segment of the base curve runs along an asymptotic
  // direction"); a dome so jittered covered 1 % of itself.
  const int n = 120;
  auto jitter = [](int i, int j) {
    std::uint32_t h = std::uint32_t(i) * 73856093u ^ std::uint32_t(j) * 19349663u;
    h ^= h >> 15, h *= 2246822519u, h ^= h >> 13, h *= 3266489917u, h ^= h >> 16;
    return h / 2147483648.0 - 1.0;
  };
  PipelineParams p;
  p.mesh = heightFieldUpload("rough-saddle", n, [&](double x, double y) {
    const int i = int(std::lround((x + 1) * n / 2)), j = int(std::lround((y + 1) * n / 2));
    return 0.3 * (x * x - y * y) + 0.002 * jitter(i, j);
  });
  p.faces = 1500;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK(notes.find("the uploaded mesh is noisy") != std::string::npos);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.interiorHexagonFraction >= 0.9);
}

TEST_CASE("pipeline: a developable is tiled along its rulings, its hexagons planar as laid (§3, §5.3)") {
  // The dual gives the vertices of each ruling one shared tangent plane, so every hexagon lies in one plane
  // with its quad-shaped outline and the solve has nothing to do. The local solver used to stall on Method 2's
  // lays at 1e-6 (cylinder) to 1e-3 (cone), and Method 1 on a cone, whose rows drifted off the fanning
  // rulings, left 9-11 % of the faces other than hexagons, unconverged.
  for (const std::string surface : {"cylinder", "cone"}) {
    for (const TriangulationMethod method : {TriangulationMethod::Prespecified, TriangulationMethod::Progressive}) {
      PipelineParams p;
      p.surface = surface;
      p.method = method;
      p.faces = 2500;
      const PipelineResult r = runPipeline(p);
      INFO(surface << " by " << triangulationMethodName(method));
      CHECK(r.method == TriangulationMethod::Prespecified);
      checkPlanarAsLaid(r);
      if (method == TriangulationMethod::Progressive) {
        REQUIRE_FALSE(r.triangulation.notes.empty());
        CHECK(r.triangulation.notes.front().find("no ideal triangles on a developable") != std::string::npos);
      }
    }
  }
}

TEST_CASE("pipeline: a corrugated vault, a developable with inflections, is planar as laid") {
  // z = 0.25 sin(pi y) + 0.12 sin(2 pi y): rulings along x, and an inflection of the profile at y = 0 (and near
  // y = +-0.7), whose ruling is made of planar points (no zero-curvature direction of their own: they borrow
  // their neighbours') and whose neighbouring rulings' planes are nearly parallel (they share one plane).
  // Before, 800, 1000, 1500 and 2000 faces stopped at 2e-7 to 9e-6; then 1500 still left 4 faces crossing
  // themselves (and 500 stopped at 1e-2), until the planar points' directions came from their neighbours'
  // rulings (MeshSurface) and no longer turned the rows about the inflections.
  PipelineParams p;
  p.mesh = heightFieldUpload("corrugated", 100, [](double, double y) {
    return 0.25 * std::sin(3.14159265358979 * y) + 0.12 * std::sin(2 * 3.14159265358979 * y);
  });
  for (const int faces : {1000, 1500}) {
    p.faces = faces;
    const PipelineResult r = runPipeline(p);
    INFO(faces << " faces");
    checkPlanarAsLaid(r);
    CHECK(r.check.coverage > 0.95);
  }
}

TEST_CASE("pipeline: a developable whose middle is an inflection ruling starts L0 on a curved ruling") {
  // A wavy vault, z = 0.25 (sin pi (y + 1) + 0.5 sin 2 pi (y + 1)): the middle of the bounds lies on the
  // inflection ruling y = 0, all planar points, whose principal directions are arbitrary: L0 ran across the
  // rulings there and no solve converged (1e-2 at 2000 and 5000 faces). It starts on the nearest clearly
  // curved ruling now, and says so.
  PipelineParams p;
  p.mesh = heightFieldUpload("wavy-vault", 100, [](double, double y) {
    return 0.25 * (std::sin(3.14159265358979 * (y + 1)) + 0.5 * std::sin(2 * 3.14159265358979 * (y + 1)));
  });
  for (const int faces : {2000, 5000}) {
    p.faces = faces;
    const PipelineResult r = runPipeline(p);
    const std::string notes = allNotes(r.triangulation);
    INFO(faces << " faces\n" << notes);
    CHECK(notes.find("is a planar point of the developable") != std::string::npos);
    checkPlanarAsLaid(r);
    CHECK(r.check.coverage > 0.95);
  }
}

TEST_CASE("pipeline: a vault on a flat apron, a developable with planar points, is planar as laid") {
  // z = 0 for y < -0.3, then a circular bend of radius 1.5. The apron's points are planar: they used to be
  // taken as umbilics, whose rows followed the meridians about the middle (in arcs, laid as a second system),
  // and their vertices kept a plane each in the dual; 1000 and 3000 faces stopped at 8e-6 and 1.5e-4 (exit 2).
  // Now they carry the rulings of the bend (along x), and the apron's rows share its plane.
  PipelineParams p;
  p.mesh = heightFieldUpload("vault-on-apron", 100, [](double, double y) {
    return y < -0.3 ? 0.0 : 1.5 - std::sqrt(1.5 * 1.5 - (y + 0.3) * (y + 0.3));
  });
  for (const int faces : {1000, 3000}) {
    p.faces = faces;
    const PipelineResult r = runPipeline(p);
    INFO(faces << " faces\n" << allNotes(r.triangulation));
    CHECK(r.triangulation.systems == 1);
    checkPlanarAsLaid(r);
    CHECK(r.check.coverage > 0.95);
  }
}

TEST_CASE("pipeline: a run on the same upload reuses its MeshSurface, with the same result") {
  clearUploadCache();
  PipelineParams p;
  p.mesh = heightFieldUpload("dome", 40, [](double x, double y) { return 0.4 - 0.2 * (x * x + y * y); });
  p.faces = 300;
  const PipelineResult first = runPipeline(p);
  CHECK_FALSE(first.surfaceReused);
  const PipelineResult again = runPipeline(p);
  CHECK(again.surfaceReused);
  CHECK(again.surface == first.surface);  // the very object
  REQUIRE(again.hex.V.rows() == first.hex.V.rows());
  CHECK(again.hex.V == first.hex.V);  // bit for bit
  CHECK(surfacePreview(p).mesh.V == dynamic_cast<const MeshSurface&>(*first.surface).mesh().V);
  CHECK(runPipeline(p).surfaceReused);  // the preview kept it too
  // Other bytes, or the same bytes under another name (it names the surface in the notes): built anew.
  PipelineParams other = p;
  other.mesh = heightFieldUpload("dome", 40, [](double x, double y) { return 0.4 - 0.21 * (x * x + y * y); });
  CHECK_FALSE(runPipeline(other).surfaceReused);
  CHECK_FALSE(runPipeline(p).surfaceReused);  // one upload is kept at a time
  other = p;
  other.mesh->name = "dome-2.obj";
  CHECK_FALSE(runPipeline(other).surfaceReused);
  clearUploadCache();
  CHECK_FALSE(runPipeline(other).surfaceReused);
  // A malformed upload is not kept (the one before was let go as it was read).
  PipelineParams bad = p;
  bad.mesh->bytes.resize(bad.mesh->bytes.size() / 2);
  bad.mesh->bytes.insert(bad.mesh->bytes.end(), {'f', ' ', '9', '9', '9', '9', '9', ' ', '1', ' ', '2', '\n'});
  CHECK_THROWS_AS(runPipeline(bad), Error);
  CHECK_FALSE(runPipeline(other).surfaceReused);
  CHECK(runPipeline(other).surfaceReused);
  clearUploadCache();
}

TEST_CASE("pipeline: an upload with a crease says where it is, and a smooth or merely folded one says nothing") {
  // A gable roof: two planes meeting at a ridge turning by 44 degrees. No tangent plane there (§3), and a panel
  // across it cannot be planar; before, the run only stopped short of planarity (exit 2), with no word why.
  PipelineParams p;
  p.mesh = heightFieldUpload("gable", 60, [](double, double y) { return 0.4 - 0.4 * std::abs(y); });
  p.faces = 300;
  const TriangulationStage gable = triangulate(p);
  const std::string notes = allNotes(gable.triangulation);
  INFO(notes);
  CHECK(notes.find("the uploaded mesh has a crease: 60 edges") != std::string::npos);
  CHECK(notes.find("the sharpest by 44") != std::string::npos);
  // A smooth vault, and the same with vertices pushed past their neighbours in the plan (a broken grid, not a
  // ridge): its triangles fold back over each other, turning by nearly 180 degrees. No crease either way.
  for (const bool folded : {false, true}) {
    const int n = 60;
    p.mesh = gridUpload("vault", n, [&](double x, double y) {
      const long i = std::lround((x + 1) * n / 2), j = std::lround((y + 1) * n / 2);
      if (folded && j % 10 == 5 && i % 10 == 5) x += 1.6 * 2.0 / n;
      return Vec3(x, y, 0.5 - 0.3 * y * y);
    });
    const MeshSurface surface(readMeshBytes(p.mesh->bytes.data(), p.mesh->bytes.size(), "obj", "vault.obj"));
    CHECK(surface.creases().edges == 0);
    const std::string smooth = allNotes(triangulate(p).triangulation);
    INFO(smooth);
    CHECK(smooth.find("crease") == std::string::npos);
  }
}

TEST_CASE("pipeline: a coarse upload laid finer than its triangles is laid on a smooth surface near its vertices") {
  // A dome sampled 8 x 8 (128 triangles, edges of 0.25) at 3000 faces (a cell of about 0.04): on its flat
  // facets the solve stalled at 3.3e-3 (exit 2), and a 12 x 12 dome at 3000 faces ended 0.21 % of the diagonal
  // off. Laid on the refined surface: planar, every interior face a hexagon, near the dome itself.
  clearUploadCache();
  const auto dome = [](double x, double y) { return 0.5 - 0.25 * (x * x + y * y); };
  PipelineParams p;
  p.mesh = heightFieldUpload("sketch", 8, dome);
  p.relay = false;  // auto's rows as they are (at 2000 faces they leave a corner bare: with relay, tiled globally)
  p.faces = 3000;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK(notes.find("the uploaded mesh is coarse for this lay") != std::string::npos);
  // Triangles of 0.279 (triangleSize), a cell of 0.0407: split 14 x 14 for edges of half a cell at most, or up to
  // three times finer where the global method's field mesh then splits them to nearer its own edge (refinementFor).
  const std::size_t split = notes.find(" triangles split ");
  REQUIRE(split != std::string::npos);
  const int k = std::stoi(notes.substr(split + 17));
  CHECK(k >= 14);
  CHECK(k <= 17);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.interiorHexagonFraction >= 0.99);
  CHECK(r.metrics.surfaceDistanceMax < 0.002);
  const double diagonal = std::sqrt(2.0 * 2 * 2 + 0.5 * 0.5 * 0.25);
  double offDome = 0;  // the P-Hex nodes against the function the sketch sampled
  for (Eigen::Index v = 0; v < r.hex.V.rows(); ++v) {
    const Vec3 x = r.hex.V.row(v);
    if (std::max(std::abs(x.x()), std::abs(x.y())) < 1) offDome = std::max(offDome, std::abs(x.z() - dome(x.x(), x.y())));
  }
  CHECK(offDome < 0.002 * diagonal);
  // The refined surface is kept with the upload: the same run again reuses both, to the bit.
  const PipelineResult again = runPipeline(p);
  CHECK(again.surfaceReused);
  CHECK(again.hex.V == r.hex.V);
  // A mesh as fine as the lay is laid as it is.
  p.mesh = heightFieldUpload("survey", 60, dome);
  CHECK(allNotes(triangulate(p).triangulation).find("coarse") == std::string::npos);
  // A low-poly hemisphere: its facets turn by 30 degrees at the rim, three times their median turn, which is
  // no crease. Refined, without a crease note (on its facets it stopped short of planarity, exit 2).
  p.mesh = heightFieldUpload("low-poly", 8, [](double x, double y) { return std::sqrt(std::max(0.0, 2.05 - x * x - y * y)); });
  p.faces = 1000;
  p.relay = true;
  const MeshSurface lowPoly(readMeshBytes(p.mesh->bytes.data(), p.mesh->bytes.size(), "obj", "low-poly.obj"));
  CHECK(lowPoly.creases().edges > 0);
  CHECK_FALSE(lowPoly.creases().sharp());
  const PipelineResult hemisphere = runPipeline(p);
  const std::string hemisphereNotes = allNotes(hemisphere.triangulation);
  INFO(hemisphereNotes);
  CHECK(hemisphereNotes.find("laid on a smooth surface near its 81 vertices") != std::string::npos);
  CHECK(hemisphereNotes.find("crease") == std::string::npos);
  CHECK(hemisphere.solve.converged);
  // Method 2's rows (along plane sections) left a part of it bare, so the global method tiled it: covered, at
  // 94 % hexagons where the rows had 98 %.
  CHECK(hemisphere.method == TriangulationMethod::Global);
  CHECK(hemisphere.coverageGap <= kCoverageGapGoal);
  CHECK(hemisphere.interiorHexagonFraction >= 0.9);
  // A steep dome sampled 4 x 4: its fits around a corner span most of it, and their blend by barycentric weights
  // creased by 120 degrees (laid on its facets then); their smooth blend does not: laid on it, planar, 90 %
  // hexagons, 0.09 % of the diagonal off it.
  p.mesh = heightFieldUpload("steep", 4, [](double x, double y) { return 1 - 0.8 * (x * x + y * y); });
  const PipelineResult steep = runPipeline(p);
  const std::string steepNotes = allNotes(steep.triangulation);
  INFO(steepNotes);
  CHECK(steepNotes.find("laid on a smooth surface near its 25 vertices") != std::string::npos);
  CHECK(steep.metrics.planarityMax <= 1e-9);
  CHECK(steep.interiorHexagonFraction >= 0.85);
  CHECK(steep.metrics.surfaceDistanceMax <= kSurfaceDistanceGoal);
  // Steeper still (1 - 3 r^2, falling by 3 over the half-width), even the smooth blend turns far
  // between neighbouring triangles: laid on its facets, and the note says why.
  p.mesh = heightFieldUpload("steeper", 4, [](double x, double y) { return 1 - 3 * (x * x + y * y); });
  CHECK(allNotes(triangulate(p).triangulation).find("too coarse to be refined smoothly") != std::string::npos);
  clearUploadCache();
}

// A triangle mesh as uploaded OBJ bytes.
MeshInput objUpload(const TriMesh& m, const std::string& name) {
  const std::string obj = toObj(m);
  return MeshInput{std::vector<std::uint8_t>(obj.begin(), obj.end()), "obj", name + ".obj"};
}

TEST_CASE("pipeline: an uploaded closed convex polyhedron coarser than the lay is tiled as §7's control mesh") {
  // The egg control (12 vertices, 20 faces) uploaded under method auto: before, Method 2 covered 8 % of its
  // facets (exit 1, "the mesh is noisy"). Now its Loop limit surface is tiled, as method subdivision does.
  PipelineParams p;
  p.mesh = objUpload(eggControl(1.5, 0.8), "pebble");
  p.faces = 600;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK(r.method == TriangulationMethod::Subdivision);
  CHECK(notes.find("closed convex polyhedron of 12 vertices") != std::string::npos);
  CHECK(r.solve.converged);
  CHECK(r.metrics.facesBySize.at(5) == 12);
  CHECK(r.metrics.facesBySize.size() == 2);  // pentagons and hexagons only
  CHECK(r.metrics.selfIntersectingCount == 0);
  // Not taken so: a polyhedron that is not convex (the egg with its pole pushed in), or with a method named
  // (whose lays fail on the facets: their errors, or notes, say nothing of a polyhedron).
  auto route = [](const PipelineParams& q) {
    try {
      return allNotes(triangulate(q).triangulation);
    } catch (const Error& e) {
      return std::string(e.what());
    }
  };
  TriMesh dented = eggControl(1.5, 0.8);
  dented.V.row(0) *= 0.3;
  p.mesh = objUpload(dented, "dented");
  CHECK(route(p).find("polyhedron") == std::string::npos);
  p.mesh = objUpload(eggControl(1.5, 0.8), "pebble");
  p.method = TriangulationMethod::Prespecified;
  CHECK(route(p).find("polyhedron") == std::string::npos);
  clearUploadCache();
}

TEST_CASE("pipeline: a surface fit left past the distance goal is tried again with more faces frozen") {
  // The uploaded cyclide at 1500 faces: the fit's shifts fold faces next to the farthest node, and freezing
  // the folded faces alone, then their neighbours, left it 0.24 % of the diagonal off. Tried again with the
  // neighbours frozen at once: 0.18 %.
  PipelineParams p;
  p.mesh = sampledUpload("cyclide", 60000);
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  p.faces = 1500;
  const PipelineResult r = runPipeline(p);
  CHECK(r.solve.converged);
  CHECK(r.solve.surfaceFitted);
  CHECK(r.metrics.surfaceDistanceMax < 0.002);
  clearUploadCache();
}

TEST_CASE("pipeline: a control mesh in site coordinates is subdivided about its centre") {
  // The egg control 5400 km from the origin, by method subdivision and as a polyhedron under auto: in the
  // file's coordinates the solve stalled at planarity 5e-8 (exit 2), where the egg at the origin converges.
  // Both now compute about its centre and give the egg at the origin's mesh, moved to the site.
  const Vec3 site(512345.678, 5432109.876, 250.0);
  TriMesh egg = eggControl(1.5, 0.8), far = egg;
  far.V.rowwise() += site.transpose();
  PipelineParams p;
  p.faces = 600;
  p.method = TriangulationMethod::Subdivision;
  p.mesh = objUpload(egg, "pebble");
  const PipelineResult home = runPipeline(p);
  REQUIRE(home.solve.converged);
  for (const TriangulationMethod method : {TriangulationMethod::Subdivision, TriangulationMethod::Auto}) {
    p.method = method;
    p.mesh = objUpload(far, "pebble-on-site");
    const PipelineResult away = runPipeline(p);
    INFO(triangulationMethodName(method) << ": planarity " << away.metrics.planarityMax);
    CHECK(away.method == TriangulationMethod::Subdivision);
    const Vec3 centre = 0.5 * (egg.V.colwise().minCoeff() + egg.V.colwise().maxCoeff()).transpose();
    CHECK((away.origin - (site + centre)).norm() < 1e-6);  // the centre of its box
    CHECK(away.solve.converged);
    CHECK(away.metrics.planarityMax <= 1e-9);
    REQUIRE(away.hex.V.rows() == home.hex.V.rows());
    CHECK(((away.hex.V.rowwise() - site.transpose()) - home.hex.V).cwiseAbs().maxCoeff() < 1e-6);
    CHECK((triangulate(p).triangulation.mesh.V.colwise().mean().transpose() - site).norm() < 1);
  }
  clearUploadCache();
}

TEST_CASE("pipeline: a vertex filled in on a closed row stays between its neighbours") {
  // A torus sampled 24 x 12, refined, at 1000 faces (cells of 0.27): a closed row's missing apex was filled in
  // at the middle of the arc between its neighbours, whose arcs had come out a hair in the wrong order, so on
  // the far side of the loop: five triangles 3.2 long spanned the hole, and a P-Hex node lay 0.8 off the
  // surface (9.8 % of the diagonal). Now no edge of the lay is over 4 cells (the edge collapses against folds
  // next to the parabolic circles leave edges of up to about 3 cells: 3.05 here).
  std::ostringstream obj;
  obj << std::fixed;
  obj.precision(9);
  const int nu = 24, nv = 12;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv, r = 2 + 0.8 * std::cos(v);
      obj << "v " << r * std::cos(u) << ' ' << r * std::sin(u) << ' ' << 0.8 * std::sin(v) << '\n';
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int a = j * nu + i + 1, b = j * nu + (i + 1) % nu + 1, c = (j + 1) % nv * nu + (i + 1) % nu + 1,
                d = (j + 1) % nv * nu + i + 1;
      obj << "f " << a << ' ' << b << ' ' << c << "\nf " << a << ' ' << c << ' ' << d << '\n';
    }
  const std::string text = obj.str();
  PipelineParams p;
  p.mesh = MeshInput{std::vector<std::uint8_t>(text.begin(), text.end()), "obj", "low-poly-torus.obj"};
  p.faces = 1000;
  const PipelineResult r = runPipeline(p);
  const TriMesh& t = r.triangulation.mesh;
  const double cell = cellForFaceCount(*r.surface, 1000);
  double longest = 0;
  for (Eigen::Index f = 0; f < t.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (t.V.row(t.F(f, k)) - t.V.row(t.F(f, (k + 1) % 3))).norm());
  INFO("longest edge " << longest << ", cell " << cell);
  CHECK(longest < 4 * cell);
  CHECK(r.farNodes == 0);
  clearUploadCache();
}

TEST_CASE("pipeline: P-Hex nodes far off the surface are counted and named") {
  // Off by over 1 % of the diagonal and a mean edge. A rounded box at 8000 faces had one 19 % off, converged
  // and planar (a vertex filled in across a loop); 20 hexagons on a torus bulge off it by over 1 % but by
  // less than their size.
  PolyMesh square;
  square.V.resize(4, 3);
  square.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  square.addFace({0, 1, 2, 3});
  CHECK(farNodeDistance(square, 10.0) == Approx(0.1));   // a mean edge of 1 on a diagonal of 10
  CHECK(farNodeDistance(square, 1000.0) == kFarNodeDistance);
  int farthest = -1;
  CHECK(countFarNodes({0.001, 0.2, 0.05, 0.3}, 0.1, &farthest) == 2);
  CHECK(farthest == 3);
  CHECK(countFarNodes({0.001, 0.002}, 0.1, &farthest) == 0);
  // A good result has none and no such note; the torus's 20 hexagons have none either.
  PipelineParams p;
  p.mesh = heightFieldUpload("dome", 40, [](double x, double y) { return 0.4 - 0.2 * (x * x + y * y); });
  p.faces = 300;
  const PipelineResult near = runPipeline(p);
  CHECK(near.farNodes == 0);
  CHECK(allNotes(near.triangulation).find("off the surface, the farthest") == std::string::npos);
  PipelineParams coarse;
  coarse.surface = "torus";
  coarse.cell = cellForFaceCount(*makeSurface("torus"), 12);  // 20 faces (12 asked: 12 faces, 0.1 % off)
  const PipelineResult twelve = runPipeline(coarse);
  CHECK(twelve.metrics.surfaceDistanceMax > kFarNodeDistance);
  CHECK(twelve.farNodes == 0);
  clearUploadCache();
}

// A closed ellipsoid with semi-axes a, b, c as an uploaded OBJ: nu meridians, nv - 1 parallels and two poles.
MeshInput closedEllipsoidUpload(int nu, int nv, double a, double b, double c) {
  std::ostringstream obj;
  obj.precision(17);
  obj << "v 0 0 " << c << '\n';
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = kPi * j / nv, ph = 2 * kPi * i / nu;
      obj << "v " << a * std::sin(th) * std::cos(ph) << ' ' << b * std::sin(th) * std::sin(ph) << ' ' << c * std::cos(th) << '\n';
    }
  obj << "v 0 0 " << -c << '\n';
  const int south = 1 + (nv - 1) * nu + 1;
  auto id = [&](int j, int i) { return 2 + (j - 1) * nu + i % nu; };  // 1-based
  for (int i = 0; i < nu; ++i) obj << "f 1 " << id(1, i) << ' ' << id(1, i + 1) << '\n';
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i)
      obj << "f " << id(j, i) << ' ' << id(j + 1, i) << ' ' << id(j + 1, i + 1) << "\nf " << id(j, i) << ' '
          << id(j + 1, i + 1) << ' ' << id(j, i + 1) << '\n';
  for (int i = 0; i < nu; ++i) obj << "f " << south << ' ' << id(nv - 1, i + 1) << ' ' << id(nv - 1, i) << '\n';
  const std::string text = obj.str();
  return MeshInput{std::vector<std::uint8_t>(text.begin(), text.end()), "obj", "ellipsoid.obj"};
}

TEST_CASE("pipeline: an uploaded closed convex surface is tiled as §7 has it: hexagons and 12 pentagons") {
  // Method 2 laid an uploaded ellipsoid (four umbilics) at 3000 faces in two systems with eight zipped seams,
  // overlapping itself (coverage 1.09), 86 % hexagons, 0.35 % of the diagonal off. The geodesic icosahedron
  // mapped onto it has valence 6 everywhere but at 12 vertices, whose faces are the pentagons Euler's formula
  // asks for (§7, Figure 21 right).
  PipelineParams p;
  p.mesh = closedEllipsoidUpload(160, 80, 1.5, 1.0, 0.7);
  for (const int faces : {1000, 3000}) {
    p.faces = faces;
    const PipelineResult r = runPipeline(p);
    INFO(faces << " faces\n" << allNotes(r.triangulation));
    CHECK(r.method == TriangulationMethod::Subdivision);
    CHECK(r.check.invalidStars.empty());
    CHECK(r.metrics.facesBySize.at(5) == 12);
    CHECK(r.metrics.facesBySize.at(6) == r.metrics.faceCount - 12);
    CHECK(std::abs(r.metrics.faceCount - faces) < 0.1 * faces);
    CHECK(r.solve.converged);
    CHECK(r.solve.iterations <= 12);  // the paper's claim from the Dupin dual: about 10
    CHECK(r.metrics.selfIntersectingCount == 0);
    CHECK(r.metrics.surfaceDistanceMax < 0.002);
  }
  // A closed surface of genus 1 (a torus) is laid by Method 2 as before.
  p.mesh = sampledUpload("torus", 6000);
  p.faces = 1000;
  CHECK(triangulate(p).method == TriangulationMethod::Prespecified);
}

TEST_CASE("pipeline: an uploaded sloping plane is tiled in straight rows of hexagons, planar as laid") {
  // Any hexagon tiling of a plane is planar (§3). Its principal directions are undefined; the fits' round-off
  // (1e-14) gave the principal field directions of its own, meridians through one point under the umbilics'
  // convention: 104 triangles of no area at 3000 faces, 71 % hexagons, stopped at 6e-4 (exit 2); and Method 1
  // laid 91 % hexagons from ideal triangles of that round-off.
  PipelineParams p;
  p.mesh = heightFieldUpload("slope", 60, [](double x, double y) { return 0.3 * x + 0.2 * y; });
  for (const TriangulationMethod method : {TriangulationMethod::Auto, TriangulationMethod::Progressive})
    for (const int faces : {500, 3000}) {
      p.method = method;
      p.faces = faces;
      const PipelineResult r = runPipeline(p);
      const std::string notes = allNotes(r.triangulation);
      INFO(triangulationMethodName(method) << ", " << faces << " faces\n" << notes);
      CHECK(r.solve.iterations == 0);  // planar as laid (to the 12 digits the upload's heights are written with)
      CHECK(r.metrics.planarityMax <= 1e-10);
      CHECK(r.interiorHexagonFraction == 1.0);
      CHECK(r.triangulation.systems == 1);
      if (method == TriangulationMethod::Auto) {
        CHECK(r.field == "section");
        CHECK(notes.find("the uploaded mesh is a plane") != std::string::npos);
      }
    }
}

TEST_CASE("pipeline: an upload in site coordinates, far from the origin, is tiled as at the origin") {
  // A 20 m saddle roof in survey coordinates, some 5400 km from the origin: there a unit in the last place is
  // 9e-10, 3e-8 of an edge, and the solve stalled at 4e-9 (exit 2) on a lay that differed from the same roof's
  // at the origin. It is computed about the centre of its box now, and comes back in the file's coordinates.
  const Vec3 site(512345.678, 5432109.876, 250.0);
  auto upload = [&](const Vec3& shift, double scale) {
    return gridUpload("roof", 80, [&](double x, double y) { return Vec3(scale * Vec3(x, y, 0.3 * (x * x - y * y)) + shift); },
                      [](double, double) { return true; }, 17);
  };
  PipelineParams p;
  p.faces = 4000;
  p.mesh = upload(Vec3::Zero(), 10);
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  const PipelineResult home = runPipeline(p);
  p.mesh = upload(site, 10);
  p.method = TriangulationMethod::Prespecified;  // Method 2's machinery (auto takes global here)
  const PipelineResult away = runPipeline(p);
  CHECK(home.origin == Vec3::Zero());
  CHECK((away.origin - site).norm() < 1e-6);
  CHECK(away.solve.converged);
  CHECK(away.metrics.planarityMax <= 1e-9);
  CHECK(away.metrics.faceCount == home.metrics.faceCount);
  CHECK(away.interiorHexagonFraction == home.interiorHexagonFraction);
  // The same mesh in the file's frame, up to what the file's last digits change in the lay (a step of the flow
  // lines' control accepted or not): within 1 % of an edge.
  REQUIRE(away.hex.V.rows() == home.hex.V.rows());
  const double edge = home.metrics.edgeLengthMean;
  CHECK(((away.hex.V.rowwise() - site.transpose()) - home.hex.V).cwiseAbs().maxCoeff() < 0.01 * edge);
  CHECK(((away.triangulation.mesh.V.rowwise() - site.transpose()) - home.triangulation.mesh.V).cwiseAbs().maxCoeff() <
        0.01 * edge);
  const std::string notes = allNotes(away.triangulation);
  INFO(notes);
  CHECK(notes.find("near (512345.678, 5432109.876, 250)") != std::string::npos);  // the start, where the file has it
  // The preview, and the triangulation stage alone, in the file's coordinates too.
  CHECK((surfacePreview(p).mesh.V.colwise().mean().transpose() - site).norm() < 1);
  const TriangulationStage t = triangulate(p);
  CHECK((t.triangulation.mesh.V.colwise().mean().transpose() - site).norm() < 1);
  // A start point is given in the file's coordinates.
  p.start = site + Vec3(5, 5, 0);
  CHECK(allNotes(runPipeline(p).triangulation).find("through (512350.") != std::string::npos);
}

TEST_CASE("pipeline: the panels around a hole in an uploaded mesh keep to its rim") {
  // A saddle with a round hole off its middle, cut out of the grid (a jagged rim). The triangulation's
  // boundary edges there are chords across the hole: the dual points of those edges, and the triangles' points
  // moved back behind them, lay inside the hole, 0.31 % of the diagonal off the surface at 2000 faces and
  // 0.15 % at 4000. Now they are placed by the rim beside the chord.
  // Method 2 keeps them within 0.1 % of the diagonal; the global method, which auto takes for this upload (its
  // trial lays took several systems of rows), within the goal of 0.2 % (0.15 % at 4000 faces).
  PipelineParams p;
  p.mesh = heightFieldUpload(
      "saddle-with-hole", 80, [](double x, double y) { return 0.3 * (x * x - y * y); },
      [](double x, double y) { return std::hypot(x - 0.2, y) > 0.3; });
  for (const TriangulationMethod method : {TriangulationMethod::Prespecified, TriangulationMethod::Auto})
    for (const int faces : {2000, 4000}) {
      p.method = method;
      p.faces = faces;
      const PipelineResult r = runPipeline(p);
      INFO(triangulationMethodName(r.method) << ", " << faces << " faces\n" << allNotes(r.triangulation));
      CHECK(r.solve.converged);
      CHECK(r.metrics.selfIntersectingCount == 0);
      CHECK(r.metrics.surfaceDistanceMax < (r.method == TriangulationMethod::Global ? kSurfaceDistanceGoal : 0.001));
    }
}

TEST_CASE("pipeline: an uploaded cylinder or cone is a developable too, planar as laid") {
  // Their estimated curvature keeps a trace of the vanishing one (1e-5 to 1e-3 of the other): taken as 0
  // (MeshSurface::developable). Before, every lay had layers at the lower bound (ideal steps of a few
  // hundredths of a cell), 60-90 % hexagons, and no solve converged (1e-5 to 1e-2).
  for (const std::string surface : {"cylinder", "cone"}) {
    PipelineParams p;
    p.mesh = sampledUpload(surface, 15000);
    p.faces = 2500;
    const PipelineResult r = runPipeline(p);
    const std::string notes = allNotes(r.triangulation);
    INFO(surface << "\n" << notes);
    CHECK(notes.find("the uploaded mesh is a developable") != std::string::npos);
    checkPlanarAsLaid(r);
  }
}

// An upload laid under auto (`laid`, from `p`) tiled by the global method, as `--method global` tiles it; its notes.
std::string checkLaidGlobally(PipelineParams p, const TriangulationStage& laid) {
  CHECK(laid.method == TriangulationMethod::Global);
  p.method = TriangulationMethod::Global;
  const TriangulationStage global = triangulate(p);
  CHECK(laid.triangulation.mesh.V == global.triangulation.mesh.V);
  CHECK(laid.triangulation.mesh.F == global.triangulation.mesh.F);
  return allNotes(laid.triangulation);
}

// Under auto an upload is laid by Method 2 where one system of its rows covers it, and globally where its trial
// lays take several; one quick lay (about 250 faces) first, and where that takes several systems of rows too
// (the bumps' umbilics: every principal network needs several), the trial lays are skipped. The result is the
// global method's, bit for bit; an upload of the wave roof, which one system covers, runs the trials and keeps
// Method 2.
TEST_CASE("pipeline: under auto, an upload whose quick trial lay takes several systems of rows goes global without the trials") {
  PipelineParams p;
  p.mesh = sampledUpload("freeform", 20000);
  p.faces = 2000;
  const std::string notes = checkLaidGlobally(p, triangulate(p));
  INFO(notes);
  CHECK(notes.find("a trial lay at about 250 faces took") != std::string::npos);
  CHECK(notes.find("start chosen among") == std::string::npos);
  p.mesh = sampledUpload("wave-roof", 20000);
  const TriangulationStage rows = triangulate(p);
  INFO(allNotes(rows.triangulation));
  CHECK(rows.method == TriangulationMethod::Prespecified);
  CHECK(allNotes(rows.triangulation).find("a trial lay at about") == std::string::npos);
}

// Where the curvature lines' trial lays take several systems of rows and plane sections are in question (an
// umbilic, sections bending mostly one way), the sections' trials run only where one quick lay along them takes
// one system: on PH-CPF's intersection shell it cannot be laid, and the shell is tiled globally at once.
TEST_CASE("pipeline: under auto, plane sections whose quick lay cannot cover an upload are not tried at full size") {
  std::ifstream in(PHEX_TEST_DATA "/phcpf_intersection.off", std::ios::binary);
  PipelineParams p;
  p.mesh = MeshInput{std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {}), "off", "phcpf_intersection.off"};
  p.faces = 2000;
  const std::string notes = checkLaidGlobally(p, triangulate(p));
  INFO(notes);
  // The curvature lines' trial lays took several systems (2 on the barycentric blend of the refinement, 6 on the
  // smooth one); the count is the surface's.
  CHECK(notes.find("systems of rows (no singularity-free conjugate network covers the upload") != std::string::npos);
  CHECK(notes.find("a lay along plane sections could not be laid") != std::string::npos);
}

// Under auto an upload that one system of rows covers is laid by Method 2, but where its rows stop short and
// leave part of the upload bare (the sampled ellipsoid band: a hole over three triangle edges wide), the global
// method tiles it instead and covers it; an upload whose rows end about an edge short of its boundary (the
// sampled hyperboloid) keeps Method 2.
TEST_CASE("pipeline: under auto, an upload that Method 2's rows leave partly bare is tiled by the global method") {
  PipelineParams p;
  p.mesh = sampledUpload("ellipsoid", 20000);
  p.faces = 1000;
  const PipelineResult bare = runPipeline(p);
  const std::string notes = allNotes(bare.triangulation);
  INFO(notes);
  CHECK(bare.method == TriangulationMethod::Global);
  CHECK(notes.find("stopped short there") != std::string::npos);
  CHECK(bare.coverageGap <= kCoverageGapGoal);
  CHECK(bare.metrics.planarityMax <= 1e-9);
  CHECK(bare.metrics.selfIntersectingCount == 0);
  // Where the rows cover the upload to within the goal they stay (a cylinder sampled: 100 % hexagons); where
  // their panels leave a spot farther than a mean panel edge from any panel (the hyperboloid sampled, at 1000
  // faces; its rows' own check passes them), the global method tiles it again and is kept.
  p.mesh = sampledUpload("cylinder", 20000);
  const PipelineResult covered = runPipeline(p);
  INFO(allNotes(covered.triangulation));
  CHECK(covered.method == TriangulationMethod::Prespecified);
  CHECK_FALSE(covered.relay.tried);
  CHECK(covered.coverageGap <= kCoverageGapGoal);
  p.mesh = sampledUpload("hyperboloid", 20000);
  const PipelineResult relaid = runPipeline(p);
  INFO(allNotes(relaid.triangulation));
  CHECK(allNotes(relaid.triangulation).find("stopped short there") == std::string::npos);
  CHECK(relaid.relay.tried);
  CHECK(relaid.relay.globally);
  CHECK(relaid.relay.kept);
  CHECK(relaid.relay.firstCoverageGap > kCoverageGapGoal);
  CHECK(relaid.method == TriangulationMethod::Global);
  CHECK(relaid.coverageGap <= kCoverageGapGoal);
  CHECK(relaid.metrics.planarityMax <= 1e-9);
  CHECK(relaid.metrics.selfIntersectingCount == 0);
  // With relay off the rows stand.
  p.relay = false;
  CHECK(runPipeline(p).method == TriangulationMethod::Prespecified);
  // Rows that reach a P-Hex mesh only by cutting faces (the vase sampled with 6000 vertices, at 3000 faces: boundary
  // panels cut where its rows end on the rims): the global method's, whose cuts make fewer nodes of four, is kept.
  p.relay = true;
  p.mesh = sampledUpload("vase", 6000);
  p.faces = 3000;
  const PipelineResult cut = runPipeline(p);
  INFO(allNotes(cut.triangulation));
  CHECK(cut.relay.globally);
  CHECK(cut.relay.firstNodesOfFour > 0);
  CHECK(cut.relay.kept);
  CHECK(cut.method == TriangulationMethod::Global);
  CHECK(2 * cut.interiorFacesSplit + cut.boundaryPanelsSplit < cut.relay.firstNodesOfFour);
  CHECK(cut.coverageGap <= kCoverageGapGoal);
}
