// phex — laying valid triangulations along conjugate directions (§5.2, §5.3): the triangulations whose
// Dupin / tangent duals are P-Hex meshes without self-intersecting faces.
//
// Both methods start from a base curve L0, a flow line of the chosen direction field through the start
// point sampled every `cell`, and lay layers of triangles on both sides of it, one row of apexes per layer:
// - Progressive conjugation (Method 1, Fig. 14): the apex C_i of each segment A_i A_{i+1} makes an ideal
//   triangle (§5.1) in the tangent plane at the segment's midpoint M_i; the C polyline is the next base curve.
// - Pre-specified conjugation (Method 2, Fig. 16): the apexes lie on the flow lines l_i of the conjugate field
//   D_G through the M_i, and the next base curve is the flow line of the field D_F that best fits the ideal
//   apexes, kept above the line DE of §5.1 so that every star stays valid (Props 4, 5).
// Near parabolic curves the step is bounded from below and re-used across (§5.3). Works on any Surface
// (an uploaded MeshSurface too): steps are taken in the tangent plane and projected back.
#pragma once
#include <optional>
#include <string>

#include "phex/direction_field.hpp"
#include "phex/progress.hpp"
#include "phex/triangulation.hpp"

namespace phex {

enum class LayingMethod { Progressive, Prespecified };

// "progressive" | "prespecified" <-> LayingMethod; parseLayingMethod throws Error(InvalidParameter) otherwise.
LayingMethod parseLayingMethod(const std::string& name);
const char* layingMethodName(LayingMethod method);

// Which family of the conjugate network (field, conjugate field) the base curves follow.
enum class BaseFamily {
  Auto,       // on a surface with parabolic curves, the family along the zero-curvature direction there
              // (§5.3: on a torus the parallels, the only feasible choice of Fig. 19; on a vase the meridians),
              // see parabolicBaseFamily; elsewhere the one of smaller normal curvature at the start point (on a
              // developable: the rulings)
  First,      // the field itself (D_F)
  Conjugate   // its conjugate (D_G)
};

struct LayingOptions {
  LayingMethod method = LayingMethod::Progressive;
  std::string field = "principal";  // see parseFieldSpec: principal, angle:DEG, param[:v], radial, diverging[:DEG], spiral[:DEG]
  double cell = 0;                  // edge length along the base curves, model units; required, > 0
  // §5.3: lower bound b on the step ratio |CM| / |AB|, applied smoothly (stepLowerBound); 0 disables it.
  // In [0, 2]; 0.3 keeps layers near parabolic curves at least about a third of the base.
  double lowerBound = 0.3;
  // §5.3: an ideal step ratio above this has exploded at a parabolic curve crossed by the zero-curvature
  // direction; the previous layer's valid ratio is re-used instead. In [1, 100].
  double maxStepRatio = 2.5;
  std::optional<Vec3> start;          // a point near the surface; default: the centre of the bounds, projected
  BaseFamily base = BaseFamily::Auto;
  // A tangent vector at the start: the base curve follows the family closest to it (overrides `base`).
  std::optional<Vec3> baseDirection;
  // Sweeps of repairStars over the laid triangulation, after which openInvalidBoundaryStars opens the stars
  // still invalid next to the boundary (0: leave it as laid); what they did goes in the notes.
  int repairSweeps = 12;
  int maxLayers = 100000;    // layers over all fronts; laying stops there (with a note)
  int maxVertices = 4000000; // more would be needed: Error(InvalidParameter) naming the cell size
};

// The family BaseFamily::Auto takes on `surface` for options.field whatever the start: the one nearer the
// zero-curvature direction at the near-parabolic points (two thirds of them at least), or Auto where the
// surface has none or they disagree (the start point's normal curvatures decide then). Throws like
// layTriangulation for a bad field or cell.
BaseFamily parabolicBaseFamily(const Surface& surface, const LayingOptions& options);

// §5.3: the step ratio actually used for a computed ratio r >= 0 and a lower bound b > 0:
// r when r >= 2b, else b + r^2 / (4b) — at least b, and joining r smoothly at 2b. b <= 0 returns r.
double stepLowerBound(double r, double b);

// Lays a triangulation of `surface` (mesh triangles CCW seen from the surface normal; uv filled on a
// ParametricSurface). fieldLines holds the base curves laid (L0 first) and, for Method 2, the conjugate
// flow lines of the first layer; notes say what happened (lower bound active, steps re-used across
// parabolic curves, rows resampled, row ends moved onto the boundary, fronts stopped at the boundary or zipped
// where they met). Method 2's rows crossing an open boundary steeply end on it (extendRow in laying.cpp).
// Throws Error(InvalidParameter) for bad options (naming the option and value), Error(CannotTile) where
// the chosen field cannot give a valid triangulation (e.g. a base along an asymptotic direction, which is
// self-conjugate) naming the point and suggesting another field or method, Error(Cancelled) when cancelled.
Triangulation layTriangulation(const Surface& surface, const LayingOptions& options, const ProgressFn& progress = {},
                               const CancelFlag* cancel = nullptr);

// Whether `surface` is a developable: an uploaded mesh that MeshSurface found one (its vanishing curvature
// then set to 0), or an analytic surface with one principal curvature under kDevelopableRatio of the other
// at kDevelopableShare of its 400 samples where it is curved (`samples`, if given, are those samples).
bool isDevelopable(const Surface& surface, const std::vector<LocalGeometry>* samples = nullptr);

// The repair layTriangulation ends with (options.repairSweeps > 0): repairStars, then openInvalidBoundaryStars;
// for a triangulation laid with repairSweeps = 0 and repaired later (the face-count loop repairs only the lay
// it keeps). Nothing where repairSweeps is 0.
void repairLaidTriangulation(Triangulation& triangulation, const Surface& surface, int repairSweeps,
                             const CancelFlag* cancel = nullptr);

}  // namespace phex
