#include <catch.hpp>
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>

#include "phex/duality.hpp"
#include "phex/error.hpp"
#include "phex/metrics.hpp"
#include "phex/planarize.hpp"
#include "phex/subdivision.hpp"

using namespace phex;

namespace {

constexpr double kPi = 3.141592653589793;

// Mean length of the triangles' edges (each interior edge counted twice).
double meanEdgeLength(const TriMesh& mesh) {
  double sum = 0;
  for (int f = 0; f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (mesh.V.row(mesh.F(f, k)) - mesh.V.row(mesh.F(f, (k + 1) % 3))).norm();
  return sum / (3.0 * mesh.F.rows());
}

// Valence -> number of vertices, over the vertices of a closed triangle mesh.
std::map<int, int> valenceHistogram(const TriMesh& mesh) {
  const VertexRings rings = vertexRings(mesh);
  std::map<int, int> histogram;
  for (std::size_t v = 0; v < rings.triangles.size(); ++v) {
    REQUIRE(rings.closed[v]);
    ++histogram[static_cast<int>(rings.triangles[v].size())];
  }
  return histogram;
}

// A flat 4 x 4 grid of unit squares in z = 0, each split along a diagonal: 16 boundary vertices, 9 inside.
TriMesh flatGrid() {
  TriMesh m;
  m.V.resize(25, 3);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 5; ++i) m.V.row(5 * j + i) << i, j, 0;
  m.F.resize(32, 3);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const int a = 5 * j + i;
      m.F.row(2 * (4 * j + i)) << a, a + 1, a + 6;
      m.F.row(2 * (4 * j + i) + 1) << a, a + 6, a + 5;
    }
  return m;
}

// A torus (genus 1) as an n x n grid wrapped both ways: convex edges nowhere matter, its topology is wrong.
TriMesh torusControl(int n) {
  TriMesh m;
  m.V.resize(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double u = 2 * kPi * i / n, v = 2 * kPi * j / n;
      m.V.row(n * j + i) << (2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v);
    }
  m.F.resize(2 * n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = n * j + i, b = n * j + (i + 1) % n, c = n * ((j + 1) % n) + (i + 1) % n, d = n * ((j + 1) % n) + i;
      m.F.row(2 * a) << a, b, c;
      m.F.row(2 * a + 1) << a, c, d;
    }
  return m;
}

struct RouteResult {
  SubdivisionTriangulation route;
  TriangulationCheck check;
  MeshMetrics metrics;
  PlanarizeReport solve;
  std::map<int, int> dualVertexValence;  // faces per dual vertex -> count
  double milliseconds[4] = {0, 0, 0, 0};  // subdivision + surface, check, dual, planarize
};

// §7 end to end: subdivide, check Proposition 4, Dupin dual, planarize with the default options, measure.
RouteResult runRoute(const TriMesh& control, int levels) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
  RouteResult r;
  auto t = Clock::now();
  r.route = subdivisionTriangulation(control, levels);
  r.milliseconds[0] = since(t);
  t = Clock::now();
  r.check = checkTriangulation(r.route.triangulation, *r.route.surface);
  r.milliseconds[1] = since(t);
  t = Clock::now();
  DualMesh dual = dupinDual(r.route.triangulation, *r.route.surface);
  r.milliseconds[2] = since(t);
  t = Clock::now();
  r.solve = planarize(dual.mesh, PlanarizeOptions{});
  r.milliseconds[3] = since(t);
  r.metrics = measure(dual.mesh);
  std::vector<int> facesAtVertex(dual.mesh.V.rows(), 0);
  for (int i : dual.mesh.indices) ++facesAtVertex[i];
  for (int n : facesAtVertex) ++r.dualVertexValence[n];
  return r;
}

// The claims of §7 for a convex control whose extraordinary vertices all have valence 5.
void requirePHexWithTwelvePentagons(const RouteResult& r) {
  const int hexagons = static_cast<int>(r.route.triangulation.mesh.V.rows()) - 12;
  CHECK(r.check.interiorValence == std::map<int, int>{{5, 12}, {6, hexagons}});
  CHECK(r.check.boundaryVertices == 0);
  CHECK(r.check.invalidStars.empty());    // Proposition 4: triangles contain their Dupin centres
  CHECK(r.check.parabolicStars.empty());  // convex: K > 0 at every vertex
  CHECK(r.metrics.facesBySize == std::map<int, int>{{5, 12}, {6, hexagons}});  // F5 - F7 = 12 (1 - 0)
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.dualVertexValence == std::map<int, int>{{3, r.metrics.vertexCount}});  // closed: no boundary
}

}  // namespace

TEST_CASE("subdivision: Loop's split keeps vertex ids and orientation, and counts V + E, 4F") {
  const TriMesh control = icosahedronControl(1.0);
  const TriMesh once = loopSubdivide(control, 1);
  CHECK(once.V.rows() == 12 + 30);
  CHECK(once.F.rows() == 80);
  const TriMesh twice = loopSubdivide(control, 2);
  CHECK(twice.V.rows() == 42 + 120);
  CHECK(twice.F.rows() == 320);
  // Even vertices keep their ids: vertex 0 (the +z pole, valence 5, neighbours at height 1/sqrt(5)) moves
  // along the axis to (1 - 5 beta) + 5 beta / sqrt(5) with Loop's beta (Warren's 3/40 would give 0.7927).
  const double c = 3.0 / 8.0 + std::cos(2 * kPi / 5) / 4, beta = (5.0 / 8.0 - c * c) / 5;
  CHECK(std::abs(once.V(0, 0)) < 1e-15);
  CHECK(once.V(0, 2) == Approx(1 - 5 * beta + 5 * beta / std::sqrt(5.0)));
  CHECK(once.V(0, 2) == Approx(0.76757).epsilon(1e-4));
  // Outward CCW triangles: positive volume.
  double volume = 0;
  for (int f = 0; f < twice.F.rows(); ++f)
    volume += twice.V.row(twice.F(f, 0)).dot(twice.V.row(twice.F(f, 1)).cross(twice.V.row(twice.F(f, 2)))) / 6;
  CHECK(volume > 0);
  CHECK(loopSubdivide(control, 0).V == control.V);
}

TEST_CASE("subdivision: regular interior masks, and boundary curves refine as cubic B-splines on their own") {
  TriMesh grid = flatGrid();
  // Lift the middle vertex: interior vertices near it rise, the boundary must not notice.
  grid.V(12, 2) = 1.0;
  const TriMesh sub = loopSubdivide(grid, 1);
  // Interior even vertex of valence 6: 5/8 v + 1/16 per neighbour (beta = 1/16).
  CHECK(sub.V(12, 2) == Approx(0.625));
  // Interior edge 12-13 (opposite vertices 7 and 18 in this grid): 3/8 (a + b) + 1/8 (c + d).
  bool foundEdge = false;
  for (int v = 25; v < sub.V.rows(); ++v)
    if (std::abs(sub.V(v, 0) - 2.5) < 1e-12 && std::abs(sub.V(v, 1) - 2.0) < 1e-12) {
      CHECK(sub.V(v, 2) == Approx(0.375));
      foundEdge = true;
    }
  CHECK(foundEdge);
  // Boundary vertex 2 (neighbours 1 and 3 along y = 0): 3/4 v + 1/8 (b0 + b1), no interior influence.
  for (int v = 0; v < sub.V.rows(); ++v)
    if (sub.V(v, 1) == 0.0) REQUIRE(sub.V(v, 2) == 0.0);
  // Cubic B-spline on the boundary: limit of vertex 0 (a corner, boundary neighbours 1 and 5) is 2/3 v + 1/6 (b0 + b1).
  const TriMesh limit = loopLimitPositions(grid);
  CHECK(limit.V(0, 0) == Approx(1.0 / 6.0));
  CHECK(limit.V(0, 1) == Approx(1.0 / 6.0));
  // Regular interior limit mask: 1/2 v + 1/12 per neighbour.
  CHECK(limit.V(12, 2) == Approx(0.5));
}

TEST_CASE("subdivision: limit points stay put under further subdivision, closed and open") {
  for (const TriMesh& control : {eggControl(1.4, 0.9), flatGrid()}) {
    const TriMesh coarse = loopLimitPositions(loopSubdivide(control, 1));
    const TriMesh fine = loopLimitPositions(loopSubdivide(control, 3));
    for (int v = 0; v < coarse.V.rows(); ++v) REQUIRE((coarse.V.row(v) - fine.V.row(v)).norm() < 1e-12);
  }
}

TEST_CASE("subdivision: limit normals from the tangent masks match a much finer mesh") {
  const TriMesh control = stretchedIcosahedronControl(Vec3(1.5, 1.0, 0.7));
  const TriMesh coarse = loopSubdivide(control, 1);
  const Points normals = loopLimitNormals(coarse);
  // The average of the face normals of the limit mesh four levels finer, around the same vertex.
  const TriMesh fine = loopLimitPositions(loopSubdivide(coarse, 4));
  const VertexRings rings = vertexRings(fine);
  double worstDegrees = 0;
  for (int v = 0; v < coarse.V.rows(); ++v) {
    Vec3 n = Vec3::Zero();
    for (int f : rings.triangles[v]) {
      const Vec3 a = fine.V.row(fine.F(f, 0)), b = fine.V.row(fine.F(f, 1)), c = fine.V.row(fine.F(f, 2));
      n += (b - a).cross(c - a).normalized();
    }
    const Vec3 exact = normals.row(v).transpose();
    CHECK(exact.dot(fine.V.row(v).transpose()) > 0);  // outward on a convex shape around the origin
    worstDegrees = std::max(worstDegrees, std::acos(std::min(1.0, exact.dot(n.normalized()))) * 180 / kPi);
  }
  CHECK(worstDegrees < 0.5);
  CHECK_THROWS_WITH(loopLimitNormals(flatGrid()), Catch::Contains("boundary"));
}

TEST_CASE("subdivision: Loop keeps a convex control convex, valence 6 except at the control's vertices") {
  for (const TriMesh& control :
       {icosahedronControl(2.0), stretchedIcosahedronControl(Vec3(1.6, 1.0, 0.6)), eggControl(1.5, 0.8)}) {
    REQUIRE_NOTHROW(checkConvexControl(control));
    for (int levels = 1; levels <= 4; ++levels) {
      const TriMesh sub = loopSubdivide(control, levels);
      // checkConvexControl names any reflex edge; the subdivided mesh and its limit points pass it.
      CHECK_NOTHROW(checkConvexControl(sub));
      CHECK_NOTHROW(checkConvexControl(loopLimitPositions(sub)));
      const std::map<int, int> valences = valenceHistogram(sub);
      CHECK(valences.at(5) == 12);
      CHECK(valences.at(6) == sub.V.rows() - 12);
    }
  }
}

TEST_CASE("subdivision: §7 on the icosahedron gives a valid P-Hex mesh with exactly 12 pentagons") {
  const RouteResult r = runRoute(icosahedronControl(1.0), 3);
  CHECK(r.route.levels == 3);
  CHECK(r.route.triangulation.mesh.V.rows() == 642);
  // The triangulation's vertices are vertices of the surface it is measured against.
  for (int v = 0; v < r.route.triangulation.mesh.V.rows(); ++v)
    REQUIRE((r.route.triangulation.mesh.V.row(v) - r.route.surface->mesh().V.row(v)).norm() < 1e-12);
  requirePHexWithTwelvePentagons(r);
}

TEST_CASE("subdivision: §7 on non-spherical convex controls (stretched, egg) gives 12 pentagons as well") {
  requirePHexWithTwelvePentagons(runRoute(stretchedIcosahedronControl(Vec3(1.6, 1.0, 0.6)), 3));
  requirePHexWithTwelvePentagons(runRoute(eggControl(1.5, 0.8), 3));
}

TEST_CASE("subdivision: controls the §7 route cannot tile are rejected, naming the problem") {
  TriMesh dented = icosahedronControl(1.0);
  dented.V.row(0) *= 0.3;  // pushes the pole below its five neighbours
  CHECK_THROWS_WITH(checkConvexControl(dented), Catch::Contains("not convex") && Catch::Contains("reflex edges, e.g. edge 0-"));
  CHECK_THROWS_WITH(subdivisionTriangulation(dented, 2), Catch::Contains("not convex"));

  TriMesh open = icosahedronControl(1.0);
  open.F.conservativeResize(19, 3);
  CHECK_THROWS_WITH(checkConvexControl(open), Catch::Contains("not closed") && Catch::Contains("3 boundary edges"));

  CHECK_THROWS_WITH(checkConvexControl(torusControl(6)),
                    Catch::Contains("not genus 0") && Catch::Contains("= 0 (genus 1)"));

  TriMesh two = icosahedronControl(1.0);
  two.V.conservativeResize(24, 3);
  two.V.bottomRows(12) = two.V.topRows(12).rowwise() + Eigen::RowVector3d(5, 0, 0);
  two.F.conservativeResize(40, 3);
  two.F.bottomRows(20) = two.F.topRows(20).array() + 12;
  CHECK_THROWS_WITH(checkConvexControl(two), Catch::Contains("2 connected components"));

  try {
    subdivisionTriangulation(open, 2);
    FAIL("an open control was accepted");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::CannotTile);
  }
  TriMesh nonManifold = icosahedronControl(1.0);
  nonManifold.F.row(1) = nonManifold.F.row(0);  // the same triangle twice
  CHECK_THROWS_WITH(loopSubdivide(nonManifold, 1), Catch::Contains("edge 0-1"));
}

TEST_CASE("subdivision: level counts follow the wanted size and stop at the memory limit") {
  const TriMesh control = eggControl(1.3, 1.0);
  for (double cell : {0.7, 0.5, 0.3, 0.2, 0.13, 0.1, 0.07, 0.05}) {
    const int levels = subdivisionLevels(control, 0, cell);
    const double meanEdge = meanEdgeLength(loopLimitPositions(loopSubdivide(control, levels)));
    INFO("cell " << cell << " levels " << levels << " mean edge " << meanEdge);
    // Each level about halves the edges, and the nearest level on a log scale is within a factor sqrt(2).
    CHECK(meanEdge > cell / std::sqrt(2.0) * 0.95);
    CHECK(meanEdge < cell * std::sqrt(2.0) * 1.05);
  }
  CHECK(subdivisionLevels(control, 642, 0) == 3);  // 12 + 30 + 120 + 480 vertices
  CHECK(subdivisionLevels(control, 2000, 0) == 4);  // 2562 is nearer than 642 on a log scale
  CHECK(subdivisionLevels(control, 1, 0) == 0);
  CHECK_THROWS_WITH(subdivisionLevels(control, 1000000, 0), Catch::Contains("memory limit"));
  CHECK_THROWS_WITH(subdivisionLevels(control, 0, 1e-4), Catch::Contains("cell 0.000100 is too small"));
  CHECK_THROWS_WITH(subdivisionTriangulation(control, 7), Catch::Contains("memory limit"));
  CHECK_THROWS_WITH(loopSubdivide(control, -1), Catch::Contains(">= 0"));
}

// Timings of the route at about 10k hexagons (hidden: run with "[perf]"); a measurement, with the
// same checks as the small cases.
TEST_CASE("subdivision: §7 route at 10k hexagons", "[.][perf]") {
  const TriMesh control = eggControl(1.5, 0.8);
  const auto start = std::chrono::steady_clock::now();
  const TriMesh surfaceMesh = loopLimitPositions(loopSubdivide(control, 5 + kSubdivisionSurfaceExtraLevels));
  const double subdivisionMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const RouteResult r = runRoute(control, 5);
  requirePHexWithTwelvePentagons(r);
  CHECK(surfaceMesh.F.rows() == r.route.surface->mesh().F.rows());
  std::cout << "§7 route, egg control, 5 levels: " << r.route.triangulation.mesh.V.rows() << " faces ("
            << r.route.surface->mesh().F.rows() << " surface triangles); subdivision + surface "
            << r.milliseconds[0] << " ms (Loop subdivision alone " << subdivisionMs << " ms), checkTriangulation " << r.milliseconds[1] << " ms, dupinDual "
            << r.milliseconds[2] << " ms, planarize " << r.milliseconds[3] << " ms (" << r.solve.iterations
            << " iterations); planarity " << r.metrics.planarityMax << ", self-intersecting "
            << r.metrics.selfIntersectingCount << "\n";
}
