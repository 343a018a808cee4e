// phex — the Dupin indicatrix at a surface point and the Dupin conics homothetic to it (§3, §4.1).
//
// Everything here works in the tangent plane of a LocalGeometry g, in 2D coordinates along the principal
// directions (x along g.d1, y along g.d2, origin at g.point). There the indicatrix is k1 x^2 + k2 y^2 = ±1,
// and a Dupin conic is any homothetic copy of it: II(x - m, x - m) = const with centre m.
#pragma once
#include <array>
#include <optional>
#include <vector>

#include "phex/geometry.hpp"

namespace phex {

using Triangle2 = std::array<Vec2, 3>;  // three points of the tangent plane

// Tangent-plane coordinates of a point: its vertical projection onto the tangent plane (§4.1), along d1, d2.
Vec2 toTangentPlane(const LocalGeometry& g, const Vec3& p);
// The point of the tangent plane with coordinates x.
Vec3 fromTangentPlane(const LocalGeometry& g, const Vec2& x);
// Tangent-plane components of a vector (its normal component dropped), and back.
Vec2 tangentVector(const LocalGeometry& g, const Vec3& v);
Vec3 spatialVector(const LocalGeometry& g, const Vec2& t);

// The second fundamental form in the principal frame, II(s, t) = k1 s.x t.x + k2 s.y t.y (curvature units
// times length^2). Its sign follows LocalGeometry's convention; conjugacy and Dupin conics do not depend on it.
double secondFundamentalForm(const LocalGeometry& g, const Vec2& s, const Vec2& t);

enum class PointType { Elliptic, Hyperbolic, Parabolic, Planar };

// Kind of the point, with scale-free tests. With kmax = max(|k1|, |k2|) and kmin = min(|k1|, |k2|):
//   Planar     when kmax * lengthScale <= tolerance: over a distance lengthScale (say a mesh edge) the surface
//              leaves its tangent plane by about kmax lengthScale^2 / 2, a negligible fraction of lengthScale;
//   Parabolic  when kmin <= tolerance * kmax: the indicatrix is as good as a pair of lines;
//   Elliptic / Hyperbolic by the sign of K = k1 k2 otherwise.
// tolerance is dimensionless (1e-6 is a reasonable default); lengthScale > 0 is a length.
PointType classify(const LocalGeometry& g, double tolerance, double lengthScale);

// A developable (§3: K = 0 throughout): one principal curvature under kDevelopableRatio of the other at
// kDevelopableShare of the points where the surface is curved. Used by MeshSurface::developable, by the dual's
// shared ruling planes and by the hand-over of Method 1 to Method 2 on developables.
constexpr double kDevelopableRatio = 0.01;
constexpr double kDevelopableShare = 0.95;
// Whether `samples` are those of a developable: curved (max |k| over `curvedAbove`) at half of them or more,
// and one principal curvature under kDevelopableRatio of the other at kDevelopableShare of those.
bool samplesDevelopable(const std::vector<LocalGeometry>& samples, double curvedAbove);
// A developable's point whose largest curvature is under kPlanarShare of the samples' median is taken as
// planar (about an inflection of the profile, or on a flat part): the bound, from `samples` (not empty).
constexpr double kPlanarShare = 0.2;
double planarBelow(const std::vector<LocalGeometry>& samples);

// The direction conjugate to the tangent direction t (2D, any length): the unit t' with II(t, t') = 0, i.e.
// k1 t.x t'.x + k2 t.y t'.y = 0, oriented counterclockwise from t (t x t' >= 0 seen from the normal).
// - An asymptotic t (K <= 0, II(t, t) = 0) is self-conjugate: the result is t normalized.
// - At a parabolic point (one k zero) every direction but the zero-curvature one has that direction (the
//   ruling of a developable) as its conjugate; the zero-curvature direction itself is conjugate to every
//   direction, so the conjugate is undefined: nullopt. Likewise at a planar point and for t = 0.
std::optional<Vec2> conjugateDirection(const LocalGeometry& g, const Vec2& t);

// The two asymptotic directions (II(t, t) = 0), unit, mirror images in d1: (sqrt(-k2), ±sqrt(k1)) normalized.
// Defined where K <= 0 and not both curvatures vanish (they coincide, along the zero-curvature direction, at
// a parabolic point); nullopt where K > 0 or at a planar point.
std::optional<std::array<Vec2, 2>> asymptoticDirections(const LocalGeometry& g);

// Dupin centre of three tangent-plane points (§4.1): the centre of the unique Dupin conic (homothetic copy of
// the indicatrix) through a, b, c. It depends only on k2 / k1 and is affine-covariant with the indicatrix.
// nullopt when the centre is not defined: K = 0 (the linear system degenerates), or a, b, c collinear
// (relative determinant below 1e-12).
std::optional<Vec2> dupinCenter(const LocalGeometry& g, const Vec2& a, const Vec2& b, const Vec2& c);
// The same for points in space, projected vertically onto the tangent plane first (§6 step 2); the centre
// is returned as a point of the tangent plane. dupinCenter(g, g.point, p, q) is §6's conic through the
// vertex g.point and the projections of the other two vertices of a triangle.
std::optional<Vec3> dupinCenter(const LocalGeometry& g, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace phex
