#include <catch.hpp>
#include <cmath>

#include "phex/error.hpp"
#include "phex/surfaces.hpp"

using namespace phex;

TEST_CASE("surfaces: sphere has k1 = k2 = 1/R and outward normals") {
  const SurfacePtr s = makeSurface("sphere", {{"R", 2.0}});
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
  const SurfacePtr s = makeSurface("torus", {{"R", R}, {"r", r}});
  for (double v : {-2.5, -1.0, 0.0, 0.7, 3.0}) {
    const LocalGeometry g = s->geometryAt(0.3, v);
    // Meridian curvature 1/r; parallel curvature cos v / (R + r cos v).
    const double km = 1.0 / r, kp = std::cos(v) / (R + r * std::cos(v));
    CHECK(g.k1 == Approx(std::max(km, kp)).epsilon(1e-10));
    CHECK(g.k2 == Approx(std::min(km, kp)).margin(1e-12));
    CHECK(g.gaussianCurvature() * (std::cos(v) > 0 ? 1 : -1) >= -1e-12);
  }
}

TEST_CASE("surfaces: closest point projects onto the surface") {
  const SurfacePtr s = makeSurface("torus");
  const Vec3 p(1.3, 0.4, 0.5);
  const LocalGeometry g = s->closestPoint(p);
  // The foot point lies on the torus and p - foot is along the normal.
  const double rho = std::hypot(g.point.x(), g.point.y());
  CHECK(std::hypot(rho - 1.0, g.point.z()) == Approx(0.4).epsilon(1e-10));
  CHECK((p - g.point).normalized().cross(g.normal).norm() < 1e-8);
}

TEST_CASE("surfaces: bad names and parameters are rejected with a message") {
  CHECK_THROWS_WITH(makeSurface("teapot"), Catch::Contains("unknown surface 'teapot'"));
  CHECK_THROWS_WITH(makeSurface("torus", {{"R", -1.0}}), Catch::Contains("'R'"));
  CHECK_THROWS_WITH(makeSurface("torus", {{"R", 1.0}, {"r", 2.0}}), Catch::Contains("r must be less than R"));
  CHECK_THROWS_WITH(makeSurface("torus", {{"q", 1.0}}), Catch::Contains("unknown parameter 'q'"));
  CHECK_THROWS_WITH(makeSurface("sphere", {{"R", std::nan("")}}), Catch::Contains("'R'"));
  CHECK_THROWS_AS(makeSurface("teapot"), Error);
}
