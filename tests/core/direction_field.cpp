#include <catch.hpp>

#include <cmath>

#include "phex/direction_field.hpp"
#include "phex/error.hpp"
#include "phex/surfaces.hpp"

using namespace phex;

TEST_CASE("direction_field: names parse, bad ones are rejected by name") {
  CHECK(parseFieldSpec("principal").kind == FieldKind::Principal);
  const FieldSpec angle = parseFieldSpec("angle:30");
  CHECK(angle.kind == FieldKind::Angle);
  CHECK(angle.degrees == 30);
  CHECK(parseFieldSpec("param:v").paramV);
  CHECK(parseFieldSpec("spiral").degrees == 45);
  CHECK(parseFieldSpec("diverging:10").degrees == 10);
  CHECK(fieldSpecName(parseFieldSpec("spiral:30")) == "spiral:30");
  CHECK(parseFieldSpec("section").kind == FieldKind::Section);
  CHECK(parseFieldSpec("section").degrees == 0);
  CHECK(fieldSpecName(parseFieldSpec("section:-45")) == "section:-45");
  for (const char* bad : {"angle", "angle:x", "angle:400", "spiral:90", "principal:2", "param:w", "zigzag", "section:181",
                          "section:x", ""}) {
    INFO(bad);
    try {
      parseFieldSpec(bad);
      FAIL("accepted");
    } catch (const Error& e) {
      CHECK(e.code() == ErrorCode::InvalidParameter);
      CHECK(std::string(e.what()).find("'" + std::string(bad)) != std::string::npos);
    }
  }
}

TEST_CASE("direction_field: param needs a parametric surface; conjugate fields are conjugate") {
  const ParametricSurfacePtr torus = makeSurface("torus");
  const SurfaceWalker walker(*torus, 0.1);
  const DirectionField angle(walker, parseFieldSpec("angle:30"));
  const SurfacePoint p = walker.project(Vec3(1.3, 0.2, 0.2));
  const Vec3 f = *angle.direction(p, Family::First), g = *angle.direction(p, Family::Conjugate);
  // II(f, g) = 0 in the principal frame.
  const double II = p.g.k1 * f.dot(p.g.d1) * g.dot(p.g.d1) + p.g.k2 * f.dot(p.g.d2) * g.dot(p.g.d2);
  CHECK(std::abs(II) < 1e-12);
  CHECK(std::abs(f.dot(p.g.normal)) < 1e-12);
  CHECK(std::abs(f.dot(p.g.d1)) == Approx(std::cos(30 * 3.141592653589793 / 180)).epsilon(1e-9));
  // The sign follows `previous`.
  const Vec3 back = -f;
  CHECK(angle.direction(p, Family::First, &back)->dot(back) > 0.99);
}

TEST_CASE("direction_field: flow lines close around a torus and stop at the boundary of a sphere band") {
  const ParametricSurfacePtr torus = makeSurface("torus");  // R = 1, r = 0.4
  const SurfaceWalker walker(*torus, 0.05);
  const DirectionField principal(walker, parseFieldSpec("principal"));
  // A parallel (a curvature line) on the outer equator: a circle of radius 1.4.
  const SurfacePoint start = walker.project(Vec3(1.4, 0, 0));
  const FlowLine parallel = traceFlowLine(principal, Family::Conjugate, start, Vec3(0, 1, 0), 100.0);
  REQUIRE(parallel.end == FlowLine::End::Closed);
  CHECK(parallel.length == Approx(2 * 3.141592653589793 * 1.4).epsilon(1e-3));
  for (const SurfacePoint& q : parallel.points) CHECK(std::abs(q.point().z()) < 1e-3);
  const std::vector<SurfacePoint> samples = sampleByArcLength(walker, parallel.points, true, 0.05);
  CHECK(samples.size() == 176);  // round(2 pi 1.4 / 0.05)
  for (std::size_t i = 0; i < samples.size(); ++i)
    CHECK((samples[i].point() - samples[(i + 1) % samples.size()].point()).norm() == Approx(0.04998).epsilon(2e-3));

  // A meridian of the sphere band (latitudes -60..60) ends at the boundary.
  const ParametricSurfacePtr sphere = makeSurface("sphere");
  const SurfaceWalker sw(*sphere, 0.05);
  const DirectionField radial(sw, parseFieldSpec("radial"));
  const FlowLine meridian = traceFlowLine(radial, Family::First, sw.project(Vec3(1, 0, 0)), Vec3(0, 0, 1), 100.0);
  REQUIRE(meridian.end == FlowLine::End::Boundary);
  CHECK(meridian.points.back().point().z() == Approx(std::sin(3.141592653589793 / 3)).epsilon(0.01));
  CHECK(meridian.length == Approx(3.141592653589793 / 3).epsilon(0.01));
  CHECK(std::abs(meridian.points.back().point().y()) < 1e-6);
}

TEST_CASE("direction_field: loxodromes keep their angle to the meridians") {
  const ParametricSurfacePtr sphere = makeSurface("sphere");
  const SurfaceWalker sw(*sphere, 0.05);
  const DirectionField spiral(sw, parseFieldSpec("spiral:45"));
  const FlowLine line = traceFlowLine(spiral, Family::First, sw.project(Vec3(1, 0, 0)), Vec3(0, 1, 1), 100.0);
  REQUIRE(line.end == FlowLine::End::Boundary);
  // Mercator: a 45-degree loxodrome from the equator to latitude 60 turns by ln tan(75 deg) in longitude.
  const Vec3 end = line.points.back().point();
  CHECK(std::abs(std::atan2(end.y(), end.x())) == Approx(std::log(std::tan(75 * 3.141592653589793 / 180))).epsilon(0.01));
}

TEST_CASE("direction_field: a flow line traced in installments is the one traced in one go") {
  const ParametricSurfacePtr torus = makeSurface("torus");
  const SurfaceWalker walker(*torus, 0.05);
  const DirectionField angle(walker, parseFieldSpec("angle:30"));
  const SurfacePoint start = walker.project(Vec3(1.3, 0.2, 0.2));
  for (const bool closure : {false, true}) {
    const FlowLine whole = traceFlowLine(angle, Family::Conjugate, start, Vec3(0, 0, 1), 2.0, closure);
    FlowTracer tracer(angle, Family::Conjugate, start, Vec3(0, 0, 1), 2.0, closure);
    for (double upTo = 0.01; !tracer.finished() && upTo < 1.0; upTo *= 1.7) {
      CHECK_FALSE(tracer.advance(upTo));
      CHECK(tracer.line().length >= upTo);
    }
    const FlowLine& pieces = tracer.finish();
    CHECK(tracer.finished());
    CHECK(pieces.end == whole.end);
    CHECK(pieces.length == whole.length);
    REQUIRE(pieces.points.size() == whole.points.size());
    for (std::size_t i = 0; i < whole.points.size(); ++i) {
      CHECK(pieces.points[i].point() == whole.points[i].point());
      CHECK(pieces.points[i].uv == whole.points[i].uv);
    }
  }
  // Ends are reported as in one go: the boundary of a sphere band.
  const ParametricSurfacePtr sphere = makeSurface("sphere");
  const SurfaceWalker sw(*sphere, 0.05);
  const DirectionField radial(sw, parseFieldSpec("radial"));
  FlowTracer meridian(radial, Family::First, sw.project(Vec3(1, 0, 0)), Vec3(0, 0, 1), 100.0);
  CHECK_FALSE(meridian.advance(0.5));
  CHECK(meridian.advance(5.0));
  CHECK(meridian.line().end == FlowLine::End::Boundary);
  CHECK(meridian.line().length == traceFlowLine(radial, Family::First, sw.project(Vec3(1, 0, 0)), Vec3(0, 0, 1), 100.0).length);
}

TEST_CASE("direction_field: plane sections stand on the mean plane, pass the umbilic, and have conjugates") {
  // A paraboloid of revolution over a square: the mean plane is z = const, so the cutting planes stand upright.
  const ParametricSurfacePtr dome = makeSurface("elliptic-paraboloid", {{"ra", 1.0}, {"rb", 1.0}});
  const SurfaceWalker walker(*dome, 0.1);
  const Vec3 planes = sectionPlaneNormal(*dome, 0);
  CHECK(std::abs(planes.z()) < 1e-9);  // the cutting planes are vertical
  CHECK(std::abs(sectionPlaneNormal(*dome, 90).dot(planes)) < 1e-9);
  const DirectionField section(walker, parseFieldSpec("section"));
  for (const Vec3& q : {Vec3(0, 0, 0), Vec3(0.6, -0.3, 0), Vec3(-0.8, 0.7, 0)}) {
    const SurfacePoint p = walker.project(q + Vec3(0, 0, 1));
    INFO(p.point().transpose());
    const std::optional<Vec3> f = section.direction(p, Family::First), g = section.direction(p, Family::Conjugate);
    REQUIRE(f);
    REQUIRE(g);
    CHECK(std::abs(f->dot(planes)) < 1e-9);         // within the cutting plane
    CHECK(std::abs(f->dot(p.g.normal)) < 1e-9);     // and tangent
    const double II = p.g.k1 * f->dot(p.g.d1) * g->dot(p.g.d1) + p.g.k2 * f->dot(p.g.d2) * g->dot(p.g.d2);
    CHECK(std::abs(II) < 1e-9 * std::abs(p.g.k1));  // conjugate
    CHECK(std::abs(f->dot(*g)) < 0.999);             // and not the same direction
  }
  // A flow line through the apex (an umbilic) runs straight through it, along the section.
  const SurfacePoint apex = walker.project(Vec3(0, 0.02, 1));
  const FlowLine line = traceFlowLine(section, Family::First, apex, Vec3(1, 1, 0), 1.0, false);
  CHECK(line.end != FlowLine::End::Singularity);
  for (const SurfacePoint& q : line.points) CHECK(std::abs((q.point() - apex.point()).dot(planes)) < 1e-3);
}
