#include <catch.hpp>
#include <cmath>
#include <set>

#include "phex/error.hpp"
#include "phex/surfaces.hpp"

using namespace phex;

namespace {

// Interior sample parameters of a surface: fractions of its domain.
std::vector<Vec2> samples(const ParametricSurface& s) {
  const ParametricSurface::Domain d = s.domain();
  std::vector<Vec2> uv;
  for (double fu : {0.13, 0.41, 0.77})
    for (double fv : {0.17, 0.52, 0.86}) uv.emplace_back(d.u0 + fu * (d.u1 - d.u0), d.v0 + fv * (d.v1 - d.v0));
  return uv;
}

double diameter(const ParametricSurface& s) { return s.bounds().diagonal().norm(); }

// Principal curvatures from the closed-form K and H.
std::pair<double, double> fromKH(double K, double H) {
  const double r = std::sqrt(std::max(0.0, H * H - K));
  return {H + r, H - r};
}

}  // namespace

TEST_CASE("surfaces: every surface's jet matches central differences of its position") {
  for (const SurfaceSpec& spec : analyticSurfaces()) {
    const ParametricSurfacePtr s = makeSurface(spec.name);
    const ParametricSurface::Domain d = s->domain();
    const double hu = 1e-4 * (d.u1 - d.u0), hv = 1e-4 * (d.v1 - d.v0);
    for (const Vec2& uv : samples(*s)) {
      const double u = uv.x(), v = uv.y();
      auto P = [&](double du, double dv) { return s->position(u + du, v + dv); };
      const ParametricSurface::Jet j = s->jet(u, v);
      const double scale = std::max({1.0, j.P.norm(), j.Pu.norm(), j.Pv.norm(), j.Puu.norm(), j.Pvv.norm()});
      INFO(spec.name << " at (u, v) = (" << u << ", " << v << ")");
      CHECK((j.Pu - (P(hu, 0) - P(-hu, 0)) / (2 * hu)).norm() < 1e-6 * scale);
      CHECK((j.Pv - (P(0, hv) - P(0, -hv)) / (2 * hv)).norm() < 1e-6 * scale);
      CHECK((j.Puu - (P(hu, 0) - 2 * j.P + P(-hu, 0)) / (hu * hu)).norm() < 1e-5 * scale);
      CHECK((j.Pvv - (P(0, hv) - 2 * j.P + P(0, -hv)) / (hv * hv)).norm() < 1e-5 * scale);
      CHECK((j.Puv - (P(hu, hv) - P(hu, -hv) - P(-hu, hv) + P(-hu, -hv)) / (4 * hu * hv)).norm() < 1e-5 * scale);
    }
  }
}

TEST_CASE("surfaces: every surface is regular with an orthonormal right-handed principal frame") {
  for (const SurfaceSpec& spec : analyticSurfaces()) {
    const ParametricSurfacePtr s = makeSurface(spec.name);
    const ParametricSurface::Domain d = s->domain();
    INFO(spec.name);
    // Corners and edges included: trimming must keep singular points (poles, apex) out of the domain.
    for (int i = 0; i <= 8; ++i)
      for (int k = 0; k <= 8; ++k) {
        const double u = d.u0 + (d.u1 - d.u0) * i / 8, v = d.v0 + (d.v1 - d.v0) * k / 8;
        const ParametricSurface::Jet j = s->jet(u, v);
        CHECK(j.Pu.cross(j.Pv).norm() > 1e-6 * j.Pu.norm() * j.Pv.norm());
        const LocalGeometry g = s->geometryAt(u, v);
        CHECK(g.k1 >= g.k2);
        CHECK(std::abs(g.d1.dot(g.d2)) < 1e-12);
        CHECK(g.d1.cross(g.d2).dot(g.normal) == Approx(1.0).epsilon(1e-12));
        CHECK(std::abs(g.normal.dot(j.Pu)) < 1e-12 * j.Pu.norm());
      }
  }
}

TEST_CASE("surfaces: d1 and d2 are principal: normal curvatures k1 and k2, and II(d1, d2) = 0") {
  // The second fundamental form at (u, v) along tangent t, from the jet: t = a Pu + b Pv solved in the
  // tangent plane, II(s, t) = -(s_a t_a Puu + (s_a t_b + s_b t_a) Puv + s_b t_b Pvv) . n.
  for (const SurfaceSpec& spec : analyticSurfaces()) {
    const ParametricSurfacePtr s = makeSurface(spec.name);
    for (const Vec2& uv : samples(*s)) {
      const ParametricSurface::Jet j = s->jet(uv.x(), uv.y());
      const LocalGeometry g = s->geometryAt(uv.x(), uv.y());
      Eigen::Matrix<double, 3, 2> J;
      J << j.Pu, j.Pv;
      auto coefficients = [&](const Vec3& t) { return Eigen::Vector2d(J.colPivHouseholderQr().solve(t)); };
      auto II = [&](const Vec3& x, const Vec3& y) {
        const Eigen::Vector2d a = coefficients(x), b = coefficients(y);
        return -(a.x() * b.x() * j.Puu + (a.x() * b.y() + a.y() * b.x()) * j.Puv + a.y() * b.y() * j.Pvv).dot(g.normal);
      };
      const double scale = std::max({1.0, std::abs(g.k1), std::abs(g.k2)});
      INFO(spec.name << " at (" << uv.x() << ", " << uv.y() << "): k1 " << g.k1 << ", k2 " << g.k2);
      CHECK(g.k1 >= g.k2);
      CHECK(std::abs(II(g.d1, g.d1) - g.k1) < 1e-9 * scale);
      CHECK(std::abs(II(g.d2, g.d2) - g.k2) < 1e-9 * scale);
      CHECK(std::abs(II(g.d1, g.d2)) < 1e-9 * scale);
    }
  }
}

TEST_CASE("surfaces: closest point of a point off the surface along the normal is the foot") {
  for (const SurfaceSpec& spec : analyticSurfaces()) {
    const ParametricSurfacePtr s = makeSurface(spec.name);
    const double size = diameter(*s);
    for (const Vec2& uv : samples(*s)) {
      const LocalGeometry g = s->geometryAt(uv.x(), uv.y());
      // Well inside the focal distance on either side, so that the foot is the nearest point.
      const double kmax = g.largestCurvature();
      const double offset = 0.05 * std::min(size, kmax > 0 ? 1 / kmax : size);
      for (double sign : {-1.0, 1.0}) {
        const LocalGeometry f = s->closestPoint(g.point + sign * offset * g.normal);
        INFO(spec.name << " at (u, v) = (" << uv.x() << ", " << uv.y() << "), offset " << sign * offset);
        CHECK((f.point - g.point).norm() < 1e-8 * size);
        CHECK(f.normal.dot(g.normal) == Approx(1.0).epsilon(1e-8));
      }
    }
  }
}

TEST_CASE("surfaces: normals point outward on closed and revolution surfaces, upward on height fields") {
  const std::set<std::string> closed = {"torus", "cyclide"};
  const std::set<std::string> revolution = {"sphere", "ellipsoid", "hyperboloid", "vase",
                                            "cylinder", "cone", "catenoid"};
  const std::set<std::string> heightFields = {"elliptic-paraboloid", "hyperbolic-paraboloid", "plane", "freeform",
                                              "wave-roof"};
  for (const SurfaceSpec& spec : analyticSurfaces()) {
    const ParametricSurfacePtr s = makeSurface(spec.name);
    const ParametricSurface::Domain d = s->domain();
    INFO(spec.name);
    if (closed.count(spec.name)) {
      REQUIRE(s->isClosed());
      // Divergence theorem: the enclosed volume (1/3) integral of P . (Pu x Pv) is positive iff normals point out.
      constexpr int n = 96;
      double volume = 0;
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k) {
          const ParametricSurface::Jet j =
              s->jet(d.u0 + (d.u1 - d.u0) * (i + 0.5) / n, d.v0 + (d.v1 - d.v0) * (k + 0.5) / n);
          volume += j.P.dot(j.Pu.cross(j.Pv)) / 3 * (d.u1 - d.u0) * (d.v1 - d.v0) / (n * n);
        }
      CHECK(volume > 0);
      if (spec.name == "torus") CHECK(volume == Approx(2 * M_PI * M_PI * 1.0 * 0.4 * 0.4).epsilon(1e-9));
    } else if (revolution.count(spec.name)) {
      CHECK(d.periodicU);
      for (const Vec2& uv : samples(*s)) {
        const LocalGeometry g = s->geometryAt(uv.x(), uv.y());
        CHECK(g.normal.dot(Vec3(g.point.x(), g.point.y(), 0)) > 0);
      }
    } else if (heightFields.count(spec.name)) {
      for (const Vec2& uv : samples(*s)) CHECK(s->geometryAt(uv.x(), uv.y()).normal.z() > 0);
    } else if (spec.name == "enneper") {
      CHECK(s->geometryAt(0, 0).normal.z() == Approx(1.0));
    } else if (spec.name == "helicoid") {
      for (const Vec2& uv : samples(*s)) CHECK(s->geometryAt(uv.x(), uv.y()).normal.z() * uv.x() > 0);
    } else {
      FAIL("no orientation test for surface '" << spec.name << "'");
    }
    CHECK(s->isClosed() == (closed.count(spec.name) > 0));
  }
}

TEST_CASE("surfaces: sphere has k1 = k2 = 1/R and outward normals") {
  const ParametricSurfacePtr s = makeSurface("sphere", {{"R", 2.0}});
  for (double u : {0.1, 1.7, 4.0})
    for (double v : {-0.8, 0.0, 0.9}) {
      const LocalGeometry g = s->geometryAt(u, v);
      CHECK(g.k1 == Approx(0.5).epsilon(1e-12));
      CHECK(g.k2 == Approx(0.5).epsilon(1e-12));
      CHECK(g.normal.dot(g.point.normalized()) == Approx(1.0).epsilon(1e-12));
      CHECK(std::abs(g.d1.dot(g.d2)) < 1e-12);
      CHECK(g.d1.cross(g.d2).dot(g.normal) == Approx(1.0).epsilon(1e-12));
    }
}

TEST_CASE("surfaces: torus principal curvatures match the closed form") {
  const double R = 1.0, r = 0.4;
  const ParametricSurfacePtr s = makeSurface("torus", {{"R", R}, {"r", r}});
  for (double v : {-2.5, -1.0, 0.0, 0.7, 3.0}) {
    const LocalGeometry g = s->geometryAt(0.3, v);
    // Meridian curvature 1/r; parallel curvature cos v / (R + r cos v).
    const double km = 1.0 / r, kp = std::cos(v) / (R + r * std::cos(v));
    CHECK(g.k1 == Approx(std::max(km, kp)).epsilon(1e-10));
    CHECK(g.k2 == Approx(std::min(km, kp)).margin(1e-12));
    CHECK(g.gaussianCurvature() * (std::cos(v) > 0 ? 1 : -1) >= -1e-12);
  }
}

TEST_CASE("surfaces: ellipsoid and hyperboloid Gaussian curvatures match the quadric formulas") {
  const double a = 1.3, b = 0.9, c = 0.7;
  const ParametricSurfacePtr e = makeSurface("ellipsoid", {{"a", a}, {"b", b}, {"c", c}});
  for (const Vec2& uv : samples(*e)) {
    const LocalGeometry g = e->geometryAt(uv.x(), uv.y());
    const Vec3 p = g.point;
    CHECK(std::pow(p.x() / a, 2) + std::pow(p.y() / b, 2) + std::pow(p.z() / c, 2) == Approx(1.0).epsilon(1e-12));
    const double s = std::pow(p.x() / (a * a), 2) + std::pow(p.y() / (b * b), 2) + std::pow(p.z() / (c * c), 2);
    CHECK(g.gaussianCurvature() == Approx(1 / (a * a * b * b * c * c * s * s)).epsilon(1e-10));
    CHECK(g.k2 > 0);
  }
  // x^2/a^2 + y^2/a^2 - z^2/c^2 = 1: K = -1 / (a^4 c^2 ((x^2 + y^2)/a^4 + z^2/c^4)^2), -1/c^2 at the waist.
  const double ha = 0.7, hc = 0.5;
  const ParametricSurfacePtr h = makeSurface("hyperboloid", {{"a", ha}, {"c", hc}, {"height", 3.0}});
  CHECK(h->geometryAt(0.4, 0.0).gaussianCurvature() == Approx(-1 / (hc * hc)).epsilon(1e-12));
  for (const Vec2& uv : samples(*h)) {
    const LocalGeometry g = h->geometryAt(uv.x(), uv.y());
    const Vec3 p = g.point;
    const double rho2 = p.x() * p.x() + p.y() * p.y();
    CHECK(rho2 / (ha * ha) - p.z() * p.z() / (hc * hc) == Approx(1.0).epsilon(1e-12));
    const double s = rho2 / std::pow(ha, 4) + std::pow(p.z() / (hc * hc), 2);
    CHECK(g.gaussianCurvature() == Approx(-1 / (std::pow(ha, 4) * hc * hc * s * s)).epsilon(1e-10));
  }
  const ParametricSurface::Domain d = h->domain();
  CHECK(h->position(0, d.v1).z() == Approx(1.5).epsilon(1e-12));
}

TEST_CASE("surfaces: the cyclide satisfies its implicit equation and is a Dupin cyclide") {
  const double a = 1.0, c = 0.35, mu = 0.55, b2 = a * a - c * c;
  const ParametricSurfacePtr s = makeSurface("cyclide", {{"a", a}, {"c", c}, {"mu", mu}});
  for (int i = 0; i < 12; ++i)
    for (int k = 0; k < 12; ++k) {
      const Vec3 p = s->position(0.1 + i * 0.52, 0.2 + k * 0.52);
      const double lhs = std::pow(p.squaredNorm() + b2 - mu * mu, 2) - 4 * std::pow(a * p.x() - c * mu, 2) -
                         4 * b2 * p.y() * p.y();
      CHECK(std::abs(lhs) < 1e-12);
    }
  // Dupin cyclides are the surfaces whose principal curvatures are constant along their own curvature lines;
  // here those are the parameter circles.
  auto curvatureAlong = [&](double u, double v, bool alongU) {
    const LocalGeometry g = s->geometryAt(u, v);
    const ParametricSurface::Jet j = s->jet(u, v);
    const Vec3 t = (alongU ? j.Pu : j.Pv).normalized();
    CHECK(std::min(std::abs(t.dot(g.d1)), std::abs(t.dot(g.d2))) < 1e-8);  // a curvature line
    return std::abs(t.dot(g.d1)) > std::abs(t.dot(g.d2)) ? g.k1 : g.k2;
  };
  for (double fixed : {0.3, 1.9, 4.4}) {
    const double ku = curvatureAlong(0.0, fixed, true), kv = curvatureAlong(fixed, 0.0, false);
    for (double t : {0.8, 2.2, 3.9, 5.5}) {
      CHECK(curvatureAlong(t, fixed, true) == Approx(ku).epsilon(1e-9));
      CHECK(curvatureAlong(fixed, t, false) == Approx(kv).epsilon(1e-9));
    }
  }
  // Elliptic on the outer equator, hyperbolic on the inner one.
  CHECK(s->geometryAt(0.0, M_PI).gaussianCurvature() > 0);
  CHECK(s->geometryAt(0.0, 0.0).gaussianCurvature() < 0);
  // c = 0 is the torus with radii a and mu, with the same orientation.
  const ParametricSurfacePtr ring = makeSurface("cyclide", {{"a", 1.0}, {"c", 0.0}, {"mu", 0.4}});
  const ParametricSurfacePtr torus = makeSurface("torus", {{"R", 1.0}, {"r", 0.4}});
  for (const Vec2& uv : samples(*ring)) {
    const LocalGeometry g = ring->geometryAt(uv.x(), uv.y());
    const LocalGeometry t = torus->closestPoint(g.point);
    CHECK((t.point - g.point).norm() < 1e-10);
    CHECK(t.normal.dot(g.normal) == Approx(1.0).epsilon(1e-10));
    CHECK(g.k1 == Approx(t.k1).epsilon(1e-9));
    CHECK(g.k2 == Approx(t.k2).margin(1e-9));
  }
  // A patch spans the given angles around the outer equator and is not closed.
  const ParametricSurfacePtr patch = makeSurface("cyclide", {{"uSpan", 90.0}, {"vSpan", 120.0}});
  const ParametricSurface::Domain d = patch->domain();
  CHECK(!patch->isClosed());
  CHECK(d.u1 - d.u0 == Approx(M_PI / 2));
  CHECK(0.5 * (d.v0 + d.v1) == Approx(M_PI));
}

TEST_CASE("surfaces: the vase has an elliptic belly, a hyperbolic neck and a parabolic circle between") {
  const double H = 3.0;
  const ParametricSurfacePtr s = makeSurface("vase", {{"height", H}});
  CHECK(s->geometryAt(0.5, H / 4).gaussianCurvature() > 0);
  CHECK(s->geometryAt(0.5, 3 * H / 4).gaussianCurvature() < 0);
  const LocalGeometry g = s->geometryAt(0.5, H / 2);
  CHECK(std::abs(g.k2) < 1e-12 * g.k1);  // the meridian has an inflection: one principal curvature vanishes
  // The other is the parallel circle's normal curvature 1 / (rho sqrt(1 + rho'^2)), with rho = 1, rho' = -A w.
  const double slope = 0.3 * 2 * M_PI / H;
  CHECK(g.k1 == Approx(1 / std::sqrt(1 + slope * slope)).epsilon(1e-12));
}

TEST_CASE("surfaces: paraboloids at the apex, cylinder and cone match the closed forms") {
  const LocalGeometry e = makeSurface("elliptic-paraboloid", {{"ra", 2.0}, {"rb", 0.5}})->geometryAt(0, 0);
  CHECK(e.k1 == Approx(2.0).epsilon(1e-12));
  CHECK(e.k2 == Approx(0.5).epsilon(1e-12));
  CHECK(std::abs(e.d1.y()) == Approx(1.0));
  const LocalGeometry h = makeSurface("hyperbolic-paraboloid", {{"ra", 2.0}, {"rb", 0.5}})->geometryAt(0, 0);
  CHECK(h.k1 == Approx(0.5).epsilon(1e-12));
  CHECK(h.k2 == Approx(-2.0).epsilon(1e-12));
  CHECK(std::abs(h.d1.x()) == Approx(1.0));
  const ParametricSurfacePtr cyl = makeSurface("cylinder", {{"R", 2.0}});
  for (const Vec2& uv : samples(*cyl)) {
    const LocalGeometry g = cyl->geometryAt(uv.x(), uv.y());
    CHECK(g.k1 == Approx(0.5).epsilon(1e-12));
    CHECK(std::abs(g.k2) < 1e-14);
    CHECK(std::abs(g.d2.z()) == Approx(1.0));  // the rulings
  }
  const double alpha = 25 * M_PI / 180;
  const ParametricSurfacePtr cone = makeSurface("cone", {{"angle", 25.0}});
  for (const Vec2& uv : samples(*cone)) {
    const LocalGeometry g = cone->geometryAt(uv.x(), uv.y());
    CHECK(g.k1 == Approx(std::cos(alpha) / std::hypot(g.point.x(), g.point.y())).epsilon(1e-12));
    CHECK(std::abs(g.k2) < 1e-12);
    CHECK(std::abs(g.d2.dot(g.point.normalized())) == Approx(1.0));  // rulings through the apex
  }
  const LocalGeometry p = makeSurface("plane")->geometryAt(0.3, -0.2);
  CHECK(p.k1 == 0);
  CHECK(p.k2 == 0);
}

TEST_CASE("surfaces: Enneper, catenoid and helicoid are minimal with the closed-form K") {
  const ParametricSurfacePtr enneper = makeSurface("enneper");
  for (const Vec2& uv : samples(*enneper)) {
    const LocalGeometry g = enneper->geometryAt(uv.x(), uv.y());
    const double K = -4 / std::pow(1 + uv.squaredNorm(), 4);
    CHECK(std::abs(g.meanCurvature()) < 1e-12 * g.k1);
    CHECK(g.gaussianCurvature() == Approx(K).epsilon(1e-10));
  }
  const double c = 0.8;
  const ParametricSurfacePtr catenoid = makeSurface("catenoid", {{"c", c}});
  for (const Vec2& uv : samples(*catenoid)) {
    const LocalGeometry g = catenoid->geometryAt(uv.x(), uv.y());
    const auto [k1, k2] = fromKH(-1 / (c * c * std::pow(std::cosh(g.point.z() / c), 4)), 0.0);
    CHECK(g.k1 == Approx(k1).epsilon(1e-10));
    CHECK(g.k2 == Approx(k2).epsilon(1e-10));
  }
  const ParametricSurfacePtr helicoid = makeSurface("helicoid", {{"pitch", 3.0}});
  const double hc = 3.0 / (2 * M_PI);
  for (const Vec2& uv : samples(*helicoid)) {
    const LocalGeometry g = helicoid->geometryAt(uv.x(), uv.y());
    const double s2 = uv.x() * uv.x();
    const auto [k1, k2] = fromKH(-hc * hc / std::pow(hc * hc + s2, 2), 0.0);
    CHECK(g.k1 == Approx(k1).epsilon(1e-10));
    CHECK(g.k2 == Approx(k2).epsilon(1e-10));
  }
}

TEST_CASE("surfaces: the free-form height field has elliptic, hyperbolic and parabolic points") {
  const double L = 3.0;
  const ParametricSurfacePtr s = makeSurface("freeform", {{"size", L}});
  CHECK(s->geometryAt(-0.18 * L, -0.12 * L).gaussianCurvature() > 0);  // top of the larger bump
  CHECK(s->geometryAt(0.45 * L, -0.45 * L).gaussianCurvature() > 0);   // the dome far from the bumps
  // Walking out of the bump top along x, K changes sign: a parabolic curve is crossed.
  bool hyperbolic = false;
  for (int i = 1; i <= 30; ++i) hyperbolic |= s->geometryAt(-0.18 * L - i * 0.01 * L, -0.12 * L).gaussianCurvature() < 0;
  CHECK(hyperbolic);
}

TEST_CASE("surfaces: the wave roof has one parabolic curve and no umbilics") {
  // Elliptic where the wave's trough curves like the vault, hyperbolic where its crest curves against it; the
  // parabolic curve between them is x = -(bend / wavenumber) y^2 (the phase 1.5 x + 0.3 y^2 crossing 0).
  const ParametricSurfacePtr s = makeSurface("wave-roof");
  int elliptic = 0, hyperbolic = 0;
  double closestToUmbilic = 1;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j) {
      const double x = -1.5 + 3.0 * i / 40, y = -1.5 + 3.0 * j / 40;
      const LocalGeometry g = s->geometryAt(x, y);
      const double K = g.gaussianCurvature(), onCurve = x + 0.2 * y * y;
      if (std::abs(onCurve) > 0.05) {
        INFO("x " << x << ", y " << y << ", K " << K);
        CHECK((K > 0) == (onCurve < 0));
      }
      elliptic += K > 0;
      hyperbolic += K < 0;
      closestToUmbilic = std::min(closestToUmbilic, std::abs(g.k1 - g.k2) / (std::abs(g.k1) + std::abs(g.k2)));
    }
  CHECK(elliptic > 600);
  CHECK(hyperbolic > 600);
  CHECK(closestToUmbilic > 0.1);  // the curvature lines form one regular net (§5.2's premise)
  CHECK_THROWS_WITH(makeSurface("wave-roof", {{"radius", 1.0}}), Catch::Contains("more than half the side"));
}

TEST_CASE("surfaces: defaults are in range and documented") {
  std::set<std::string> names;
  for (const SurfaceSpec& spec : analyticSurfaces()) {
    INFO(spec.name);
    CHECK(names.insert(spec.name).second);
    CHECK(!spec.description.empty());
    for (const ParameterSpec& p : spec.parameters) {
      CHECK(p.min <= p.defaultValue);
      CHECK(p.defaultValue <= p.max);
      CHECK(!p.description.empty());
    }
    CHECK_NOTHROW(makeSurface(spec.name));
  }
  for (const char* name : {"sphere", "ellipsoid", "torus", "hyperboloid", "cyclide", "vase", "elliptic-paraboloid",
                           "hyperbolic-paraboloid", "cylinder", "cone", "plane", "enneper", "catenoid", "helicoid",
                           "freeform", "wave-roof"})
    CHECK(names.count(name) == 1);
}

TEST_CASE("surfaces: bad names and parameters are rejected with a message") {
  CHECK_THROWS_WITH(makeSurface("teapot"), Catch::Contains("unknown surface 'teapot'"));
  CHECK_THROWS_WITH(makeSurface("torus", {{"R", -1.0}}), Catch::Contains("'R'"));
  CHECK_THROWS_WITH(makeSurface("torus", {{"R", 1.0}, {"r", 2.0}}), Catch::Contains("r must be less than R"));
  CHECK_THROWS_WITH(makeSurface("torus", {{"q", 1.0}}), Catch::Contains("unknown parameter 'q'"));
  CHECK_THROWS_WITH(makeSurface("sphere", {{"R", std::nan("")}}), Catch::Contains("'R'"));
  CHECK_THROWS_WITH(makeSurface("cone", {{"angle", 95.0}}), Catch::Contains("'angle'"));
  CHECK_THROWS_WITH(makeSurface("cone", {{"start", 0.0}}), Catch::Contains("'start'"));
  CHECK_THROWS_WITH(makeSurface("cyclide", {{"c", 0.6}, {"mu", 0.5}}), Catch::Contains("c < mu < a"));
  CHECK_THROWS_WITH(makeSurface("cyclide", {{"mu", 1.5}}), Catch::Contains("c < mu < a"));
  CHECK_THROWS_WITH(makeSurface("vase", {{"bulge", 1.0}}), Catch::Contains("bulge must be less than radius"));
  CHECK_THROWS_WITH(makeSurface("enneper", {{"R", 2.0}}), Catch::Contains("'R'"));
  CHECK_THROWS_WITH(makeSurface("ellipsoid", {{"latitude", 90.0}}), Catch::Contains("'latitude'"));
  CHECK_THROWS_AS(makeSurface("teapot"), Error);
  try {
    makeSurface("hyperboloid", {{"c", 0.0}});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::InvalidParameter);
    CHECK_THAT(e.what(), Catch::Contains("'c'"));
  }
}
