#include <catch.hpp>

#include "phex/duality.hpp"
#include "phex/surfaces.hpp"
#include "phex/triangulation.hpp"

using namespace phex;

TEST_CASE("triangulation: lattice on the torus is closed and regular") {
  const SurfacePtr s = makeSurface("torus");
  const Triangulation t = latticeTriangulation(*s, cellForFaceCount(*s, 2000));
  const int nv = static_cast<int>(t.mesh.V.rows());
  CHECK(nv > 1600);
  CHECK(nv < 2400);
  CHECK(t.mesh.F.rows() == 2 * nv);  // Euler: V - E + F = 0 on a torus with valence 6
  const VertexRings rings = vertexRings(t.mesh);
  for (int v = 0; v < nv; ++v) {
    REQUIRE(rings.closed[v]);
    REQUIRE(rings.triangles[v].size() == 6);
  }
  // Vertices lie on the surface.
  for (int v = 0; v < nv; v += 97) CHECK((s->closestPoint(t.mesh.V.row(v).transpose()).point - t.mesh.V.row(v).transpose()).norm() < 1e-9);
}

TEST_CASE("triangulation: edge lengths follow the cell size") {
  const SurfacePtr s = makeSurface("sphere");
  const double h = 0.1;
  const Triangulation t = latticeTriangulation(*s, h);
  double sum = 0;
  int n = 0;
  for (int f = 0; f < t.mesh.F.rows(); ++f)
    for (int c = 0; c < 3; ++c, ++n) sum += (t.mesh.V.row(t.mesh.F(f, c)) - t.mesh.V.row(t.mesh.F(f, (c + 1) % 3))).norm();
  CHECK(sum / n == Approx(h).epsilon(0.2));
  // The sphere band has a boundary: its boundary vertices have open fans.
  const VertexRings rings = vertexRings(t.mesh);
  int open = 0;
  for (bool c : rings.closed) open += !c;
  CHECK(open > 0);
}
