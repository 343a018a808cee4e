#include <catch.hpp>
#include <cmath>

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
