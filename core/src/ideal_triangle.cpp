#include "phex/ideal_triangle.hpp"

#include <algorithm>
#include <cmath>

namespace phex {
namespace {
double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
}  // namespace

IdealApex idealApex(const LocalGeometry& g, const Vec2& A, const Vec2& B, Side side, double tolerance) {
  IdealApex r;
  const double length = (B - A).norm();
  if (!A.allFinite() || !B.allFinite() || !(length > 0)) return r;
  const PointType type = classify(g, tolerance, length);
  if (type == PointType::Parabolic || type == PointType::Planar) {
    r.status = IdealApex::Status::Parabolic;
    return r;
  }
  const Vec2 h = 0.5 * (B - A);  // M -> B
  const double kmax = g.largestCurvature();
  const double hh = secondFundamentalForm(g, h, h);
  if (!(std::abs(hh) > tolerance * kmax * h.squaredNorm())) {
    r.status = IdealApex::Status::Asymptotic;
    return r;
  }
  // l through M, conjugate to AB; the conjugate of a non-asymptotic direction exists off parabolic points.
  const std::optional<Vec2> w = conjugateDirection(g, h);
  if (!w) {
    r.status = IdealApex::Status::Parabolic;
    return r;
  }
  r.midpoint = 0.5 * (A + B);
  r.direction = side == Side::Left ? *w : Vec2(-*w);
  // D = A + s w, E = B + s w, so that M + s w is on DE. As II(h, w) = 0:
  //   K > 0: DE touches the Dupin ellipse II(x - M, x - M) = II(h, h) with diameter AB at M + s w,
  //          so s^2 II(w, w) = II(h, h);
  //   K < 0: MD = s w - h lies on an asymptote of the Dupin hyperbola centred at M,
  //          so II(s w - h, s w - h) = s^2 II(w, w) + II(h, h) = 0.
  // Either way s^2 = |II(h, h) / II(w, w)|, and |CM| = sqrt(3) |AD| = sqrt(3) s (§5.1).
  const double s = std::sqrt(std::abs(hh / secondFundamentalForm(g, *w, *w)));
  if (!std::isfinite(s) || !(s > 0)) {
    r.status = IdealApex::Status::Parabolic;
    return r;
  }
  r.validStep = s;
  r.step = std::sqrt(3.0) * s;
  r.apex = r.midpoint + r.step * r.direction;
  r.status = IdealApex::Status::Ok;
  return r;
}

StarValidity starValidity(const LocalGeometry& g, const Triangle2& t) {
  StarValidity r;
  const Vec2 e0 = t[1] - t[0], e1 = t[2] - t[1], e2 = t[0] - t[2];
  const double area2 = cross(e0, -e2);
  if (!(std::abs(area2) > 1e-12 * e0.norm() * e2.norm())) return r;
  const double K = g.k1 * g.k2;
  if (K > 0) {
    // Prop. 4: the Dupin centre strictly inside t (all barycentric coordinates positive).
    const std::optional<Vec2> m = dupinCenter(g, t[0], t[1], t[2]);
    if (!m) return r;
    r.measures = {cross(t[1] - *m, t[2] - *m) / area2, cross(t[2] - *m, t[0] - *m) / area2,
                  cross(t[0] - *m, t[1] - *m) / area2};
    r.judged = true;
    r.valid = r.measures[0] > 0 && r.measures[1] > 0 && r.measures[2] > 0;
    return r;
  }
  if (K < 0) {
    // Prop. 5 (3): the asymptotic lines split the edge directions into II > 0 and II < 0; an edge on an
    // asymptote has no circumscribing Dupin hyperbola at all.
    const double kmax = g.largestCurvature();
    int positive = 0, negative = 0, k = 0;
    for (const Vec2& e : {e0, e1, e2}) {
      const double q = secondFundamentalForm(g, e, e);
      positive += q > 0;
      negative += q < 0;
      r.measures[k++] = q / (kmax * e.squaredNorm());
    }
    r.judged = true;
    r.valid = positive > 0 && negative > 0 && positive + negative == 3;
  }
  return r;
}

bool starIsValid(const LocalGeometry& g, const Triangle2& t) { return starValidity(g, t).valid; }

std::array<Vec2, 6> triangleStar(const Vec2& a, const Vec2& b) { return {a, b, b - a, -a, -b, a - b}; }

std::optional<std::array<Vec2, 6>> dupinHexagon(const LocalGeometry& g, const std::array<Vec2, 6>& star) {
  std::array<Vec2, 6> hexagon;
  for (int i = 0; i < 6; ++i) {
    const std::optional<Vec2> m = dupinCenter(g, Vec2::Zero(), star[i], star[(i + 1) % 6]);
    if (!m) return std::nullopt;
    hexagon[i] = *m;
  }
  return hexagon;
}

}  // namespace phex
