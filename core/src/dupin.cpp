#include "phex/dupin.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace phex {

Vec2 toTangentPlane(const LocalGeometry& g, const Vec3& p) { return tangentVector(g, p - g.point); }
Vec3 fromTangentPlane(const LocalGeometry& g, const Vec2& x) { return g.point + spatialVector(g, x); }
Vec2 tangentVector(const LocalGeometry& g, const Vec3& v) { return Vec2(v.dot(g.d1), v.dot(g.d2)); }
Vec3 spatialVector(const LocalGeometry& g, const Vec2& t) { return t.x() * g.d1 + t.y() * g.d2; }

double secondFundamentalForm(const LocalGeometry& g, const Vec2& s, const Vec2& t) {
  return g.k1 * s.x() * t.x() + g.k2 * s.y() * t.y();
}

PointType classify(const LocalGeometry& g, double tolerance, double lengthScale) {
  const double kmax = g.largestCurvature();
  const double kmin = std::min(std::abs(g.k1), std::abs(g.k2));
  if (kmax * lengthScale <= tolerance) return PointType::Planar;
  if (kmin <= tolerance * kmax) return PointType::Parabolic;
  return g.k1 * g.k2 > 0 ? PointType::Elliptic : PointType::Hyperbolic;
}

std::optional<Vec2> conjugateDirection(const LocalGeometry& g, const Vec2& t) {
  // II(t, t') = (S t) . t' with S = diag(k1, k2): t' is S t turned by a quarter.
  const Vec2 St(g.k1 * t.x(), g.k2 * t.y());
  const double kmax = g.largestCurvature();
  if (!(St.norm() > 1e-14 * kmax * t.norm())) return std::nullopt;
  Vec2 c = Vec2(-St.y(), St.x()).normalized();
  // t x c = II(t, t) / |S t|: flip to keep c counterclockwise from t; an asymptotic t (to round-off) gets
  // t itself.
  const double twist = secondFundamentalForm(g, t, t);
  const bool asymptotic = std::abs(twist) <= 1e-12 * St.norm() * t.norm();
  if (asymptotic ? c.dot(t) < 0 : twist < 0) c = -c;
  return c;
}

std::optional<std::array<Vec2, 2>> asymptoticDirections(const LocalGeometry& g) {
  if (!(g.k1 >= 0 && g.k2 <= 0) || (g.k1 == 0 && g.k2 == 0)) return std::nullopt;
  const double x = std::sqrt(-g.k2), y = std::sqrt(g.k1);
  return std::array<Vec2, 2>{Vec2(x, y).normalized(), Vec2(x, -y).normalized()};
}

std::optional<Vec2> dupinCenter(const LocalGeometry& g, const Vec2& a, const Vec2& b, const Vec2& c) {
  // With m the centre, II(a - m, a - m) = II(b - m, b - m) = II(c - m, c - m). Relative to a (e = b - a,
  // f = c - a, n = m - a) the squares cancel: 2 II(e, n) = II(e, e), 2 II(f, n) = II(f, f).
  const Vec2 e = b - a, f = c - a;
  Eigen::Matrix2d M;
  M << 2 * g.k1 * e.x(), 2 * g.k2 * e.y(), 2 * g.k1 * f.x(), 2 * g.k2 * f.y();
  const Eigen::Vector2d rhs(secondFundamentalForm(g, e, e), secondFundamentalForm(g, f, f));
  // The rows turn parallel as K -> 0 or as a, b, c become collinear: compare the determinant to their norms.
  const double det = M.determinant();
  if (!(std::abs(det) > 1e-12 * M.row(0).norm() * M.row(1).norm())) return std::nullopt;
  const Vec2 n = M.inverse() * rhs;
  if (!n.allFinite()) return std::nullopt;
  return Vec2(a + n);
}

std::optional<Vec3> dupinCenter(const LocalGeometry& g, const Vec3& a, const Vec3& b, const Vec3& c) {
  const std::optional<Vec2> m = dupinCenter(g, toTangentPlane(g, a), toTangentPlane(g, b), toTangentPlane(g, c));
  if (!m) return std::nullopt;
  return fromTangentPlane(g, *m);
}

bool samplesDevelopable(const std::vector<LocalGeometry>& samples, double curvedAbove) {
  std::size_t curved = 0, parabolic = 0;
  for (const LocalGeometry& g : samples) {
    const double kmax = g.largestCurvature(), kmin = std::min(std::abs(g.k1), std::abs(g.k2));
    if (!(kmax > curvedAbove)) continue;
    ++curved;
    parabolic += kmin <= kDevelopableRatio * kmax;
  }
  return curved > 0 && 2 * curved >= samples.size() && parabolic >= kDevelopableShare * double(curved);
}

double planarBelow(const std::vector<LocalGeometry>& samples) {
  std::vector<double> kmax;
  kmax.reserve(samples.size());
  for (const LocalGeometry& g : samples) kmax.push_back(g.largestCurvature());
  std::nth_element(kmax.begin(), kmax.begin() + kmax.size() / 2, kmax.end());
  return kPlanarShare * kmax[kmax.size() / 2];
}

}  // namespace phex
