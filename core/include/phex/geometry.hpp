// phex — basic geometric types shared by every stage.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace phex {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Box3 = Eigen::AlignedBox3d;

// The cell of a grid of n cells along an axis that holds coordinate x (in cells from the grid's origin):
// floor(x) clamped to [0, n) in floating point before the cast, NaN to 0 (a double beyond int's range cast
// to int is undefined behaviour, and points far off a grid or not finite reach grids from data).
inline int gridCell(double x, int n) {
  const double q = std::floor(x);
  return q >= 0 ? (q < n ? static_cast<int>(q) : n - 1) : 0;
}

// A hash of a point's coordinates bit for bit, -0 taken as +0, so that points equal by == hash alike (for tables
// keyed on exact coordinates: the STL reader's welding, the rounds against folds matching a dual's points and
// looking up closest points).
inline std::uint64_t exactPointHash(double x, double y, double z) {
  std::uint64_t h = 1469598103934665603ull;
  for (double c : {x + 0.0, y + 0.0, z + 0.0}) {  // + 0.0 turns -0 into +0
    std::uint64_t bits;
    std::memcpy(&bits, &c, sizeof bits);
    h = (h ^ bits) * 1099511628211ull;
    h ^= h >> 29;
  }
  return h;
}
// Tables keyed on exact coordinates by open addressing: item numbers (-1 where empty) in a power-of-two table,
// probed linearly from the coordinates' hash. The empty table for up to `items` items, at most half full.
inline std::vector<int> exactPointSlots(std::size_t items) {
  std::size_t size = 16;
  while (size < 2 * items) size *= 2;
  return std::vector<int>(size, -1);
}
// The slot of `slots` holding the item at (x, y, z) (equal by ==: -0 and +0 alike), `point(item)` giving an item's
// coordinates as a Vec3; or, where there is none, the empty slot where it goes.
template <typename PointOf>
std::size_t exactPointSlot(const std::vector<int>& slots, double x, double y, double z, const PointOf& point) {
  const std::size_t mask = slots.size() - 1;
  for (std::size_t at = exactPointHash(x, y, z) & mask;; at = (at + 1) & mask) {
    const int item = slots[at];
    if (item < 0) return at;
    const Vec3 q = point(item);
    if (q.x() == x && q.y() == y && q.z() == z) return at;
  }
}

// The point of segment ab nearest to p (a when the segment has no length).
inline Vec3 closestPointOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 e = b - a;
  const double ee = e.squaredNorm();
  if (!(ee > 0)) return a;
  return a + std::clamp((p - a).dot(e) / ee, 0.0, 1.0) * e;
}

// Second-order local geometry of a surface at one point (§3).
// Sign convention: a principal curvature is positive where the surface bends away from `normal`,
// so a sphere of radius R with outward normals has k1 = k2 = 1/R.
// k1 >= k2; d1, d2 are unit principal directions in the tangent plane, d1 x d2 = normal.
struct LocalGeometry {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  Vec3 d1 = Vec3::UnitX();
  Vec3 d2 = Vec3::UnitY();
  double k1 = 0.0;
  double k2 = 0.0;

  double gaussianCurvature() const { return k1 * k2; }
  double meanCurvature() const { return 0.5 * (k1 + k2); }
  double largestCurvature() const { return std::max(std::abs(k1), std::abs(k2)); }
};

// The direction of the larger eigenvalue of a symmetric 2x2 form [[a, b], [b, c]], as (cos t, sin t) of the angle
// t = atan2(Y, X) / 2 with X = a - c, Y = 2 b and R = |(X, Y)| (computed by the caller), from +, -, *, / and
// sqrt alone (libm's atan2, cos and sin differ between platforms in the last bit). By the half-angle formulas
// cos t = (R + X) / s, sin t = Y / s with s = sqrt(2 R (R + X)) where X >= 0, and cos t = |Y| / s,
// sin t = +-(R - X) / s with s = sqrt(2 R (R - X)) where X < 0 (no cancellation either way). R = 0: (1, 0).
inline Eigen::Vector2d largerEigenDirection(double X, double Y, double R) {
  if (X >= 0) {
    if (!(R > 0)) return Eigen::Vector2d(1, 0);
    const double s = std::sqrt(2 * R * (R + X));
    return Eigen::Vector2d((R + X) / s, Y / s);
  }
  const double s = std::sqrt(2 * R * (R - X));
  return Eigen::Vector2d(std::abs(Y) / s, std::copysign((R - X) / s, Y));
}

}  // namespace phex
