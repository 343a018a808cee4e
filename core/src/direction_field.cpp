#include "phex/direction_field.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "phex/dupin.hpp"
#include "phex/error.hpp"
#include "phex/mesh_surface.hpp"

namespace phex {
namespace {

// The cube root of x > 0 from +, *, / and the exact frexp / ldexp alone, so that every platform rounds it
// alike (libm's cbrt differs between glibc and musl in the last bit, and the step controller below decides
// on it): the exponent's third and the mantissa's root by Newton's method from a linear start, within an
// ulp or two. x <= 0 or not finite: x itself.
double portableCbrt(double x) {
  if (!(x > 0) || !std::isfinite(x)) return x;
  int e = 0;
  double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1)
  const int r = ((e % 3) + 3) % 3;
  m = std::ldexp(m, r);          // m in [0.5, 4), e - r divisible by 3
  double y = 0.6 + 0.4 * m;      // within 20 % of m^(1/3) on [0.5, 4)
  for (int k = 0; k < 6; ++k) y -= (y * y * y - m) / (3 * y * y);
  return std::ldexp(y, (e - r) / 3);
}


constexpr double kPi = 3.14159265358979323846;

// The tangential part of v at g, normalized; nullopt when v is (nearly) normal.
std::optional<Vec3> tangentUnit(const LocalGeometry& g, const Vec3& v) {
  const Vec3 t = v - v.dot(g.normal) * g.normal;
  const double n = t.norm();
  if (!(n > 1e-12 * v.norm()) || !std::isfinite(n)) return std::nullopt;
  return Vec3(t / n);
}

// Every direction is principal at an umbilic or planar point: the principal fields are undefined there.
bool isUmbilic(const LocalGeometry& g, double cell, double tolerance) {
  const double kmax = g.largestCurvature();
  return g.k1 - g.k2 <= tolerance * kmax || kmax * cell <= 1e-9;
}

// Relative k1 - k2 below which a point counts as umbilic: round-off on analytic surfaces, the estimation
// noise of jet-fitted curvature on uploaded meshes.
constexpr double kUmbilicAnalytic = 1e-6, kUmbilicMesh = 0.02;

double parseNumber(const std::string& text, const std::string& whole) {
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(x))
    throw Error(ErrorCode::InvalidParameter, "direction field '" + whole + "': '" + text + "' is not a number");
  return x;
}

}  // namespace

SurfaceWalker::SurfaceWalker(const Surface& surface, double cell)
    : surface_(surface), parametric_(dynamic_cast<const ParametricSurface*>(&surface)), cell_(cell) {
  if (!(cell > 0) || !std::isfinite(cell))
    throw Error(ErrorCode::InvalidParameter, "cell size must be positive and finite");
}

SurfacePoint SurfaceWalker::project(const Vec3& p) const {
  const LocalGeometry g = surface_.closestPoint(p);
  if (!parametric_) return {g, Vec2::Zero()};
  // closestPoint does not return parameters: refine from the nearest parameter of a coarse grid.
  const ParametricSurface::Domain d = parametric_->domain();
  Vec2 best(d.u0, d.v0);
  double bestDistance = std::numeric_limits<double>::infinity();
  constexpr int n = 32;
  for (int i = 0; i <= n; ++i)
    for (int k = 0; k <= n; ++k) {
      const Vec2 uv(d.u0 + (d.u1 - d.u0) * i / n, d.v0 + (d.v1 - d.v0) * k / n);
      const double dist = (parametric_->position(uv.x(), uv.y()) - g.point).squaredNorm();
      if (dist < bestDistance) bestDistance = dist, best = uv;
    }
  const Vec2 uv = parametric_->project(g.point, best);
  return {parametric_->geometryAt(uv.x(), uv.y()), uv};
}

SurfacePoint SurfaceWalker::project(const Vec3& p, const SurfacePoint& near) const {
  if (!parametric_) return {surface_.closestPoint(p), Vec2::Zero()};
  const Vec2 uv = parametric_->project(p, near.uv);
  return {parametric_->geometryAt(uv.x(), uv.y()), uv};
}

bool SurfaceWalker::isOutside(const Vec3& p, const SurfacePoint& foot) const {
  const Vec3 t = p - foot.point();
  return (t - t.dot(foot.g.normal) * foot.g.normal).norm() > outsideTolerance();
}

Vec3 sectionPlaneNormal(const Surface& surface, double degrees) {
  // The principal axes of some 400 samples: the normal of their mean plane (least variance) and their longest
  // extent (most); the cutting planes contain the normal and the longest extent turned by `degrees`.
  const std::vector<LocalGeometry> samples = surface.samples(400);
  Vec3 mean = Vec3::Zero();
  for (const LocalGeometry& g : samples) mean += g.point;
  mean /= double(std::max<std::size_t>(samples.size(), 1));
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const LocalGeometry& g : samples) covariance += (g.point - mean) * (g.point - mean).transpose();
  Vec3 up = Vec3::UnitZ(), along = Vec3::UnitX();
  if (samples.size() >= 3) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes(covariance);  // eigenvalues ascending
    if (axes.info() == Eigen::Success && axes.eigenvalues()(2) > 0) {
      up = axes.eigenvectors().col(0);
      along = axes.eigenvectors().col(2);
    }
  }
  Eigen::Index largest = 0;
  up.cwiseAbs().maxCoeff(&largest);
  if (up(largest) < 0) up = -up;
  along.cwiseAbs().maxCoeff(&largest);
  if (along(largest) < 0) along = -along;
  const double rad = degrees * kPi / 180;
  const Vec3 across = up.cross(along).normalized();
  return Vec3(-std::sin(rad) * along + std::cos(rad) * across);
}

FieldSpec parseFieldSpec(const std::string& text) {
  const std::size_t colon = text.find(':');
  const std::string name = text.substr(0, colon);
  const bool hasArgument = colon != std::string::npos;
  const std::string argument = hasArgument ? text.substr(colon + 1) : "";
  FieldSpec spec;
  auto noArgument = [&] {
    if (hasArgument)
      throw Error(ErrorCode::InvalidParameter, "direction field '" + text + "': '" + name + "' takes no value");
  };
  auto degreesIn = [&](double lo, double hi, double fallback) {
    if (!hasArgument) return fallback;
    const double x = parseNumber(argument, text);
    if (x < lo || x > hi) {
      std::ostringstream msg;
      msg << "direction field '" << text << "': " << x << " degrees is outside [" << lo << ", " << hi << "]";
      throw Error(ErrorCode::InvalidParameter, msg.str());
    }
    return x;
  };
  if (name == "principal") {
    noArgument();
    spec.kind = FieldKind::Principal;
  } else if (name == "angle") {
    if (!hasArgument)
      throw Error(ErrorCode::InvalidParameter, "direction field '" + text + "': write angle:DEG, e.g. angle:30");
    spec.kind = FieldKind::Angle;
    spec.degrees = degreesIn(-180, 180, 0);
  } else if (name == "param") {
    spec.kind = FieldKind::Param;
    if (hasArgument && argument != "u" && argument != "v")
      throw Error(ErrorCode::InvalidParameter, "direction field '" + text + "': write param, param:u or param:v");
    spec.paramV = argument == "v";
  } else if (name == "radial") {
    noArgument();
    spec.kind = FieldKind::Radial;
  } else if (name == "diverging") {
    spec.kind = FieldKind::Diverging;
    spec.degrees = degreesIn(0, 89, 20);
  } else if (name == "spiral") {
    spec.kind = FieldKind::Spiral;
    spec.degrees = degreesIn(-89, 89, 45);
  } else if (name == "section") {
    spec.kind = FieldKind::Section;
    spec.degrees = degreesIn(-180, 180, 0);
  } else {
    throw Error(ErrorCode::InvalidParameter, "unknown direction field '" + text +
                                                 "' (known: principal, angle:DEG, param, param:v, radial, "
                                                 "diverging[:DEG], spiral[:DEG], section[:DEG])");
  }
  return spec;
}

std::string fieldSpecName(const FieldSpec& spec) {
  std::ostringstream s;
  switch (spec.kind) {
    case FieldKind::Principal: s << "principal"; break;
    case FieldKind::Angle: s << "angle:" << spec.degrees; break;
    case FieldKind::Param: s << (spec.paramV ? "param:v" : "param:u"); break;
    case FieldKind::Radial: s << "radial"; break;
    case FieldKind::Diverging: s << "diverging:" << spec.degrees; break;
    case FieldKind::Spiral: s << "spiral:" << spec.degrees; break;
    case FieldKind::Section: s << "section:" << spec.degrees; break;
  }
  return s.str();
}

DirectionField::DirectionField(const SurfaceWalker& walker, const FieldSpec& spec) : walker_(walker), spec_(spec) {
  if (spec.kind == FieldKind::Param && !walker.parametric())
    throw Error(ErrorCode::InvalidParameter, "direction field 'param' needs a parametric surface, and '" +
                                                 walker.surface().name() + "' is not one");
  const double tilt = spec.kind == FieldKind::Diverging ? spec.degrees * kPi / 180 : 0.0;
  axis_ = Vec3(std::sin(tilt), 0, std::cos(tilt));
  centre_ = walker.surface().bounds().center();
  if (spec.kind == FieldKind::Section) sectionNormal_ = sectionPlaneNormal(walker.surface(), spec.degrees);
  const auto* mesh = dynamic_cast<const MeshSurface*>(&walker.surface());
  rulings_ = mesh && mesh->developable();
}

std::optional<Vec3> DirectionField::meridian(const SurfacePoint& p) const {
  // The section by the plane through the axis and p.
  const Vec3 planeNormal = axis_.cross(p.point() - centre_);
  if (!(planeNormal.norm() > 1e-9 * std::max(walker_.cell(), (p.point() - centre_).norm()))) return std::nullopt;
  return tangentUnit(p.g, p.g.normal.cross(planeNormal));
}

bool DirectionField::isUmbilic(const LocalGeometry& g) const {
  // A flat apron of a vault: the meridians about the bounds' centre laid its rows in arcs, the seams with the
  // rows along the rulings left 115 faces off planar (a sampled vault on a flat apron at 1000 faces).
  if (rulings_) return false;
  return phex::isUmbilic(g, walker_.cell(), walker_.parametric() ? kUmbilicAnalytic : kUmbilicMesh);
}

std::optional<Vec3> DirectionField::first(const SurfacePoint& p) const {
  const LocalGeometry& g = p.g;
  const double rad = spec_.degrees * kPi / 180;
  auto rotated = [&](const std::optional<Vec3>& d) -> std::optional<Vec3> {
    if (!d) return d;
    return Vec3(std::cos(rad) * *d + std::sin(rad) * g.normal.cross(*d));
  };
  switch (spec_.kind) {
    case FieldKind::Principal:
    case FieldKind::Angle:
      // At an umbilic every direction is principal; a sphere's curvature lines are then taken as its meridians
      // and parallels about z, so that a sphere laid with "principal" gets the radial network (Fig. 20).
      return isUmbilic(g) ? rotated(meridian(p)) : rotated(g.d1);
    case FieldKind::Param: {
      const ParametricSurface::Jet j = walker_.parametric()->jet(p.uv.x(), p.uv.y());
      return tangentUnit(g, spec_.paramV ? j.Pv : j.Pu);
    }
    case FieldKind::Radial:
    case FieldKind::Diverging:
      return meridian(p);
    case FieldKind::Spiral:
      return rotated(meridian(p));  // loxodrome: a fixed angle to the meridians
    case FieldKind::Section:
      return tangentUnit(g, g.normal.cross(sectionNormal_));  // the section curve's tangent
  }
  return std::nullopt;
}

std::optional<Vec3> DirectionField::direction(const SurfacePoint& p, Family family, const Vec3* previous) const {
  const LocalGeometry& g = p.g;
  std::optional<Vec3> d = first(p);
  const bool umbilic = isUmbilic(g);
  // Where the field is undefined because the point is umbilic (principal), or the tangent plane is the cutting
  // plane itself (section), any direction is as good as another and the line goes straight on.
  bool anyIsFine = !d && (spec_.kind == FieldKind::Principal || spec_.kind == FieldKind::Angle ||
                          spec_.kind == FieldKind::Section);
  // The conjugate direction of v, or nullopt at a parabolic point, where the zero-curvature direction is
  // conjugate to every direction (§5.3).
  auto conjugateOf = [&](const Vec3& v) -> std::optional<Vec3> {
    // Principal directions (all, at an umbilic) are conjugate and orthogonal.
    if (spec_.kind == FieldKind::Principal || umbilic) return Vec3(g.normal.cross(v));
    const std::optional<Vec2> c = conjugateDirection(g, tangentVector(g, v));
    return c ? std::optional<Vec3>(spatialVector(g, *c)) : std::nullopt;
  };
  if (d && spec_.kind == FieldKind::Principal && previous) {
    // Curvature lines by continuity, not by label: where k1 and k2 cross (an umbilic curve, e.g. on a surface
    // of revolution) d1 and d2 swap, and a line following d1 would turn by 90 degrees. The same across an
    // umbilic region, where the meridian or its perpendicular stands in for them.
    const Vec3 other = g.normal.cross(*d);
    if (std::abs(other.dot(*previous)) > std::abs(d->dot(*previous))) d = other;
  } else if (d && spec_.kind == FieldKind::Angle && previous) {
    // The same for the principal directions turned by an angle: across an umbilic curve d1 and d2 swap, and
    // a line of d1 turned by 30 degrees would turn by 90 there; so would its conjugate lines. Of the two
    // turned principal directions (or their conjugates) the one nearer the line's own direction is followed.
    // The vase laid along angle:90 or angle:0 met its umbilic circle in the belly and gave up there, with
    // rows along the asymptotic direction, where "principal" (followed by continuity) lays it whole.
    std::optional<Vec3> candidates[2] = {d, Vec3(g.normal.cross(*d))};
    if (family == Family::Conjugate)
      for (std::optional<Vec3>& c : candidates) c = conjugateOf(*c);
    auto nearness = [&](const std::optional<Vec3>& c) { return c ? std::abs(c->dot(*previous)) : -1.0; };
    d = nearness(candidates[1]) > nearness(candidates[0]) ? candidates[1] : candidates[0];
    anyIsFine = !d;
  } else if (d && family == Family::Conjugate) {
    d = conjugateOf(*d);
    anyIsFine = !d;
  }
  if (!d && anyIsFine && previous) d = tangentUnit(g, *previous);
  if (d && previous && d->dot(*previous) < 0) *d = -*d;
  return d;
}

double polylineLength(const std::vector<SurfacePoint>& polyline, bool closed) {
  double length = 0;
  for (std::size_t i = 1; i < polyline.size(); ++i) length += (polyline[i].point() - polyline[i - 1].point()).norm();
  if (closed && polyline.size() > 1) length += (polyline.front().point() - polyline.back().point()).norm();
  return length;
}

FlowTracer::FlowTracer(const DirectionField& field, Family family, const SurfacePoint& start, const Vec3& initial,
                       double maxLength, bool detectClosure)
    : field_(&field), family_(family), start_(start), current_(start), maxLength_(maxLength),
      detectClosure_(detectClosure) {
  line_.points.push_back(start);
  const std::optional<Vec3> k1 = field.direction(start, family, &initial);
  if (!k1) {
    line_.end = FlowLine::End::Singularity;
    finished_ = true;
    return;
  }
  startDirection_ = k1_ = *k1;
  h_ = 0.25 * field.walker().cell();
}

bool FlowTracer::advance(double upTo) {
  while (!finished_ && line_.length < upTo) attempt();
  return finished_;
}

void FlowTracer::attempt() {
  const SurfaceWalker& walker = field_->walker();
  const double cell = walker.cell(), tolerance = 1e-4 * cell, maxStep = 0.5 * cell, minStep = 1e-3 * cell;
  auto end = [&](FlowLine::End how) {
    line_.end = how;
    finished_ = true;
  };
  if (!(line_.length < maxLength_)) return end(FlowLine::End::Length);
  double& h = h_;
  h = std::min(h, maxLength_ - line_.length);
  if (h < 1e-9 * cell) return end(FlowLine::End::Length);
  // Bogacki–Shampine RK 3(2) in space; each stage is evaluated at the projection of its point.
  const Vec3 x = current_.point();
  const SurfacePoint p2 = walker.project(x + 0.5 * h * k1_, current_);
  const std::optional<Vec3> k2 = field_->direction(p2, family_, &k1_);
  const std::optional<Vec3> k3 =
      k2 ? field_->direction(walker.project(x + 0.75 * h * *k2, current_), family_, &*k2) : std::nullopt;
  if (!k3) {
    if (h > minStep) {
      h *= 0.25;
      return;
    }
    return end(FlowLine::End::Singularity);
  }
  const Vec3 next = x + h * (2.0 / 9 * k1_ + 1.0 / 3 * *k2 + 4.0 / 9 * *k3);
  const SurfacePoint pn = walker.project(next, current_);
  if (walker.isOutside(next, pn)) {
    // Locate the boundary crossing by bisection on the step.
    double inside = 0, outside = 1;
    SurfacePoint last = current_;
    for (int it = 0; it < 10; ++it) {
      const double t = 0.5 * (inside + outside);
      const Vec3 q = x + t * (next - x);
      const SurfacePoint pq = walker.project(q, current_);
      if (walker.isOutside(q, pq)) {
        outside = t;
      } else {
        inside = t;
        last = pq;
      }
    }
    if (inside > 0) {
      line_.length += (last.point() - x).norm();
      line_.points.push_back(last);
    }
    return end(FlowLine::End::Boundary);
  }
  const std::optional<Vec3> k4 = field_->direction(pn, family_, &*k3);
  const double error = h * (-5.0 / 72 * k1_ + 1.0 / 12 * *k2 + 1.0 / 9 * *k3 - 1.0 / 8 * k4.value_or(*k3)).norm();
  if (error > tolerance && h > minStep) {
    h *= std::max(0.2, 0.9 * portableCbrt(tolerance / error));
    return;
  }
  const double segment = (pn.point() - x).norm();
  if (segment < 0.25 * h) {
    // The projection does not follow the step: the foot is held at a trimmed edge within the tolerance.
    return end(FlowLine::End::Boundary);
  }
  if (detectClosure_ && line_.length + segment > 3 * cell) {
    // Back at the start, heading the same way: a loop. Close it exactly at the start.
    const Vec3 s = pn.point() - x;
    const double t = std::clamp((start_.point() - x).dot(s) / std::max(s.squaredNorm(), 1e-300), 0.0, 1.0);
    if ((x + t * s - start_.point()).norm() < 0.25 * cell && s.dot(startDirection_) > 0.5 * segment) {
      line_.length += (start_.point() - x).norm();
      return end(FlowLine::End::Closed);
    }
  }
  line_.points.push_back(pn);
  line_.length += segment;
  current_ = pn;
  if (!k4) return end(FlowLine::End::Singularity);
  k1_ = *k4;
  h = std::min(maxStep, h * std::min(4.0, 0.9 * portableCbrt(tolerance / std::max(error, 1e-300))));
}

FlowLine traceFlowLine(const DirectionField& field, Family family, const SurfacePoint& start, const Vec3& initial,
                       double maxLength, bool detectClosure) {
  FlowTracer tracer(field, family, start, initial, maxLength, detectClosure);
  tracer.finish();
  return tracer.release();
}

std::vector<SurfacePoint> sampleByArcLength(const SurfaceWalker& walker, const std::vector<SurfacePoint>& polyline,
                                            bool closed, double spacing) {
  std::vector<SurfacePoint> samples;
  if (polyline.empty()) return samples;
  std::vector<SurfacePoint> path = polyline;
  if (closed) path.push_back(polyline.front());
  std::vector<double> arc(path.size(), 0.0);
  for (std::size_t i = 1; i < path.size(); ++i) arc[i] = arc[i - 1] + (path[i].point() - path[i - 1].point()).norm();
  const double length = arc.back();
  int count;
  double step = spacing;
  if (closed) {
    count = std::max(3, static_cast<int>(std::lround(length / spacing)));
    step = length / count;
  } else {
    count = static_cast<int>(std::floor(length / spacing + 1e-9)) + 1;
  }
  std::size_t k = 1;
  for (int i = 0; i < count; ++i) {
    const double t = i * step;
    while (k + 1 < path.size() && arc[k] < t) ++k;
    const double span = arc[k] - arc[k - 1];
    const double w = span > 0 ? std::clamp((t - arc[k - 1]) / span, 0.0, 1.0) : 0.0;
    if (w == 0.0) {
      samples.push_back(path[k - 1]);
    } else {
      const Vec3 q = (1 - w) * path[k - 1].point() + w * path[k].point();
      samples.push_back(walker.project(q, path[k - 1]));
    }
  }
  return samples;
}

}  // namespace phex
