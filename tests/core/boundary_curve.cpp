// phex — the surfaces' boundary curves, and the P-Hex mesh's boundary nodes put on them.
#include <catch.hpp>

#include <cmath>

#include "phex/boundary_curve.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/pipeline.hpp"
#include "phex/surfaces.hpp"

using namespace phex;

namespace {

// The unit square in z = 0 as two triangles, the surface above it.
TriMesh unitSquare() {
  TriMesh m;
  m.V.resize(4, 3);
  m.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 0, 2, 3;
  return m;
}

}  // namespace

TEST_CASE("boundary curve: nearest point, and the offset across the surface without the height over it") {
  const MeshSurface square(unitSquare());
  const std::vector<std::vector<Vec3>> loops = square.boundaryCurves();
  REQUIRE(loops.size() == 1);
  CHECK(loops[0].size() == 4);
  const BoundaryCurve curve(loops, 0.5);
  const auto [point, distance] = curve.nearest(Vec3(0.5, -0.1, 0.3));
  CHECK((point - Vec3(0.5, 0, 0)).norm() < 1e-12);
  CHECK(distance == Approx(std::sqrt(0.1)));
  std::vector<int> near;
  curve.near(Vec3(0.5, -0.1, 0.3), near);
  const BoundaryCurve::Offset o = curve.offset(Vec3(0.5, -0.1, 0.3), near, square);
  CHECK(o.across == Approx(0.1));  // the height 0.3 over the surface left out
  CHECK(std::abs(o.normal.z()) == Approx(1.0));
  // Nothing within reach of a point far off: infinite, not a wrong nearest point.
  CHECK(std::isinf(curve.nearest(Vec3(40, 40, 40)).second));
}

TEST_CASE("boundary curve: an analytic surface's is its domain's edges in the directions that do not wrap") {
  CHECK(makeSurface("torus")->boundaryCurves().empty());
  const ParametricSurfacePtr band = makeSurface("sphere");  // a band of latitudes: u wraps, two rims
  const std::vector<std::vector<Vec3>> rims = band->boundaryCurves();
  REQUIRE(rims.size() == 2);
  for (const std::vector<Vec3>& rim : rims) {
    CHECK(rim.size() == ParametricSurface::kBoundarySamples);
    for (const Vec3& x : rim) CHECK(std::abs(x.z()) == Approx(std::sin(60.0 * M_PI / 180)).epsilon(1e-9));
  }
  const ParametricSurfacePtr patch = makeSurface("elliptic-paraboloid");  // a square patch: one loop of four sides
  const std::vector<std::vector<Vec3>> loop = patch->boundaryCurves();
  REQUIRE(loop.size() == 1);
  CHECK(loop[0].size() == 4 * ParametricSurface::kBoundarySamples);
  double step = 0;
  for (std::size_t i = 0; i < loop[0].size(); ++i) {
    const Vec3& x = loop[0][i];
    CHECK(std::max(std::abs(x.x()), std::abs(x.y())) == Approx(1.0).epsilon(1e-9));  // on the square's sides
    step = std::max(step, (loop[0][(i + 1) % loop[0].size()] - x).norm());
  }
  CHECK(step < 0.01);  // closed, in small steps (the last point joins the first)
}

TEST_CASE("pipeline: the boundary nodes end on the boundary curve, the panels as planar") {
  for (const std::string name : {"catenoid", "cyclide"}) {
    CAPTURE(name);
    PipelineParams p;
    p.surface = name;
    if (name == "catenoid") p.method = TriangulationMethod::Global;
    else p.surfaceParams["uSpan"] = 180;
    p.faces = 800;
    const PipelineResult r = runPipeline(p);
    REQUIRE(r.solve.converged);
    CHECK(r.metrics.planarityMax <= 1e-9);
    CHECK(r.boundaryOffset.nodes > 50);
    CHECK(r.solve.boundaryNodesPlaced > 20);  // the others on the curve already (the free nodes settled there)
    // In mean edges: every node on the catenoid; on the cyclide a few stay put where their line leaves the surface
    // steeply (a move may take no node farther off the surface than the farthest one).
    CHECK((name == "catenoid" ? r.boundaryOffset.max : r.boundaryOffset.median) <= 1e-3);
    // Without the surface fit (which places them) they lie beside the curve, as the dual put them.
    p.fitSurface = false;
    const PipelineResult raw = runPipeline(p);
    CHECK(raw.solve.boundaryNodesPlaced == 0);
    CHECK(raw.boundaryOffset.median > 0.01);
  }
  PipelineParams closed;
  closed.surface = "torus";
  closed.faces = 300;
  const PipelineResult r = runPipeline(closed);
  CHECK(r.boundaryOffset.nodes == 0);
  CHECK(r.solve.boundaryNodesPlaced == 0);
}
