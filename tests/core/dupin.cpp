#include <catch.hpp>

#include "random_geometry.hpp"
#include <cmath>
#include <random>

#include "phex/dupin.hpp"

using namespace phex;
using namespace phex::testing;

namespace {


// The Dupin conic level of x around centre m.
double level(const LocalGeometry& g, const Vec2& x, const Vec2& m) { return secondFundamentalForm(g, x - m, x - m); }

}  // namespace

TEST_CASE("dupin: tangent-plane coordinates project vertically and map back") {
  LocalGeometry g;
  g.point = Vec3(1, 2, 3);
  g.normal = Vec3(1, 1, 1).normalized();
  g.d1 = Vec3(1, -1, 0).normalized();
  g.d2 = g.normal.cross(g.d1);
  const Vec2 x(0.3, -1.7);
  CHECK((toTangentPlane(g, fromTangentPlane(g, x)) - x).norm() < 1e-15);
  CHECK((toTangentPlane(g, fromTangentPlane(g, x) + 5.0 * g.normal) - x).norm() < 1e-14);
  CHECK((tangentVector(g, spatialVector(g, x) - 2.0 * g.normal) - x).norm() < 1e-15);
  CHECK(std::abs((fromTangentPlane(g, x) - g.point).dot(g.normal)) < 1e-15);
}

TEST_CASE("dupin: classify tells the four kinds of points apart, independently of scale") {
  const double tol = 1e-6;
  for (double scale : {1e-3, 1.0, 1e4}) {
    // Curvatures scale as 1 / length: the same shape at another size is the same kind of point.
    auto kind = [&](double k1, double k2) { return classify(withCurvatures(k1 / scale, k2 / scale), tol, 0.1 * scale); };
    CHECK(kind(2, 1) == PointType::Elliptic);
    CHECK(kind(-2, -1) == PointType::Elliptic);
    CHECK(kind(2, -1) == PointType::Hyperbolic);
    CHECK(kind(2, 1e-9) == PointType::Parabolic);
    CHECK(kind(-1e-9, -2) == PointType::Parabolic);
    CHECK(kind(2, 0) == PointType::Parabolic);
    CHECK(kind(1e-8, -1e-8) == PointType::Planar);
    CHECK(kind(0, 0) == PointType::Planar);
  }
}

TEST_CASE("dupin: the conjugate direction satisfies II(t, t') = 0") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 400; ++trial) {
    const LocalGeometry g = randomGeometry(rng, trial % 2 ? 1 : -1);
    const Vec2 t = randomPoint(rng);
    const std::optional<Vec2> c = conjugateDirection(g, t);
    REQUIRE(c);
    CHECK(c->norm() == Approx(1.0).epsilon(1e-14));
    CHECK(std::abs(secondFundamentalForm(g, t, *c)) < 1e-13 * (std::abs(g.k1) + std::abs(g.k2)) * t.norm());
    CHECK(t.x() * c->y() - t.y() * c->x() >= 0);  // counterclockwise from t
    // Conjugacy is symmetric: the conjugate of the conjugate is t's line again.
    const std::optional<Vec2> back = conjugateDirection(g, *c);
    REQUIRE(back);
    CHECK(std::abs(back->x() * t.y() - back->y() * t.x()) < 1e-12 * t.norm());
  }
  // Principal directions are conjugate to each other.
  const LocalGeometry g = withCurvatures(3, -0.5);
  CHECK((*conjugateDirection(g, Vec2(2, 0)) - Vec2(0, 1)).norm() < 1e-15);
  CHECK(std::abs(conjugateDirection(g, Vec2(0, 1))->x()) == Approx(1.0));
}

TEST_CASE("dupin: asymptotic directions are self-conjugate; the zero-curvature direction has no conjugate") {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const LocalGeometry g = randomGeometry(rng, -1);
    const auto a = asymptoticDirections(g);
    REQUIRE(a);
    for (const Vec2& t : *a) {
      CHECK(t.norm() == Approx(1.0));
      CHECK(std::abs(secondFundamentalForm(g, t, t)) < 1e-14 * (std::abs(g.k1) + std::abs(g.k2)));
      CHECK((*conjugateDirection(g, 3.0 * t) - t).norm() < 1e-7);
    }
    CHECK(std::abs((*a)[0].x() * (*a)[1].y() - (*a)[0].y() * (*a)[1].x()) > 1e-3);  // two distinct lines
    CHECK_FALSE(asymptoticDirections(randomGeometry(rng, 1)));
  }
  // Parabolic point (k2 = 0, zero-curvature direction d2): every other direction is conjugate to d2, and d2
  // is conjugate to everything; the two asymptotic directions merge into d2.
  const LocalGeometry p = withCurvatures(2, 0);
  for (const Vec2& t : {Vec2(1, 0), Vec2(1, 3), Vec2(-2, 0.1)})
    CHECK(std::abs(conjugateDirection(p, t)->x()) < 1e-15);
  CHECK_FALSE(conjugateDirection(p, Vec2(0, 1)));
  const auto a = asymptoticDirections(p);
  REQUIRE(a);
  CHECK(std::abs((*a)[0].y()) == Approx(1.0));
  CHECK(std::abs((*a)[1].y()) == Approx(1.0));
  // Planar point: nothing is defined.
  CHECK_FALSE(conjugateDirection(withCurvatures(0, 0), Vec2(1, 0)));
  CHECK_FALSE(asymptoticDirections(withCurvatures(0, 0)));
}

TEST_CASE("dupin: the Dupin centre is the centre of the Dupin conic through three points") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI), param(-1.5, 1.5), size(0.2, 2.0);
  for (int trial = 0; trial < 300; ++trial) {
    const bool elliptic = trial % 2 == 0;
    const LocalGeometry g = randomGeometry(rng, elliptic ? 1 : -1);
    const double s1 = 1 / std::sqrt(std::abs(g.k1)), s2 = 1 / std::sqrt(std::abs(g.k2));
    // Three points on a homothetic copy of the indicatrix with a known centre m (hyperbola: both branches).
    const Vec2 m = randomPoint(rng);
    const double r = size(rng);
    Vec2 p[3];
    for (Vec2& q : p) {
      if (elliptic) {
        const double a = angle(rng);
        q = m + r * Vec2(s1 * std::cos(a), s2 * std::sin(a));
      } else {
        const double t = param(rng), branch = angle(rng) < M_PI ? 1 : -1;
        q = m + r * Vec2(branch * s1 * std::cosh(t), s2 * std::sinh(t));
      }
    }
    const double area = std::abs((p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x());
    if (area < 1e-3 * r * r) continue;  // nearly collinear: the centre is ill-conditioned
    const std::optional<Vec2> c = dupinCenter(g, p[0], p[1], p[2]);
    REQUIRE(c);
    CHECK((*c - m).norm() < 1e-9 * (1 + r));
    // Only the indicatrix's shape matters: the same centre for -II and for a scaled II.
    for (double factor : {-1.0, 7.0}) {
      LocalGeometry h = g;
      h.k1 *= factor;
      h.k2 *= factor;
      CHECK((*dupinCenter(h, p[0], p[1], p[2]) - m).norm() < 1e-9 * (1 + r));
    }
  }
  // Random triangles: equal conic levels at the three vertices, and symmetry in the order of the points.
  for (int trial = 0; trial < 300; ++trial) {
    const LocalGeometry g = randomGeometry(rng, trial % 2 ? 1 : -1);
    const Vec2 a = randomPoint(rng), b = randomPoint(rng), c = randomPoint(rng);
    const std::optional<Vec2> m = dupinCenter(g, a, b, c);
    if (!m) continue;
    const double scale = std::max({std::abs(level(g, a, *m)), std::abs(level(g, b, *m)), 1e-3});
    CHECK(std::abs(level(g, a, *m) - level(g, b, *m)) < 1e-9 * scale);
    CHECK(std::abs(level(g, a, *m) - level(g, c, *m)) < 1e-9 * scale);
    CHECK((*dupinCenter(g, c, a, b) - *m).norm() < 1e-9 * (1 + m->norm()));
  }
  const LocalGeometry g = withCurvatures(1, 2);
  CHECK_FALSE(dupinCenter(g, Vec2(0, 0), Vec2(1, 1), Vec2(2, 2)));             // collinear
  CHECK_FALSE(dupinCenter(withCurvatures(1, 0), Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)));  // parabolic
}

TEST_CASE("dupin: the spatial Dupin centre uses vertical projections onto the tangent plane") {
  LocalGeometry g;
  g.point = Vec3(0.5, -1, 2);
  g.normal = Vec3(0.2, 0.3, 1).normalized();
  g.d1 = g.normal.cross(Vec3::UnitX()).normalized();
  g.d2 = g.normal.cross(g.d1);
  g.k1 = 1.3;
  g.k2 = -0.4;
  const Vec2 a(0.1, 0.2), b(0.9, -0.3), c(-0.4, 0.7);
  const Vec3 A = fromTangentPlane(g, a) + 0.3 * g.normal, B = fromTangentPlane(g, b) - 0.2 * g.normal,
             C = fromTangentPlane(g, c) + 0.05 * g.normal;
  const std::optional<Vec3> m3 = dupinCenter(g, A, B, C);
  REQUIRE(m3);
  CHECK((*m3 - fromTangentPlane(g, *dupinCenter(g, a, b, c))).norm() < 1e-14);
  CHECK(std::abs((*m3 - g.point).dot(g.normal)) < 1e-14);
}
