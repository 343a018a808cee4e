// phex — direction fields on a surface and their flow lines: the conjugate curve networks along which
// triangulations are laid (§5.2, §7).
//
// Everything works on any Surface in 3D: a step is taken in space and projected back onto the surface, so an
// uploaded MeshSurface serves as well as an analytic one. Lengths are in model units.
#pragma once
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "phex/surface.hpp"

namespace phex {

// A point of the surface with its local geometry. uv holds its parameters when the surface is a
// ParametricSurface (then projections start from them), and is unused otherwise.
struct SurfacePoint {
  LocalGeometry g;
  Vec2 uv = Vec2::Zero();
  const Vec3& point() const { return g.point; }
};

// Projects points of space onto a surface: by Newton's method from a nearby point's parameters on a
// ParametricSurface (fast, and it keeps uv), by closestPoint otherwise (a MeshSurface).
class SurfaceWalker {
 public:
  // cell > 0: the edge length of the triangulation being laid, the unit of every tolerance below.
  SurfaceWalker(const Surface& surface, double cell);

  // The surface point nearest to p, searched globally.
  SurfacePoint project(const Vec3& p) const;
  // The surface point nearest to p, for p within a few cells of `near`.
  SurfacePoint project(const Vec3& p, const SurfacePoint& near) const;
  // True when p lies beyond the boundary of a trimmed surface: p - foot.point (foot = its projection) has a
  // tangential component longer than outsideTolerance() (on an untrimmed surface that component vanishes).
  bool isOutside(const Vec3& p, const SurfacePoint& foot) const;

  const Surface& surface() const { return surface_; }
  const ParametricSurface* parametric() const { return parametric_; }
  double cell() const { return cell_; }
  double outsideTolerance() const { return 0.05 * cell_; }

 private:
  const Surface& surface_;
  const ParametricSurface* parametric_;
  double cell_;
};

// Which direction field; parsed from the strings of `parseFieldSpec`.
enum class FieldKind {
  Principal,  // "principal": curvature lines, d1 (its conjugate is d2); at umbilics the meridians of "radial"
  Angle,      // "angle:DEG": d1 rotated by DEG degrees in the tangent plane
  Param,      // "param" / "param:u" (Pu), "param:v" (Pv): parameter lines, ParametricSurface only
  Radial,     // "radial": meridians, the plane sections through the z axis through the centre of the bounds
  Diverging,  // "diverging" / "diverging:DEG": meridians of an axis tilted DEG (default 20) from z towards x;
              // they fan out from one side of the surface to the other (Fig. 20, middle)
  Spiral,     // "spiral" / "spiral:DEG": loxodromes, crossing the meridians of "radial" at DEG (default 45)
  Section     // "section" / "section:DEG": plane sections by parallel planes standing on the surface's mean plane,
              // along its longest extent turned by DEG (default 0) about its normal. Free of singularities on
              // any height field over that plane, umbilics included (a dome's top), where the curvature lines
              // of "principal" turn around them; with its conjugate a conjugate network on the elliptic part
};

struct FieldSpec {
  FieldKind kind = FieldKind::Principal;
  double degrees = 0;   // Angle: rotation; Diverging: axis tilt; Spiral: angle to the meridians; Section: turn
  bool paramV = false;  // Param: follow Pv instead of Pu
};

// Parses a field name as listed at FieldKind; throws Error(InvalidParameter) naming the bad value.
FieldSpec parseFieldSpec(const std::string& text);
// The canonical string of a spec, e.g. "angle:30".
std::string fieldSpecName(const FieldSpec& spec);
// The normal of the cutting planes of "section:DEG" on `surface`: the planes contain the normal of the
// samples' mean plane and their longest extent turned by `degrees` about it (axes from principal component
// analysis, signed so that the largest component of each is positive).
Vec3 sectionPlaneNormal(const Surface& surface, double degrees);

// The two families of a conjugate network (§5.2): D_F, the field itself, and D_G, its conjugate.
enum class Family { First, Conjugate };

// A line field (sign-free) and its conjugate field on a surface.
class DirectionField {
 public:
  // Throws Error(InvalidParameter) for "param" on a surface that is not a ParametricSurface.
  DirectionField(const SurfaceWalker& walker, const FieldSpec& spec);

  // The unit tangent of `family` at p, signed to agree with `previous` when given (a line field has no sign;
  // flow lines keep it continuous). nullopt at a singularity of the field: a point where the axis meets the
  // surface at right angles for the meridian fields (and for "principal" / "angle" at an umbilic, where they
  // follow the meridians), and for the conjugate family a parabolic point whose zero-curvature direction is
  // the field itself (§5.3: it is conjugate to every direction). Where the directions are undefined because
  // any direction is as good as any other there (planar points, such parabolic points), `previous` projected
  // onto the tangent plane is continued. For "principal" with `previous` given, the family is the
  // curvature line nearest to `previous` (continuity across curves where k1 and k2 swap labels).
  std::optional<Vec3> direction(const SurfacePoint& p, Family family, const Vec3* previous = nullptr) const;

  // Whether g is an umbilic (or planar point) for this field: k1 - k2 within round-off of kmax on an analytic
  // surface, within 2 % on an uploaded mesh, whose estimated curvatures are that noisy (a sampled sphere's
  // principal directions are noise). Never on an uploaded developable (MeshSurface::developable): its planar
  // points (a flat apron, an inflection ruling) carry the direction of the rulings around them.
  bool isUmbilic(const LocalGeometry& g) const;

  const FieldSpec& spec() const { return spec_; }
  const SurfaceWalker& walker() const { return walker_; }

 private:
  std::optional<Vec3> first(const SurfacePoint& p) const;
  std::optional<Vec3> meridian(const SurfacePoint& p) const;

  const SurfaceWalker& walker_;
  FieldSpec spec_;
  Vec3 axis_, centre_;  // the meridian fields' axis
  Vec3 sectionNormal_ = Vec3::UnitY();  // "section": the normal of the cutting planes
  bool rulings_ = false;  // an uploaded developable
};

// A traced flow line: points on the surface from the start, in the traced direction.
struct FlowLine {
  enum class End {
    Length,       // the requested length was reached
    Boundary,     // the line left the trimmed surface (the last point is within a tolerance of the boundary)
    Closed,       // the line came back to its start: it is a loop, the start is not repeated at the end
    Singularity   // the field is undefined ahead (see DirectionField::direction)
  };
  std::vector<SurfacePoint> points;
  End end = End::Length;
  double length = 0;  // arc length of the polyline (closing segment included for a loop)
};

// Traces the flow line of `family` from `start`, first along the sign of `initial`, with adaptive
// Bogacki–Shampine (RK 3(2)) steps in space projected onto the surface: the local error of each step is
// kept below 1e-4 cell and steps are at most cell / 2. Stops after maxLength, at the boundary (located
// by bisection), at a singularity, or — when detectClosure — where the line returns to its start in the
// same direction after at least three cells, closing the loop exactly at the start.
FlowLine traceFlowLine(const DirectionField& field, Family family, const SurfacePoint& start, const Vec3& initial,
                       double maxLength, bool detectClosure = true);

// traceFlowLine in installments: a flow line traced only as far as it is needed. advance(upTo) traces on
// until the line is at least upTo long (or has ended); the points are exactly those traceFlowLine returns
// with the same arguments, in the same order, however the tracing is split. Holds a reference to `field`.
class FlowTracer {
 public:
  FlowTracer(const DirectionField& field, Family family, const SurfacePoint& start, const Vec3& initial,
             double maxLength, bool detectClosure = true);
  // Traces until line().length >= upTo or the line ends; returns whether it ended (finished()).
  bool advance(double upTo);
  // Traces to the end (maxLength, the boundary, a singularity or closure).
  const FlowLine& finish() {
    advance(std::numeric_limits<double>::infinity());
    return line_;
  }
  bool finished() const { return finished_; }
  // The line so far; its `end` is meaningful once finished().
  const FlowLine& line() const { return line_; }
  // Moves the line out (the tracer is spent).
  FlowLine release() { return std::move(line_); }

 private:
  void attempt();  // one step of the integrator (accepted or retried with a smaller step)

  const DirectionField* field_;
  Family family_;
  SurfacePoint start_, current_;
  Vec3 startDirection_ = Vec3::Zero(), k1_ = Vec3::Zero();
  double maxLength_, h_ = 0;
  bool detectClosure_, finished_ = false;
  FlowLine line_;
};

// Points of the polyline at arc lengths 0, spacing, 2 spacing ... (up to its end), projected onto the surface.
// A loop (closed = true) gets round(length / spacing) points evenly spaced, so it closes without a short segment.
std::vector<SurfacePoint> sampleByArcLength(const SurfaceWalker& walker, const std::vector<SurfacePoint>& polyline,
                                            bool closed, double spacing);

// Arc length of a polyline (with its closing segment when closed).
double polylineLength(const std::vector<SurfacePoint>& polyline, bool closed);

}  // namespace phex
