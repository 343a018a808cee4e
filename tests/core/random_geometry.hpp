// Test helpers: random local geometries and tangent-plane points for the §3–§5.1 property tests.
#pragma once
#include <algorithm>
#include <cmath>
#include <random>

#include "phex/geometry.hpp"

namespace phex::testing {

// The standard frame (d1 = x, d2 = y, normal = z) with the given principal curvatures.
inline LocalGeometry withCurvatures(double k1, double k2) {
  LocalGeometry g;
  g.k1 = std::max(k1, k2);
  g.k2 = std::min(k1, k2);
  return g;
}

// Random principal curvatures, magnitudes 0.2 .. 5, either overall sign, with the sign of K asked for
// (+1 / -1 for K > 0 / K < 0).
inline LocalGeometry randomGeometry(std::mt19937& rng, int signOfK) {
  std::uniform_real_distribution<double> logk(std::log(0.2), std::log(5.0));
  const double s = std::uniform_int_distribution<int>(0, 1)(rng) ? 1.0 : -1.0;
  return withCurvatures(s * std::exp(logk(rng)), s * signOfK * std::exp(logk(rng)));
}

// A random point of the tangent plane in the square [-2, 2]^2.
inline Vec2 randomPoint(std::mt19937& rng) {
  std::uniform_real_distribution<double> x(-2.0, 2.0);
  return Vec2(x(rng), x(rng));
}

}  // namespace phex::testing
