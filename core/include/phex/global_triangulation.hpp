// phex — the global triangulation: any surface, any genus, with singular vertices placed by a field (beyond §7).
#pragma once
#include <vector>

#include "phex/progress.hpp"
#include "phex/surface.hpp"
#include "phex/triangulation.hpp"

namespace phex {

// §7 ends where the paper's methods do: they lay rows along one conjugate network without singularities, and
// closed surfaces, handles, hill tops and most uploads have none. The global method tiles any surface in three
// steps, each in its own file under core/src/global/:
//  1. a 3-direction (6-fold) field, smooth in the Dupin metric (the frame in which the Dupin indicatrix is a
//     circle, its anisotropy bounded where it degenerates), one direction along the principal direction of
//     least |curvature| where the curvature is anisotropic, along the boundary where there is one; its
//     singular points (index +-1/6) come out of the optimization (field.cpp);
//  2. a triangular lattice along it at the asked cell, as a position field (lattice.cpp), its dislocations
//     cancelled in pairs or moved into the field's singular points (dislocations.cpp);
//  3. the lattice's points as the vertices of a triangle mesh, connected by their Voronoi regions on the
//     surface, boundary vertices on the boundary curves (extraction.cpp).
// A triangle equilateral in the Dupin frame is ideal where K > 0 (its Dupin centre is its centroid, §5.1) and
// valid where K < 0 (three directions 60 degrees apart never lie between the asymptotes, Prop. 5): with one edge
// along the direction of least |curvature| it stays valid where the metric's anisotropy is bounded below the
// surface's. The dual of a manifold triangle mesh has three faces at every interior node, so the P-Hex mesh's
// nodes all join three beams; its faces other than hexagons stand at the field's singularities and on the
// boundary.
struct GlobalOptions {
  // Wanted edge length of the triangulation (the distance between neighbouring hexagons' centres), model units.
  double cell = 0;
  // When > 0, the cell is calibrated so that the triangulation has about this many vertices (hexagons).
  int faces = 0;
  // Largest ratio of the Dupin metric's two axes the field follows, in [1, 8]: 1 gives triangles equilateral
  // in space (an isotropic field), larger values follow the Dupin indicatrix further where it is elongated.
  double anisotropy = 2.0;
  // Where |curvature| is small (flat parts, parabolic curves) the Dupin metric tends to the isotropic one instead of
  // degenerating: each principal |curvature| gets this share of the surface's median largest |curvature| added
  // before their ratio is taken, in [0.01, 1]. Smaller values follow a near-developable surface's elongated
  // indicatrix further (up to `anisotropy`); larger ones keep the field nearer isotropic where the curvature is
  // weak or unreliable.
  double curvatureFloor = 0.25;
  // Weight of the alignment with the principal direction of least |curvature| where the metric is anisotropic,
  // against the field's smoothness, in [0, 10]; 0 leaves the field free but for the boundary. 3 by default (1
  // until stop 30): on the six shared models at 1000-10000 faces (30 runs) 86.34 -> 87.12 % hexagons (at 3000 faces
  // and more 88.61 -> 89.43 %), interior faces cut 317 -> 238; 1.1 / 2 / 2.9 / 5 gave 86.37 / 86.47 / 87.16 / 86.63 %
  // (docs/METHOD.md, the global method's field).
  double alignment = 3.0;
  // How far the cell follows the curvature, in [0, 1]: 0 uniform panels; 1 cells shrinking as the square root
  // of the largest |curvature| relative to the surface's median (within a factor 3 either way).
  double curvatureSizing = 0.0;
  // Whether the lattice's dislocations (a vertex of 5 next to one of 7) are glided together by edge flips and
  // cancelled (on by default; the pipeline leaves it off for a noisy upload's first lay, PipelineParams::noisyRepairs).
  bool glideDislocations = true;
  // Whether the position field's dislocations are cancelled before the extraction (dislocations.cpp): each core
  // joined with one of the opposite Burgers vector or moved into a singular point of the field, and the lattice
  // solved again around the changed translations. Irregular vertices then stand at the field's singular points,
  // the boundary, and the few cores left. On by default.
  bool cancelDislocations = true;
  // Whether a second field is solved, held to the flatter principal direction wherever the curvature is
  // anisotropic (not only where the bounded metric leaves an equilateral triangle invalid) and ten times as
  // strongly, and the lattice laid along it where it has at most three quarters of the first field's singular
  // points. The principal directions form a network without singularities on surfaces without umbilics (a
  // cyclide, a torus), where the smoothest field in the Dupin metric can still turn through pairs of them (the
  // cyclide: 20 against 4); near umbilics (hill tops, blobs) held fields gain singular points and are not taken.
  // On by default; not with `alignment` 0.
  bool principalTrial = true;
  // On a surface whose field is held to the flatter principal direction over most of it (a near-developable), the
  // boundary left free where that hold is strong, so that rows run along the flatter direction to the boundary
  // and end there cleanly instead of bending along it (on by default; the pipeline leaves it off on a noisy
  // upload, whose curvature ratios are noise). The elliptic paraboloids 1:10 and 1:30 laid globally at 3000
  // faces: 96.5 -> 99.1 % and 93.9 -> 99.7 % hexagons.
  bool freeAlignedBoundary = true;
};

// Throws Error(InvalidParameter) naming the first option out of its range.
void validate(const GlobalOptions& options);

// Lays the global triangulation of `surface` (an uploaded MeshSurface or an analytic surface). Its notes give the
// field's singularities, the cell, and anything left short; Triangulation::singularities lists them.
// Throws Error(CannotTile) where no triangulation can be laid (a cell larger than the surface, a component smaller
// than a cell), naming the place.
Triangulation globalTriangulation(const Surface& surface, const GlobalOptions& options, const ProgressFn& progress = {},
                                  const CancelFlag* cancel = nullptr);

// How many times the global method's field mesh splits each edge of an uploaded mesh whose median edge is `median`
// (its triangles k x k, before the longest left are bisected), for the first try's field-mesh edge `edge`
// (globalFieldEdge), reached or a little undershot. The pipeline refines a coarse upload so that this split lands
// near that edge (refinementFor): the two splits multiply.
int globalFieldSplit(double median, double edge);
// The global method's field-mesh edges per cell on `surface` at `cell`: 2.6, or 2.3 where that cell gives about 30k
// faces or more (fewer samples: less time and memory on large meshes, as many hexagons).
double globalSamplesPerCell(const Surface& surface, double cell);
// The global method's first field-mesh edge at `cell`.
double globalFieldEdge(const Surface& surface, double cell);

}  // namespace phex
