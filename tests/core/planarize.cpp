#include <catch.hpp>
#include <cmath>

#include "phex/error.hpp"
#include "phex/metrics.hpp"
#include "phex/duality.hpp"
#include "phex/pipeline.hpp"
#include "phex/planarize.hpp"
#include "phex/surfaces.hpp"

using namespace phex;

TEST_CASE("planarize: a bent hexagon becomes planar and stays close") {
  PolyMesh m;
  m.V.resize(6, 3);
  for (int i = 0; i < 6; ++i) m.V.row(i) << std::cos(i * M_PI / 3), std::sin(i * M_PI / 3), (i % 2 ? 0.05 : -0.05);
  m.addFace({0, 1, 2, 3, 4, 5});
  const PolyMesh before = m;
  PlanarizeOptions o;
  const PlanarizeReport r = planarize(m, o);
  CHECK(r.converged);
  CHECK(r.initialPlanarityMax > 0.04);
  CHECK(measure(m).planarityMax <= 1e-9);
  CHECK((m.V - before.V).rowwise().norm().maxCoeff() < 0.1);
  CHECK(r.iterations >= 1);
  CHECK(r.log.back().planarityMax <= 1e-9);
}

TEST_CASE("planarize: bad options are rejected, cancel stops") {
  PolyMesh m;
  m.V = Points::Random(6, 3);
  m.addFace({0, 1, 2, 3, 4, 5});
  PlanarizeOptions o;
  o.tolerance = -1;
  CHECK_THROWS_WITH(planarize(m, o), Catch::Contains("tolerance"));
  o = {};
  o.mu = 1;
  CHECK_THROWS_WITH(planarize(m, o), Catch::Contains("surface"));
  o = {};
  CancelFlag cancel{true};
  try {
    planarize(m, o, {}, &cancel);
    FAIL("expected cancel");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::Cancelled);
  }
  m.V(0, 0) = std::nan("");
  CHECK_THROWS_WITH(planarize(m, PlanarizeOptions{}), Catch::Contains("non-finite"));
}

TEST_CASE("planarize: fixed vertices keep their place, the faces at them their planes, and the rest comes planar") {
  // A planar P-Hex mesh with a patch of its nodes pushed off their faces; the patch and two rings of faces around
  // it are solved again with the rest held, as the pipeline's rounds against folds do.
  PipelineParams p;
  p.surface = "torus";
  p.faces = 600;
  const PipelineResult r = runPipeline(p);
  REQUIRE(r.solve.converged);
  PolyMesh m = r.hex;
  const int nv = static_cast<int>(m.V.rows());
  const double h = m.meanEdgeLength();
  const Vec3 centre = m.vertex(0);
  std::vector<char> free(nv, 0);
  int pushed = 0;
  for (int v = 0; v < nv; ++v)
    if ((m.vertex(v) - centre).norm() < 1.2 * h) {
      free[v] = 1, ++pushed;
      m.V.row(v) += 0.15 * h * Vec3(std::sin(3.0 * v), std::cos(5.0 * v), std::sin(7.0 * v)).transpose();
    }
  REQUIRE(pushed >= 3);
  for (int ring = 0; ring < 2; ++ring) {
    std::vector<char> grown = free;
    for (int f = 0; f < m.faceCount(); ++f) {
      bool touches = false;
      for (int i = 0; i < m.faceSize(f); ++i) touches = touches || free[m.face(f)[i]];
      if (touches)
        for (int i = 0; i < m.faceSize(f); ++i) grown[m.face(f)[i]] = 1;
    }
    free.swap(grown);
  }
  std::vector<char> fixed(nv);
  for (int v = 0; v < nv; ++v) fixed[v] = !free[v];
  const PolyMesh before = m;
  REQUIRE(maxPlanarity(m) > 1e-3);
  PlanarizeOptions o;
  o.fitSurface = false;
  o.fixedVertices = &fixed;
  const PlanarizeReport rep = planarize(m, o);
  CHECK(rep.converged);
  CHECK(maxPlanarity(m) <= 1e-9);
  int moved = 0, held = 0;
  for (int v = 0; v < nv; ++v) {
    if (fixed[v]) held += m.V.row(v) == before.V.row(v);
    else moved += m.V.row(v) != before.V.row(v);
  }
  CHECK(held == std::count(fixed.begin(), fixed.end(), char(1)));
  CHECK(moved >= pushed);
  // Without the rim held, the same solve moves nodes all over the mesh.
  PolyMesh loose = before;
  o.fixedVertices = nullptr;
  planarize(loose, o);
  int away = 0;
  for (int v = 0; v < nv; ++v) away += fixed[v] && loose.V.row(v) != before.V.row(v);
  CHECK(away > 0);
  // Bad input: a mask of another size, or another solver.
  std::vector<char> wrong(nv + 1, 0);
  o.fixedVertices = &wrong;
  CHECK_THROWS_WITH(planarize(loose, o), Catch::Contains("one entry per vertex"));
  o.fixedVertices = &fixed;
  o.method = PlanarizeMethod::Planes;
  CHECK_THROWS_WITH(planarize(loose, o), Catch::Contains("local solver"));
}

TEST_CASE("planarize: the local solver keeps simple faces simple unless folds are allowed") {
  // The free-form surface's Method 2 triangulation has faces across its parabolic rings that only reach
  // planarity by folding: with folds prevented they stay simple and planarity stops short (and says so).
  PipelineParams p;
  p.surface = "freeform";
  const TriangulationStage t = triangulate(p);
  const DualMesh dual = dupinDual(t.triangulation, *t.surface);
  const int initialFolds = measure(dual.mesh).selfIntersectingCount;
  PlanarizeOptions o;
  o.surface = t.surface.get();
  PolyMesh guarded = dual.mesh, free = dual.mesh;
  const PlanarizeReport rg = planarize(guarded, o);
  o.preventFolds = false;
  const PlanarizeReport rf = planarize(free, o);
  const int guardedFolds = measure(guarded).selfIntersectingCount, freeFolds = measure(free).selfIntersectingCount;
  INFO("self-intersecting: initial " << initialFolds << ", guarded " << guardedFolds << " (planarity " << rg.planarityMax
                                     << "), free " << freeFolds << " (planarity " << rf.planarityMax << ")");
  CHECK(guardedFolds <= initialFolds);  // no face that was simple folded
  CHECK(freeFolds > guardedFolds + 10);
  CHECK(rf.converged);
  CHECK(rg.converged == (rg.planarityMax <= o.tolerance));
  CHECK(rg.planarityMax < rg.initialPlanarityMax);
}

TEST_CASE("planarize: shifting the face planes brings the nodes to the surface and keeps every face planar") {
  SECTION("a P-Hex mesh blown up by 2 % comes back onto its sphere") {
    PipelineParams p;
    p.surface = "sphere";
    p.faces = 600;
    p.fitSurface = false;
    PipelineResult r = runPipeline(p);
    REQUIRE(r.solve.converged);
    PolyMesh blown = r.hex;
    blown.V *= 1.02;  // a scaled planar mesh is planar: only the distance is off
    const double before = measure(blown, *r.surface).surfaceDistanceMax;
    PlanarizeOptions o;
    o.surface = r.surface.get();
    const PlanarizeReport fit = planarize(blown, o);
    const MeshMetrics m = measure(blown, *r.surface);
    CHECK(fit.iterations == 0);  // already planar: only the shift ran
    CHECK(fit.surfaceFitted);
    CHECK(m.planarityMax <= 1e-9);
    CHECK(m.selfIntersectingCount == 0);
    CHECK(m.surfaceDistanceMax < 0.2 * before);
    CHECK(fit.surfaceDistanceAfter == Approx(m.surfaceDistanceMax).margin(1e-12));
    CHECK(fit.surfaceDistanceBefore == Approx(before).margin(1e-12));
  }
  SECTION("on the pipeline's results the largest distance drops, planarity and simplicity stay") {
    for (const char* name : {"sphere", "torus", "cyclide"}) {
      CAPTURE(name);
      PipelineParams p;
      p.surface = name;
      p.faces = 1000;
      const PipelineResult fitted = runPipeline(p);
      p.fitSurface = false;
      const PipelineResult plain = runPipeline(p);
      CHECK(fitted.solve.surfaceFitted);
      CHECK_FALSE(plain.solve.surfaceFitted);
      CHECK(fitted.metrics.planarityMax <= 1e-9);
      CHECK(fitted.metrics.selfIntersectingCount == 0);
      CHECK(fitted.metrics.surfaceDistanceMax < 0.6 * plain.metrics.surfaceDistanceMax);
      CHECK(fitted.metrics.surfaceDistanceMean < 0.6 * plain.metrics.surfaceDistanceMean);
      CHECK(fitted.metrics.surfaceDistanceMax <= 0.002);
    }
  }
  SECTION("a plane has nothing to gain: the mesh is left as it was") {
    PipelineParams p;
    p.surface = "plane";
    p.faces = 300;
    const PipelineResult r = runPipeline(p);
    CHECK_FALSE(r.solve.surfaceFitted);
    CHECK(r.metrics.surfaceDistanceMax < 1e-12);
  }
}

TEST_CASE("planarize: the surface-distance weight mu keeps nodes near the surface, never sends them away") {
  // mu pulled each node onto the tangent plane at its foot only: where a node's face planes nearly share that
  // plane (boundary nodes, nodes next to a parabolic curve) it ran off along their near-intersection. The
  // wave roof at 1000 faces with mu = 0.01 ended 21 % of its diagonal off the surface, nodes 12 edges from
  // their start. The pull along the plane towards the foot holds them.
  PipelineParams p;
  p.surface = "wave-roof";
  p.faces = 1000;
  p.duality = Duality::Dupin;
  p.mu = 0.01;
  const PipelineResult r = runPipeline(p);
  INFO("distance " << r.metrics.surfaceDistanceMax << ", displacement " << r.solve.displacementMax << ", planarity "
                   << r.metrics.planarityMax);
  CHECK(r.solve.displacementMax < 0.5);
  CHECK(r.metrics.surfaceDistanceMax < 0.002);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.metrics.planarityMax < r.solve.initialPlanarityMax);
}

TEST_CASE("planarize: a node drifted along a free line running nearly along the surface comes back to its faces") {
  // Two quads meet only at node 1, so it lies on their two planes alone and is free along their line, which
  // rises 1 in 10 over the plane z = 0. The node sits 0.8 out along it, 0.08 off the surface and far from the
  // quads' other corners (the analytic bumps at 100k faces had such a node 28 cells out, 0.3 % of the
  // diagonal off the surface, after cuts left two thin quads at it): closest-point steps along the line
  // barely move it, so it goes back along the line towards its faces' other corners instead.
  const ParametricSurfacePtr plane = makeSurface("plane");
  PolyMesh quads;
  quads.V.resize(7, 3);
  quads.V << -0.1, 0, -0.01,  // quad 0, in the plane z = 0.1 x
      0.8, 0, 0.08,           // the node, on the line (t, 0, 0.1 t) both planes hold
      0, 0.1, 0,              //
      0, -0.1, 0,             //
      0, -0.05, -0.015,       // quad 1, in the plane z = 0.1 x + 0.3 y
      0, 0.05, 0.015,         //
      -0.05, 0, -0.005;
  quads.addFace({0, 3, 1, 2});
  quads.addFace({4, 1, 5, 6});
  // The rest of a mesh, which sets the edge length a drift is measured against: small triangles on the
  // surface away from the quads.
  for (int i = 0; i < 40; ++i) {
    const int a = static_cast<int>(quads.V.rows());
    quads.V.conservativeResize(a + 3, 3);
    quads.V.bottomRows(3) << -0.8 + 0.02 * i, -0.8, 0, -0.79 + 0.02 * i, -0.8, 0, -0.8 + 0.02 * i, -0.79, 0;
    quads.addFace({a, a + 1, a + 2});
  }
  REQUIRE(measure(quads, *plane).planarityMax < 1e-12);
  PlanarizeOptions o;
  o.surface = plane.get();
  PolyMesh settled = quads;
  const PlanarizeReport r = planarize(settled, o);
  const MeshMetrics m = measure(settled, *plane);
  const Vec3 node = settled.vertex(1);
  INFO("node " << node.transpose());
  CHECK(r.freeNodesSettled >= 1);
  CHECK(m.planarityMax <= 1e-12);
  CHECK(m.selfIntersectingCount == 0);
  CHECK(std::abs(node.z()) < 0.02);  // 0.08 off the surface, and 0.03 after the planes were shifted
  CHECK(node.x() < 0.4);             // back among its faces' corners, which lie within 0.1 of the origin
}

TEST_CASE("planarize: a node on fewer than three face planes is put nearest the surface along its free directions") {
  // A quad in the tangent plane x = 1 of the unit sphere, one corner far out (0.22 off the sphere): each
  // corner lies on one plane only, so it may move within that plane without the quad leaving it.
  const ParametricSurfacePtr sphere = makeSurface("sphere");
  PolyMesh quad;
  quad.V.resize(4, 3);
  quad.V << 1, -0.1, -0.1, 1, 0.1, -0.1, 1, 0.5, 0.5, 1, -0.1, 0.1;
  quad.addFace({0, 1, 2, 3});
  const double before = measure(quad, *sphere).surfaceDistanceMax;
  PlanarizeOptions o;
  o.surface = sphere.get();
  PolyMesh settled = quad;
  const PlanarizeReport r = planarize(settled, o);
  const MeshMetrics m = measure(settled, *sphere);
  CHECK(r.freeNodesSettled >= 1);
  CHECK(m.planarityMax <= 1e-12);
  CHECK(m.selfIntersectingCount == 0);
  CHECK(m.surfaceDistanceMax < 0.5 * before);
  CHECK(r.surfaceDistanceAfter == Approx(m.surfaceDistanceMax).margin(1e-12));
  // The far corner came in towards the others, and stayed in the quad's plane.
  CHECK((settled.vertex(2) - settled.vertex(0)).norm() < (quad.vertex(2) - quad.vertex(0)).norm());
  // Without the surface fit nothing moves.
  o.fitSurface = false;
  PolyMesh plain = quad;
  const PlanarizeReport off = planarize(plain, o);
  CHECK(off.freeNodesSettled == 0);
  CHECK(plain.V == quad.V);
}
