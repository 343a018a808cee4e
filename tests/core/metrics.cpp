#include <catch.hpp>
#include <cmath>
#include <random>

#include "phex/metrics.hpp"

using namespace phex;

namespace {
PolyMesh hexagon(double lift, bool bowtie) {
  PolyMesh m;
  m.V.resize(6, 3);
  for (int i = 0; i < 6; ++i) {
    const double a = i * M_PI / 3;
    m.V.row(i) << std::cos(a), std::sin(a), (i % 2 ? lift : -lift);
  }
  if (bowtie) m.addFace({0, 1, 3, 2, 4, 5});
  else m.addFace({0, 1, 2, 3, 4, 5});
  return m;
}
}  // namespace

TEST_CASE("metrics: planarity is the farthest vertex distance over the mean edge length") {
  CHECK(facePlanarity(hexagon(0, false), 0) < 1e-15);
  // Alternating heights ±d around a regular hexagon of edge ~1: the LSQ plane is z = 0.
  const PolyMesh m = hexagon(0.01, false);
  double edge = 0;
  for (int i = 0; i < 6; ++i) edge += (m.V.row(i) - m.V.row((i + 1) % 6)).norm();
  CHECK(facePlanarity(m, 0) == Approx(0.01 / (edge / 6)).epsilon(1e-9));
}

TEST_CASE("metrics: self-intersection is detected") {
  CHECK_FALSE(faceSelfIntersects(hexagon(0, false), 0));
  CHECK(faceSelfIntersects(hexagon(0, true), 0));
  const MeshMetrics mm = measure(hexagon(0, true));
  CHECK(mm.selfIntersectingCount == 1);
  CHECK(mm.facesBySize.at(6) == 1);
}

// Two regular hexagons sharing the edge 5-0; vertex 0 moved nearly onto vertex 5 leaves one short edge, counted
// once though both faces have it.
TEST_CASE("metrics: edges far shorter than the mean are counted once each") {
  PolyMesh m;
  m.V.resize(10, 3);
  const double s = std::sqrt(3.0) / 2;
  m.V << 1, 0, 0, 0.5, s, 0, -0.5, s, 0, -1, 0, 0, -0.5, -s, 0, 0.5, -s, 0,  // around the origin
      2.5, -s, 0, 2, 0, 0, 1, -2 * s, 0, 2, -2 * s, 0;                        // with 0 and 5, around (1.5, -s)
  m.addFace({0, 1, 2, 3, 4, 5});
  m.addFace({6, 7, 0, 5, 8, 9});
  CHECK(measure(m).shortEdgeCount == 0);
  m.V.row(0) = m.V.row(5) + 0.002 * (m.V.row(0) - m.V.row(5));
  const MeshMetrics mm = measure(m);
  CHECK(mm.shortEdgeCount == 1);
  CHECK(mm.edgeLengthMin < kShortEdge * mm.edgeLengthMean);
}

TEST_CASE("metrics: the fold margin bounds how far one corner may move before the face crosses itself") {
  // Regular hexagon of edge 1: the edges nearest a corner not at it start at its neighbours, one edge away.
  CHECK(faceFoldMargin(hexagon(0, false), 0, Vec3::UnitZ()) == Approx(1.0));
  CHECK(faceFoldMargin(hexagon(0, true), 0, Vec3::UnitZ()) == 0.0);
  // Random hexagons and random moves of one corner: a move shorter than the margin never folds the face.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0, folded = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    PolyMesh m = hexagon(0, false);
    for (int i = 0; i < 6; ++i) m.V.row(i) += 0.4 * Eigen::RowVector3d(u(rng), u(rng), 0);
    const double margin = faceFoldMargin(m, 0, Vec3::UnitZ());
    if (margin == 0) continue;
    const int corner = trial % 6;
    const Vec3 d = Vec3(u(rng), u(rng), 0).normalized();
    const double length = std::abs(u(rng)) * 1.5 * margin;
    m.V.row(corner) += (length * d).transpose();
    const bool folds = faceSelfIntersects(m, 0, Vec3::UnitZ());
    if (length < margin) {
      ++checked;
      CHECK_FALSE(folds);
    }
    folded += folds;
  }
  CHECK(checked > 5000);
  CHECK(folded > 0);  // the longer moves do fold some: the bound is not vacuous
}

TEST_CASE("metrics: affine regularity against the regular and quasi-regular templates (§4.2)") {
  Eigen::Matrix2d A;
  A << 2.0, 0.7, -0.3, 1.1;  // any orientation-preserving affine map
  const Vec2 shift(5, -2);
  const double s = 2 / std::sqrt(3.0);
  const Vec2 quasi[6] = {{1, -s}, {1, s}, {0, s / 2}, {-1, s}, {-1, -s}, {0, -s / 2}};
  std::vector<Vec2> regularImage, quasiImage;
  for (int i = 0; i < 6; ++i) {
    regularImage.push_back(A * Vec2(std::cos(i * M_PI / 3), std::sin(i * M_PI / 3)) + shift);
    quasiImage.push_back(A * quasi[(i + 2) % 6] + shift);  // any starting corner
  }
  CHECK(affineRegularityDefect(regularImage, false) < 1e-12);
  CHECK(affineRegularityDefect(quasiImage, true) < 1e-12);
  CHECK(affineRegularityDefect(regularImage, true) > 0.1);
  CHECK(affineRegularityDefect(quasiImage, false) > 0.1);
  regularImage[0] += Vec2(0.2, 0.1);
  CHECK(affineRegularityDefect(regularImage, false) > 0.01);
  CHECK(affineRegularityDefect({Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)}, false) == -1.0);
}

TEST_CASE("metrics: diagonal planarity, convexity, areas, edges and valences") {
  const PolyMesh flat = hexagon(0, false);
  const MeshMetrics m = measure(flat);
  CHECK(m.planarityDiagonals[0] < 1e-12);
  CHECK(m.convex[0] == 1);
  CHECK(m.faceArea[0] == Approx(3 * std::sqrt(3.0) / 2).epsilon(1e-12));  // regular hexagon of side 1
  CHECK(m.edgeLengthMin == Approx(1.0));
  CHECK(m.edgeLengthMax == Approx(1.0));
  CHECK(m.vertexValence.at(1) == 6);
  CHECK(measure(hexagon(0.05, false)).planarityDiagonals[0] > 1.0);  // percent
  CHECK(measure(hexagon(0, true)).convex[0] == 0);
  // A dart (non-convex, simple) hexagon.
  PolyMesh dart = flat;
  dart.V.row(0) << 0.2, 0, 0;
  const MeshMetrics d = measure(dart);
  CHECK(d.convex[0] == 0);
  CHECK(d.selfIntersecting[0] == 0);
}

TEST_CASE("metrics: the largest gap from points to a mesh finds a hole") {
  // A 2 x 2 grid of unit squares in z = 0 without its middle ring of faces... here: two unit squares side by side,
  // and points on the plane: the one over the squares is on them, the one 1.5 beyond their edge is 1.5 away.
  PolyMesh m;
  m.V.resize(6, 3);
  m.V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0;
  m.addFace({0, 1, 4, 3});
  m.addFace({1, 2, 5, 4});
  CHECK(largestGapToMesh(m, {Vec3(0.5, 0.5, 0), Vec3(1.5, 0.2, 0)}) == Approx(0.0).margin(1e-12));
  CHECK(largestGapToMesh(m, {Vec3(0.5, 0.5, 0), Vec3(3.5, 0.5, 0)}) == Approx(1.5));
  CHECK(largestGapToMesh(m, {Vec3(1.0, 0.5, 2.0)}) == Approx(2.0));
}
