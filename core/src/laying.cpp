#include "phex/laying.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "phex/duality.hpp"
#include "phex/dupin.hpp"
#include "phex/error.hpp"
#include "phex/ideal_triangle.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/parallel.hpp"

namespace phex {
namespace {

constexpr double kSqrt3 = 1.7320508075688772;
constexpr double kEquilateralRatio = 0.5 * kSqrt3;  // |CM| / |AB| of an equilateral triangle (planar points)
// A conjugate direction closer than ~8.6 degrees to AB is as good as asymptotic: the triangles would be slivers.
constexpr double kMinConjugateSine = 0.15;
// §5.3's re-used step carries a front across a parabolic curve in a few layers where the ideal step explodes.
// A front whose ideal step explodes on most of its segments for more consecutive layers than this runs along
// the curve instead, laying layers over and over (a developable, parabolic throughout, has no ideal step to
// explode and re-uses its first layer's by design): Method 1 on the torus from Fig. 19's start at cell 0.024
// re-used it on 1428 of 1918 layers, 84k vertices where 46k cover the torus, 1122 invalid stars. Such a
// front stops there.
constexpr int kMaxReusedLayers = 20;
constexpr double kNearParabolic = 0.1;  // kmin / kmax below which a point counts as near a parabolic curve
constexpr double kResampleBelow = 0.55, kResampleAbove = 1.8;  // row spacing / cell that triggers a resample
constexpr double kResampleLimit = 2.5;  // ... even at a parabolic curve
constexpr double kResampleReach = 1.5;  // a resampled vertex lies within this many spacings (cells) of an apex
// A row whose spacing grew counts as at a parabolic curve for resampling where kmin / kmax is below this (on
// a fifth of it): the pentagons and heptagons a resample leaves fold as Dupin hexagons even a little off the
// curve. At 0.1 (kNearParabolic) a sampled 12k-triangle torus folded 4-5 faces at 700, 800 and 900 faces and
// the analytic torus (Method 2) 12 at 1500; at 0.2 none, and the uploaded cyclide converges at 10 of 12 sizes
// (was 8). A row whose spacing shrank keeps kNearParabolic: at 0.2 the uploaded wave roof's rows along its
// boundary near the parabolic curve went unresampled down to half a cell, and at 100k faces their thin
// triangles left 8 faces folded and 207 off planar.
constexpr double kResampleParabolic = 0.2;
constexpr double kValidMargin = 1.1;  // Method 2 keeps the apexes this far above DE (in units of validStep)
constexpr double kZipGap = 1.6;       // fronts facing each other closer than this many steps are zipped
// The rows of L0's two fronts (both open or both closed) facing each other closer than this many of their steps
// share out the gap between them: it is laid in whole layers of equal height no lower than a step
// (zipIfMeeting), the last one zipped. Full steps would leave whatever remains for the zip, down to slivers,
// whose stars (K < 0 in particular) and Dupin hexagons fold. Split fronts keep kZipGap.
constexpr double kMeetReach = 3.5;
// A region left uncovered by the rows laid so far whose middle is at least kSeedHole cells from every laid vertex,
// with at least kSeedShare of the surface's kSeedSamples samples uncovered, seeds another system of rows (run);
// at most kMaxSeeds are tried. Its L0 keeps kSeedClearance cells from the laid vertices.
constexpr double kSeedHole = 4.0;
constexpr double kSeedShare = 0.05;
// The first such system only where the first left at least this share uncovered: a laying that covers most of
// the surface (the helicoid's rows end short of its corners, 11 %) is better left whole than seamed. At 0.2 the
// bumps' first system left 19 % bare at one cell (100k faces asked: 68k vertices instead of 99k with further
// systems), and the face count hunted between the two coverings (128k faces kept; 101k now).
constexpr double kSeedFirstShare = 0.15;
constexpr int kSeedSamples = 1024;
constexpr int kMaxSeeds = 6;
constexpr double kSeedClearance = 0.9;
constexpr int kShrunkLoop = 16;  // a closed row of fewer vertices checks its apexes' triangles against laid ones
// ... seeded around the most nearly umbilic uncovered sample, relative k1 - k2 below this, if there is one.
constexpr double kSeedUmbilic = 0.05;
// A closed L0 of fewer samples than kTinyLoop and shorter than kTinyLoopShare of the surface's diagonal (a loop
// around an umbilic, not a thin tube's cross-section) moves kUmbilicRing cells outwards (baseCurve).
constexpr std::size_t kTinyLoop = 8;
constexpr double kTinyLoopShare = 0.1;
constexpr int kUmbilicRing = 3;
// Gaps left between systems (and between the fronts of one) are closed by triangles on the laid boundary
// vertices (fillGaps): edges up to kFillEdge cells, angles whose sine is at least kFillSine; where none fits,
// a new vertex at least kFillClearance cells from the others. Holes left inside the surface then close with
// angles down to kFillSineBlunt and edges up to kFillEdgeWide cells.
constexpr double kFillEdge = 1.6;
constexpr double kFillSine = 0.5;  // 30 degrees
constexpr double kFillClearance = 0.7;
constexpr double kFillSineBlunt = 0.3;  // 17.5 degrees
constexpr double kFillEdgeWide = 2.0;
// Method 2's rows ending at an open boundary (their flow line leaves the surface before the next sample) end on
// it (extendRow): where the gap left is at least kBoundaryMin of their spacing and kBoundaryMinCells cells, a
// vertex goes onto the boundary; where it is less than kBoundaryMin of their spacing, their end vertex is moved
// onto it if their last segment is then at most kBoundaryMaxCells cells. Rows sampled every cell from anywhere
// stopped up to a spacing short of the boundary (a sawtooth strip uncovered: the hyperboloid at 2000 faces
// covered 90 %, now 100 %). Gaps outside these bounds (rows crowded or spread out, e.g. near the wave roof's
// corners) leave the row end where it is: a vertex there would make an edge far shorter or longer than a cell.
constexpr double kBoundaryMin = 0.5;
constexpr double kBoundaryMinCells = 0.5;
constexpr double kBoundaryMaxCells = 1.5;
// ... only where the row's line crosses the boundary within about 37 degrees of its normal (the cosine): rows
// running into it slantwise (the helicoid's) got skewed ends, invalid stars and folded Dupin hexagons there.
constexpr double kBoundaryCrossing = 0.8;
// Two row ends on the boundary are joined by an edge along it only where its midpoint lies on the surface, off
// the boundary by at most this many cells (chordOnSurface): the tangent dual puts a P-Hex vertex at about the
// midpoint, which on an uploaded mesh's jagged boundary polyline could fall several mesh edges off the mesh.
constexpr double kChordOffBoundary = 0.01;
constexpr double kEllLength = 3.0;    // Method 2 traces each l_i this many ideal steps long
constexpr int kEllsPerThread = 16;   // the l_i of a row traced per thread, at least
constexpr double kEllFirst = 1.5;     // ... at first only this many: further where no crossing is found
constexpr int kParabolicSamples = 400;  // samples of the surface that vote for the base family at parabolic curves
// Method 1 smooths its apex offsets once per layer at about this many faces, more often at finer cells (see
// progressiveApexes). Measured over ten surfaces at 1k-30k faces: 2500 left the cyclide 106 / 261 invalid
// stars at 10k / 30k faces, 800 gives 53 / 119 (300 no better: 62 / 109), and at 1000 faces one pass as before.
constexpr int kSmoothingFaces = 800;

const char* const kAsymptoticBase =
    "the base curve runs (almost) along an asymptotic direction, which is self-conjugate (§4.2, Prop. 5), so no "
    "triangle on it gives a valid star; choose a field further from the asymptotic directions (e.g. principal), the "
    "other base family, or the other method";
// The same along the principal directions, which are never asymptotic off a parabolic curve: the chords of L0
// turned onto one, the cell being coarse for how fast the curvature lines turn (a helicoid at 12 faces).
const char* const kAsymptoticChord =
    "a segment of the base curve runs (almost) along an asymptotic direction, which is self-conjugate (§4.2, "
    "Prop. 5), so no triangle on it gives a valid star; the curvature lines are never asymptotic, but at this cell "
    "the base curve's chords cut across their turn: ask for more faces (a smaller cell) or another start";

std::string describe(const SurfaceWalker& walker, const SurfacePoint& p) {
  std::ostringstream s;
  s.precision(4);
  s << "(" << p.point().x() << ", " << p.point().y() << ", " << p.point().z() << ")";
  if (walker.parametric()) s << " [u, v = " << p.uv.x() << ", " << p.uv.y() << "]";
  return s.str();
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Whether segments pr and st of a plane cross at a point inside both (touching or collinear does not count).
bool segmentsCross(const Vec2& p, const Vec2& r, const Vec2& s, const Vec2& t) {
  const double d1 = cross2(r - p, s - p), d2 = cross2(r - p, t - p), d3 = cross2(t - s, p - s), d4 = cross2(t - s, r - s);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

// The directed edge a -> b as one number.
std::int64_t edgeKey(int a, int b) { return (static_cast<std::int64_t>(a) << 32) | static_cast<std::uint32_t>(b); }

std::vector<double> cumulativeArc(const std::vector<SurfacePoint>& curve) {
  std::vector<double> arc(curve.size(), 0.0);
  for (std::size_t i = 1; i < curve.size(); ++i) arc[i] = arc[i - 1] + (curve[i].point() - curve[i - 1].point()).norm();
  return arc;
}

// A row of vertices: the current base curve of a front, which advances to its left (seen from the normal).
struct Row {
  std::vector<int> ids;
  bool closed = false;
  // The curve the vertices lie on, with their arc lengths along it: for Method 2 the flow line L_k of D_F
  // (running on to the boundary past the end vertices), for Method 1 the row's own polyline.
  std::vector<SurfacePoint> curve;
  std::vector<double> curveArc;  // cumulative from curve[0]
  double curveLength = 0;        // with the closing segment on a closed curve
  std::vector<double> sampleArc; // #ids, increasing
  // On an open row, the vertices of the row it was laid from beyond its first and last apexes (the bases' ends
  // of their segments), or -1: a vertex added before the first or after the last closes the row's end with
  // them (Laying::layLayer).
  int belowStart = -1, belowEnd = -1;
};

struct Front {
  Row row;
  bool active = true;
  double lastStep = 0;  // mean |MC| of its last layer
  int layers = 0;
  int explodedLayers = 0;  // consecutive layers whose ideal step exploded on most segments (kMaxReusedLayers)
};

// One base segment A_i A_{i+1} of a layer with the apex direction and step of §5.1 and §5.3.
struct Segment {
  SurfacePoint M;        // midpoint, on the surface
  Vec3 left;             // unit tangent at M towards the apex: conjugate to AB (§5.1)
  Vec3 apexInPlane;      // M + step * left, in the tangent plane at M
  double base = 0;       // |AB|
  double step = 0;       // |MC| to lay
  double validStep = 0;  // any apex beyond it on l keeps the star valid (Props 4, 5); 0 at parabolic points
  double ratio = 0;      // step / base, kept on the apex for §5.3 re-use
  bool bounded = false, reused = false;
  bool exploded = false;    // the ideal step exploded at a parabolic curve (above maxStepRatio): re-used instead
  bool asymptotic = false;  // AB runs (nearly) along an asymptotic direction: no valid triangle on it
  bool degenerate = false;  // A and B (nearly) coincide, e.g. where a row folds back: no triangle on it
};

struct Apex {
  SurfacePoint p;
  double ratio = 0;  // step / base it was laid with
  double arc = 0;    // Method 2: arc length along the next base curve
};

// The point at arc length t of a curve (wrapping on a closed one), projected onto the surface. Between two
// curve points it follows a cubic through their neighbours: a chord would cut inside the curve
// and, projected back, move sideways along the surface by the sagitta, enough near a parabolic curve to
// turn the next conjugate directions (§5.3).
SurfacePoint pointAtArc(const SurfaceWalker& walker, const std::vector<SurfacePoint>& curve,
                        const std::vector<double>& arc, bool closed, double length, double t) {
  const int n = static_cast<int>(curve.size());
  int k;  // t lies between curve points k and k + 1 (mod n on a closed curve)
  double w;
  if (closed) {
    t = std::fmod(t, length);
    if (t < 0) t += length;
  } else {
    t = std::clamp(t, 0.0, arc.back());
  }
  if (t >= arc.back()) {
    if (!closed || length <= arc.back()) return curve.back();
    k = n - 1;
    w = (t - arc.back()) / (length - arc.back());
  } else {
    k = static_cast<int>(std::upper_bound(arc.begin(), arc.end(), t) - arc.begin()) - 1;
    const double span = arc[k + 1] - arc[k];
    w = span > 0 ? (t - arc[k]) / span : 0.0;
  }
  if (w <= 0) return curve[k];
  auto at = [&](int j) -> const Vec3& {
    return curve[closed ? ((j % n) + n) % n : std::clamp(j, 0, n - 1)].point();
  };
  // Cubic Hermite with tangents from the neighbours, scaled by the chord lengths (uneven RK steps).
  const Vec3 &p0 = at(k - 1), &p1 = at(k), &p2 = at(k + 1), &p3 = at(k + 2);
  const double d01 = (p1 - p0).norm(), d12 = (p2 - p1).norm(), d23 = (p3 - p2).norm();
  const Vec3 m1 = d12 * (p2 - p0) / std::max(d01 + d12, 1e-300), m2 = d12 * (p3 - p1) / std::max(d12 + d23, 1e-300);
  const double w2 = w * w, w3 = w2 * w;
  const Vec3 q = (2 * w3 - 3 * w2 + 1) * p1 + (w3 - 2 * w2 + w) * m1 + (3 * w2 - 2 * w3) * p2 + (w3 - w2) * m2;
  return walker.project(q, curve[k]);
}

// A uniform grid over vertex positions, for the collision test.
class PointGrid {
 public:
  explicit PointGrid(double spacing) : spacing_(spacing), keys_(kInitialSlots), slots_(kInitialSlots, -1) {}
  // Adds point `id` at p; returns the index of its cell (0, 1, ... in order of first use).
  int insert(int id, const Vec3& p) {
    const int cell = cellFor(key(cellOf(p)));
    cells_[cell].push_back(id);
    return cell;
  }
  // Visits (at least) every point closer than radius to p: the points of the cells the box p +- radius meets.
  template <class Visit>
  void forNear(const Vec3& p, double radius, Visit visit) const {
    forNearCells(p, radius, [&](int cell) {
      for (int id : cells_[cell]) visit(id);
    });
  }
  // The same cells, by index (those holding a point).
  template <class Visit>
  void forNearCells(const Vec3& p, double radius, Visit visit) const {
    forNearKeys(p, radius, [&](std::int64_t k) {
      const int cell = find(k);
      if (cell >= 0) visit(cell);
    });
  }
  // The keys of the same block of cells, held points or not (cells may gain points later).
  template <class Visit>
  void forNearKeys(const Vec3& p, double radius, Visit visit) const {
    const double reach = radius * (1 + 1e-9) + 1e-9 * spacing_;  // beyond round-off in the cell indices
    const Eigen::Array3d lo = (p.array() - reach) / spacing_, hi = (p.array() + reach) / spacing_;
    std::int64_t a[3], b[3];
    for (int c = 0; c < 3; ++c) {
      // Within the 3 x 3 x 3 block around p's cell, all the collision test ever looked at (its radii are
      // below the spacing, the cell, anyway).
      const std::int64_t centre = static_cast<std::int64_t>(std::floor(p(c) / spacing_));
      a[c] = std::max(centre - 1, static_cast<std::int64_t>(std::floor(lo(c))));
      b[c] = std::min(centre + 1, static_cast<std::int64_t>(std::floor(hi(c))));
    }
    for (std::int64_t x = a[0]; x <= b[0]; ++x)
      for (std::int64_t y = a[1]; y <= b[1]; ++y)
        for (std::int64_t z = a[2]; z <= b[2]; ++z) visit(key({x, y, z}));
  }
  // The key of the cell holding p.
  std::int64_t keyAt(const Vec3& p) const { return key(cellOf(p)); }

 private:
  // The occupied cells by key in an open-addressing table (linear probing, at most half full): the laying
  // and the gap filling look up 27 cells per query, and std::unordered_map's lookups took 10-15 % of a lay.
  static constexpr std::size_t kInitialSlots = 1024;
  static std::size_t slotOf(std::int64_t key, std::size_t mask) {
    std::uint64_t h = static_cast<std::uint64_t>(key) * 0x9E3779B97F4A7C15ull;
    return static_cast<std::size_t>(h ^ (h >> 29)) & mask;
  }
  int find(std::int64_t key) const {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = slotOf(key, mask);; i = (i + 1) & mask) {
      if (slots_[i] < 0) return -1;
      if (keys_[i] == key) return slots_[i];
    }
  }
  // The cell of `key`, added if new.
  int cellFor(std::int64_t key) {
    if (const int cell = find(key); cell >= 0) return cell;
    if (2 * (cells_.size() + 1) > slots_.size()) {
      std::vector<std::int64_t> keys(2 * slots_.size());
      std::vector<int> slots(2 * slots_.size(), -1);
      const std::size_t mask = slots.size() - 1;
      for (std::size_t j = 0; j < slots_.size(); ++j) {
        if (slots_[j] < 0) continue;
        std::size_t i = slotOf(keys_[j], mask);
        while (slots[i] >= 0) i = (i + 1) & mask;
        keys[i] = keys_[j], slots[i] = slots_[j];
      }
      keys_.swap(keys);
      slots_.swap(slots);
    }
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = slotOf(key, mask);
    while (slots_[i] >= 0) i = (i + 1) & mask;
    keys_[i] = key;
    slots_[i] = static_cast<int>(cells_.size());
    cells_.emplace_back();
    return slots_[i];
  }

  std::array<std::int64_t, 3> cellOf(const Vec3& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() / spacing_)), static_cast<std::int64_t>(std::floor(p.y() / spacing_)),
            static_cast<std::int64_t>(std::floor(p.z() / spacing_))};
  }
  static std::int64_t key(const std::array<std::int64_t, 3>& c) {
    return (c[0] & 0x1FFFFF) | ((c[1] & 0x1FFFFF) << 21) | ((c[2] & 0x1FFFFF) << 42);
  }
  double spacing_;
  std::vector<std::int64_t> keys_;
  std::vector<int> slots_;               // index into cells_, -1 where empty
  std::vector<std::vector<int>> cells_;  // the points of each occupied cell, in insertion order
};

// A lay that reaches kVertexExcess times the vertices its surface holds at the cell (plus kVertexSlack, for
// coarse cells whose rows keep a minimum count) has run its layers over each other: Method 1 on a cone along
// its principal directions laid 16k vertices where 700 fit, one front circling on and on, and would have gone
// on to maxLayers for minutes. Lays that cover the surface stay far below: thin layers at the §5.3 lower bound
// hold about three times the estimate, and the uploaded wave roof's ideal triangles 1.8 times.
constexpr double kVertexExcess = 10;
// Triangles with centroids in the cells about an apex (27 cells of two cells' width, where a covering holds
// about 100 and a few sheets of a thin closed surface some hundreds) beyond which overlapsLaid counts the apex
// as overlapping: layers piled onto each other there.
constexpr int kPiledTriangles = 2000;
// Vertices within kFillEdgeWide cells of a gap triangle beyond which fillGaps counts it as piled onto layers
// laid over each other, and adds no triangle there. A covering has about 50 there (at most 640 measured: the
// analytic bumps at 100k faces); a trial on a noisy dome along angle:4, whose L0 spiralled round the
// umbilic, piled some 2800 about each of 121k candidates, and its gap filling took 13 of its 14 s.
constexpr int kPiledVertices = 1000;
constexpr double kVertexSlack = 5000;
// Whether surfaceArea knows the surface's area (a mesh or a parametric surface).
bool areaKnown(const Surface& surface) {
  return dynamic_cast<const MeshSurface*>(&surface) || dynamic_cast<const ParametricSurface*>(&surface);
}
std::size_t vertexLimit(const Surface& surface, double cell) {
  const double area = areaKnown(surface) ? surfaceArea(surface) : surface.bounds().diagonal().squaredNorm();
  const double expected = area / (std::sqrt(3.0) / 2 * cell * cell);
  return static_cast<std::size_t>(std::min(kVertexExcess * expected + kVertexSlack, 2e9));
}

// Passes of Method 1's (1, 2, 1) / 4 smoothing per layer at `cell`: one at about kSmoothingFaces faces, and
// growing as 1 / cell. A Surface other than a mesh or a parametric one (whose area is not known) gets one.
int progressiveSmoothingPasses(const Surface& surface, double cell) {
  if (!areaKnown(surface)) return 1;
  const double passes = cellForFaceCount(surface, kSmoothingFaces) / cell;
  return static_cast<int>(std::clamp(std::lround(passes), 1L, 64L));
}

// Where a curve crosses the short flow line l (both on the surface), found in the tangent plane at l's start.
struct Crossing {
  double ellArc;   // arc length along l
  Vec3 point;
  double curveArc; // arc length along the curve
};

class Laying {
 public:
  Laying(const SurfaceWalker& walker, const DirectionField& field, const LayingOptions& options, Family baseFamily,
         const ProgressFn& progress, const CancelFlag* cancel)
      : walker_(walker),
        field_(field),
        o_(options),
        F_(baseFamily),
        G_(baseFamily == Family::First ? Family::Conjugate : Family::First),
        progress_(progress),
        cancel_(cancel),
        grid_(options.cell),
        smoothingPasses_(options.method == LayingMethod::Progressive ? progressiveSmoothingPasses(walker.surface(), options.cell)
                                                                     : 1),
        vertexLimit_(vertexLimit(walker.surface(), options.cell)) {}

  Triangulation run(const SurfacePoint& start, const Vec3& initial);

 private:
  int addVertex(const SurfacePoint& p, double ratio, double height = std::numeric_limits<double>::quiet_NaN());
  FlowLine::End traceBase(const SurfacePoint& start, const Vec3& initial, Row& row, std::vector<double>& arcs) const;
  Row baseCurve(const SurfacePoint& start, const Vec3& initial);
  std::optional<Row> seedCurve(const SurfacePoint& start, const Vec3& initial);
  void laySystem(const Row& L0);
  std::optional<Vec3> uncoveredSeed(const std::vector<LocalGeometry>& samples, std::vector<Vec3>& tried) const;
  int fillGaps();
  bool zipIfMeeting(std::size_t f, double& stepScale);
  struct RowOffset {
    Vec3 tangent, left, offset = Vec3::Zero();
    double distance = std::numeric_limits<double>::infinity();
  };
  bool rowsWithin(const std::vector<int>& P, const std::vector<int>& Q, double pad) const;
  RowOffset offsetToRow(const std::vector<int>& P, int k, const std::vector<int>& Q) const;
  bool facing(const Front& a, const Front& b) const;
  std::optional<double> facingGap(const Front& a, const Front& b, bool& staggered) const;
  void layLayer(std::size_t f, double stepScale);
  bool extendRow(Row& row, bool atStart);
  void closeRowEnd(const Row& row, bool atStart);
  void snapRowEnd(Row& row, bool atStart, const SurfacePoint& onto, double arc);
  bool chordOnSurface(const SurfacePoint& a, const SurfacePoint& b) const;
  Segment segment(const Row& row, int i) const;
  std::vector<std::optional<Apex>> progressiveApexes(const Row& row, const std::vector<Segment>& segments) const;
  // `fromL0`: the row is the first system's L0, where a segment along an asymptotic direction is the field's
  // doing (fail); on later rows such a segment gets no apex.
  std::vector<std::optional<Apex>> prespecifiedApexes(const Row& row, const std::vector<Segment>& segments, Row& next,
                                                      bool recordConjugateLines, bool fromL0);
  bool collides(const Vec3& p, double radius) const;
  void addTriangle(int a, int b, int c);
  bool overlapsLaid(int a, int b, const SurfacePoint& c);
  void zip(std::vector<int> P, bool closedP, std::vector<int> Q, bool closedQ);
  void setOwnCurve(Row& row) const;
  std::optional<Crossing> crossCurve(const LocalGeometry& g, const FlowLine& ell, const std::vector<double>& ellArc,
                                     const Row& curve, int& hint) const;
  [[noreturn]] void cannotTile(const SurfacePoint& where, const std::string& why) const;
  // Why L0 gives no valid triangle where it runs along an asymptotic direction (kAsymptoticBase, or for the
  // principal field kAsymptoticChord).
  const char* asymptoticWhy() const {
    return field_.spec().kind == FieldKind::Principal ? kAsymptoticChord : kAsymptoticBase;
  }

  const SurfaceWalker& walker_;
  const DirectionField& field_;
  const LayingOptions& o_;
  const Family F_, G_;  // base curves follow F_, apexes go along G_ (its conjugate)
  const ProgressFn& progress_;
  const CancelFlag* cancel_;

  std::vector<SurfacePoint> vertices_;
  std::vector<double> vertexRatio_;  // the step ratio each vertex was laid with (NaN on L0): §5.3 re-use
  std::vector<double> vertexHeight_; // its distance from the row it was laid from, across that row (NaN on L0)
  std::vector<char> inBase_;         // vertices of the row being laid from (exempt from the collision test)
  std::vector<Eigen::Vector3i> triangles_;
  PointGrid grid_;
  PointGrid triangleGrid_{2 * o_.cell};  // triangle centroids, for overlapsLaid
  std::size_t triangleGridCount_ = 0;    // triangles_[0 ..) in triangleGrid_
  // From the second system on, every directed edge laid: a triangle that would use one again (a later system's
  // fronts zipped across each other's first rows) is left out instead of making the mesh non-manifold.
  std::unordered_set<std::int64_t> directedEdges_;
  const int smoothingPasses_;  // of the apex offsets per layer, Method 1
  std::vector<Front> fronts_;
  std::size_t systemFront0_ = 0;  // fronts_[systemFront0_ ..] belong to the system being laid (see run)
  int systems_ = 0;               // systems of rows laid, each from its own L0
  std::size_t vertexLimit_;       // more vertices than this: the layers run over each other (vertexLimit)
  std::vector<std::vector<Vec3>> fieldLines_;
  mutable std::vector<Vec2> ellPlane_;  // crossCurve's scratch: l in the tangent plane

  // What happened, for the notes.
  int boundedLayers_ = 0, boundedSegments_ = 0, reusedLayers_ = 0, reusedSegments_ = 0;
  int filledApexes_ = 0;
  int parabolicStops_ = 0;  // fronts stopped running along a parabolic curve (kMaxReusedLayers)
  std::string firstAlongParabolic_;
  int widenedL0_ = 0;  // times L0 moved out from a tiny loop around an umbilic (baseCurve)
  int resampled_ = 0, boundaryStops_ = 0, collisions_ = 0, invalidDrops_ = 0, splits_ = 0, layers_ = 0;
  int asymptoticStops_ = 0, gapTriangles_ = 0;
  int boundaryEnds_ = 0, snappedEnds_ = 0;
  std::vector<char> onBoundary_;     // row ends laid on (or moved onto) the boundary
  std::string firstResample_, firstInvalidDrop_, firstReuse_, firstAsymptoticStop_;
  std::vector<std::string> zipNotes_;
};

void Laying::cannotTile(const SurfacePoint& where, const std::string& why) const {
  throw Error(ErrorCode::CannotTile,
              "cannot lay a valid triangulation with field '" + fieldSpecName(field_.spec()) + "' (" +
                  layingMethodName(o_.method) + " method) near " + describe(walker_, where) + ": " + why);
}

int Laying::addVertex(const SurfacePoint& p, double ratio, double height) {
  if (vertices_.size() >= vertexLimit_) {
    std::ostringstream msg;
    msg << "the layers ran over each other instead of covering the surface: " << vertices_.size()
        << " vertices laid, " << kVertexExcess << " times what the surface holds at cell " << o_.cell
        << "; choose the other method, another field or another start point";
    cannotTile(p, msg.str());
  }
  if (static_cast<int>(vertices_.size()) >= o_.maxVertices) {
    std::ostringstream msg;
    msg << "cell " << o_.cell << " is too small for this surface: more than maxVertices = " << o_.maxVertices
        << " vertices would be laid";
    throw Error(ErrorCode::InvalidParameter, msg.str());
  }
  const int id = static_cast<int>(vertices_.size());
  vertices_.push_back(p);
  vertexRatio_.push_back(ratio);
  vertexHeight_.push_back(height);
  inBase_.push_back(0);
  onBoundary_.push_back(0);
  grid_.insert(id, p.point());
  return id;
}

void Laying::setOwnCurve(Row& row) const {
  row.curve.clear();
  for (int id : row.ids) row.curve.push_back(vertices_[id]);
  row.curveArc = cumulativeArc(row.curve);
  row.curveLength = row.curveArc.back() +
                    (row.closed ? (row.curve.back().point() - row.curve.front().point()).norm() : 0.0);
  row.sampleArc = row.curveArc;
}

// The flow line of D_F through the start, both ways to the boundary or once around a loop (row.curve, closed,
// arcs), and the arc lengths every cell from the start where L0's samples go; returns how the line ended.
FlowLine::End Laying::traceBase(const SurfacePoint& start, const Vec3& initial, Row& row, std::vector<double>& arcs) const {
  const double reach = 4 * walker_.surface().bounds().diagonal().norm() + 10 * o_.cell;
  const FlowLine forward = traceFlowLine(field_, F_, start, initial, reach, true);
  if (forward.end == FlowLine::End::Closed) {
    row.closed = true;
    row.curve = forward.points;
    row.curveArc = cumulativeArc(row.curve);
    row.curveLength = forward.length;
    const int n = std::max(3, static_cast<int>(std::lround(forward.length / o_.cell)));
    for (int i = 0; i < n; ++i) arcs.push_back(forward.length * i / n);
  } else {
    const FlowLine backward = traceFlowLine(field_, F_, start, -initial, reach, false);
    row.curve.assign(backward.points.rbegin(), backward.points.rend());
    row.curve.insert(row.curve.end(), forward.points.begin() + 1, forward.points.end());
    row.curveArc = cumulativeArc(row.curve);
    row.curveLength = row.curveArc.back();
    const double s0 = backward.length;
    for (int k = -static_cast<int>(std::floor(s0 / o_.cell + 1e-9)); s0 + k * o_.cell <= row.curveLength + 1e-9 * o_.cell; ++k)
      arcs.push_back(s0 + k * o_.cell);
  }
  return forward.end;
}

// L0: the flow line of D_F through the start, both ways to the boundary or once around a loop, sampled every
// cell from the start.
Row Laying::baseCurve(const SurfacePoint& given, const Vec3& initial) {
  SurfacePoint start = given;
  Row row;
  std::vector<double> arcs;
  FlowLine::End end = traceBase(start, initial, row, arcs);
  // A start at (or next to) an umbilic around which the base family closes into rings (a hill's top) gives a
  // loop of a few samples, too tight for rows to grow from: its first layers fold onto each other (a hill at
  // 5000 faces: "the layers fold", or 7 triangles and nothing else). L0 moves out to a ring kUmbilicRing cells
  // wider, away from the loop's middle, and its inner front lays inwards to the top as around seeded umbilics.
  const double diagonal = walker_.surface().bounds().diagonal().norm();
  for (int widen = 0; widen < 2 && row.closed && arcs.size() < kTinyLoop && row.curveLength < kTinyLoopShare * diagonal;
       ++widen) {
    Vec3 middle = Vec3::Zero();
    for (const SurfacePoint& p : row.curve) middle += p.point();
    middle /= double(row.curve.size());
    Vec3 out = start.point() - middle;
    out -= out.dot(start.g.normal) * start.g.normal;
    if (!(out.norm() > 0)) break;
    const Vec3 target = start.point() + kUmbilicRing * o_.cell * out.normalized();
    const SurfacePoint moved = walker_.project(target, start);
    if (walker_.isOutside(target, moved)) break;
    Row wider;
    std::vector<double> widerArcs;
    const FlowLine::End widerEnd = traceBase(moved, initial, wider, widerArcs);
    if (widerArcs.size() <= arcs.size()) break;
    ++widenedL0_;
    start = moved;
    row = std::move(wider);
    arcs = std::move(widerArcs);
    end = widerEnd;
  }
  if (arcs.size() < 2)
    cannotTile(start, "the base curve (a flow line of the field) is shorter than one cell, " +
                          std::string(end == FlowLine::End::Singularity ? "ending at a singularity of the field"
                                                                  : "ending at the boundary") +
                          "; choose a smaller cell, another start or another field");
  for (double t : arcs) {
    const SurfacePoint p = pointAtArc(walker_, row.curve, row.curveArc, row.closed, row.curveLength, t);
    row.ids.push_back(addVertex(p, std::numeric_limits<double>::quiet_NaN()));
  }
  row.sampleArc = arcs;
  std::vector<Vec3> line;
  for (const SurfacePoint& p : row.curve) line.push_back(p.point());
  if (row.closed) line.push_back(row.curve.front().point());
  fieldLines_.push_back(line);
  if (o_.method == LayingMethod::Progressive) setOwnCurve(row);
  return row;
}

Row reversed(Row row) {
  std::reverse(row.ids.begin(), row.ids.end());
  std::reverse(row.curve.begin(), row.curve.end());
  row.curveArc = cumulativeArc(row.curve);
  // Arc t from the old start is arc (last - t) from the new one, modulo the length around a loop.
  const double last = row.curveArc.back();
  for (double& a : row.sampleArc) a = row.closed ? std::fmod(last - a + row.curveLength, row.curveLength) : last - a;
  std::reverse(row.sampleArc.begin(), row.sampleArc.end());
  return row;
}

// The segment's apex direction and step: §5.1 (ideal triangle) with §5.3 (lower bound, re-use at parabolic curves).
Segment Laying::segment(const Row& row, int i) const {
  const int n = static_cast<int>(row.ids.size());
  const SurfacePoint& A = vertices_[row.ids[i]];
  const SurfacePoint& B = vertices_[row.ids[(i + 1) % n]];
  Segment s;
  s.M = walker_.project(0.5 * (A.point() + B.point()), A);
  const LocalGeometry& g = s.M.g;
  const Vec2 a = toTangentPlane(g, A.point()), b = toTangentPlane(g, B.point());
  s.base = (b - a).norm();
  const Vec2 along = (b - a) / s.base;
  const double ra = vertexRatio_[row.ids[i]], rb = vertexRatio_[row.ids[(i + 1) % n]];
  const double previous = std::isnan(ra) ? rb : std::isnan(rb) ? ra : 0.5 * (ra + rb);
  const IdealApex ideal = idealApex(g, a, b, Side::Left);
  Vec2 direction(-along.y(), along.x());
  double r;
  // Near a parabolic curve both asymptotic directions merge into the zero-curvature one, and a base close to
  // them is §5.3's business, not a sign that the field is asymptotic.
  const double kmax = g.largestCurvature(), kmin = std::min(std::abs(g.k1), std::abs(g.k2));
  const bool sheared = ideal.status == IdealApex::Status::Asymptotic ||
                       (ideal.ok() && std::abs(cross2(along, ideal.direction)) < kMinConjugateSine);
  IdealApex::Status status = ideal.status;
  if (sheared) status = kmin <= kNearParabolic * kmax ? IdealApex::Status::Parabolic : IdealApex::Status::Asymptotic;
  switch (status) {
    case IdealApex::Status::Ok: {
      direction = ideal.direction;
      s.validStep = ideal.validStep;
      r = ideal.step / s.base;
      if (r > o_.maxStepRatio) {
        // §5.3: the zero-curvature direction points across a parabolic curve and the ideal step explodes; the
        // previous layer's step carries the layer across. No bounded step is above DE here (the stars at the
        // crossing are as degenerate as the indicatrix), so Method 2 is not held to validStep.
        s.reused = s.exploded = true;
        s.validStep = 0;
        r = std::isnan(previous) ? o_.maxStepRatio : previous;
      } else if (o_.lowerBound > 0) {
        const double bounded = stepLowerBound(r, o_.lowerBound);
        s.bounded = bounded > r;
        // Where the bound takes over, the curvature along AB is vanishing and its conjugate direction turns
        // wildly with AB's slightest wobble; the triangle is no longer ideal anyway, so the apex direction is
        // eased towards the normal of AB as the bound dominates.
        const double eased = 1 - r / bounded;
        direction = ((1 - eased) * direction + eased * Vec2(-along.y(), along.x())).normalized();
        r = bounded;
      }
      break;
    }
    case IdealApex::Status::Parabolic: {
      // §5.3: no Dupin conic. The conjugate of AB is the zero-curvature direction (the ruling of a developable)
      // unless AB is that direction itself; the step is the previous layer's, or equilateral (the plane).
      const std::optional<Vec2> c = conjugateDirection(g, b - a);
      if (c && std::abs(cross2(along, *c)) >= kMinConjugateSine) direction = *c;
      s.reused = !std::isnan(previous);
      r = s.reused ? previous : kEquilateralRatio;
      break;
    }
    case IdealApex::Status::Asymptotic:
      s.asymptotic = true;
      return s;
    case IdealApex::Status::Degenerate:
    default:
      s.degenerate = true;  // the row is left without an apex there, like at a singularity of the field
      return s;
  }
  s.ratio = r;
  s.step = r * s.base;
  s.left = spatialVector(g, direction).normalized();
  s.apexInPlane = fromTangentPlane(g, 0.5 * (a + b) + s.step * direction);
  return s;
}

bool Laying::collides(const Vec3& p, double radius) const {
  bool hit = false;
  grid_.forNear(p, radius, [&](int id) { hit = hit || (!inBase_[id] && (vertices_[id].point() - p).norm() < radius); });
  return hit;
}

// Whether the triangle (a, b, c) would overlap a laid triangle, in the tangent plane at c: an edge crossing an
// edge, or one's centroid inside the other (shared corners aside). The vertex collision test keeps apexes off
// laid vertices; a later system's rows (run) must also keep off the triangles of the rows they meet.
bool Laying::overlapsLaid(int a, int b, const SurfacePoint& c) {
  for (; triangleGridCount_ < triangles_.size(); ++triangleGridCount_) {
    const Eigen::Vector3i& t = triangles_[triangleGridCount_];
    triangleGrid_.insert(static_cast<int>(triangleGridCount_),
                         (vertices_[t(0)].point() + vertices_[t(1)].point() + vertices_[t(2)].point()) / 3);
  }
  const LocalGeometry& g = c.g;
  const std::array<Vec2, 3> T = {toTangentPlane(g, vertices_[a].point()), toTangentPlane(g, vertices_[b].point()),
                                 toTangentPlane(g, c.point())};
  const std::array<int, 3> ids = {a, b, -1};
  const Vec3 centre = (vertices_[a].point() + vertices_[b].point() + c.point()) / 3;
  auto inside = [](const std::array<Vec2, 3>& t, const Vec2& p) {
    const double d1 = cross2(t[1] - t[0], p - t[0]), d2 = cross2(t[2] - t[1], p - t[1]), d3 = cross2(t[0] - t[2], p - t[2]);
    return (d1 > 0 && d2 > 0 && d3 > 0) || (d1 < 0 && d2 < 0 && d3 < 0);
  };
  bool hit = false;
  int near = 0;
  triangleGrid_.forNear(centre, 2 * o_.cell, [&](int k) {
    if (hit) return;
    // Far more triangles about the apex than a covering holds there: layers piling onto each other (the
    // bumps laid along section:45 from their middle piled 25k triangles within a few cells, each apex tested
    // against all of them, 8.5 s for one trial lay, until the vertex limit stopped it). The apex overlaps.
    if (++near > kPiledTriangles) {
      hit = true;
      return;
    }
    const Eigen::Vector3i& t = triangles_[k];
    std::array<Vec2, 3> U;
    for (int j = 0; j < 3; ++j) {
      const Vec3& x = vertices_[t(j)].point();
      if (std::abs((x - c.point()).dot(g.normal)) > 2 * o_.cell) return;  // another sheet
      U[j] = toTangentPlane(g, x);
    }
    for (int i = 0; i < 3 && !hit; ++i)
      for (int j = 0; j < 3 && !hit; ++j) {
        const int p = ids[i], q = ids[(i + 1) % 3], r = t(j), s = t((j + 1) % 3);
        if (p >= 0 && (p == r || p == s)) continue;
        if (q >= 0 && (q == r || q == s)) continue;
        hit = segmentsCross(T[i], T[(i + 1) % 3], U[j], U[(j + 1) % 3]);
      }
    if (!hit) hit = inside(U, (T[0] + T[1] + T[2]) / 3) || inside(T, (U[0] + U[1] + U[2]) / 3);
  });
  return hit;
}

// Method 1 (§5.2, Fig. 14): the ideal apex in the tangent plane at M_i, projected onto the surface.
// Laying conjugate rows forward is a Cauchy problem, ill-posed where K > 0: a wobble of the rows grows from
// layer to layer, the faster the shorter its wavelength (about e^(2 pi d / wavelength) over a distance d).
// The apex offsets M_i -> C_i are therefore smoothed along the row with weights (1, 2, 1) / 4, which leaves
// smooth variations (rotated copies on a surface of revolution) nearly untouched. One pass per layer damps
// a given wavelength less, the finer the cell (and the more layers cross the same distance), so the passes
// grow as 1 / cell (progressiveSmoothingPasses): the damping per unit distance stays that of one pass at
// about kSmoothingFaces faces. One pass only, on a torus laid at 4x as many faces, the two fronts arrive
// at the outer equator scalloped, with rows split and 180 invalid stars (694 layers); with 4 passes they meet
// level and zip with valence 6 kept (177 layers, 0 invalid stars).
std::vector<std::optional<Apex>> Laying::progressiveApexes(const Row& row, const std::vector<Segment>& segments) const {
  const int n = static_cast<int>(segments.size());
  std::vector<std::optional<Apex>> apexes(n);
  auto usable = [&](int i) { return i >= 0 && i < n && !segments[i].asymptotic && !segments[i].degenerate; };
  std::vector<Vec3> offset(n, Vec3::Zero()), smoothed(n);
  for (int i = 0; i < n; ++i)
    if (usable(i)) offset[i] = segments[i].apexInPlane - segments[i].M.point();
  for (int pass = 0; pass < smoothingPasses_; ++pass) {
    smoothed = offset;
    for (int i = 0; i < n; ++i) {
      const int before = row.closed ? (i + n - 1) % n : i - 1, after = row.closed ? (i + 1) % n : i + 1;
      if (usable(i) && usable(before) && usable(after))
        smoothed[i] = 0.5 * offset[i] + 0.25 * (offset[before] + offset[after]);
    }
    offset.swap(smoothed);
  }
  for (int i = 0; i < n; ++i) {
    const Segment& s = segments[i];
    if (!usable(i)) continue;
    const Vec3 x = s.M.point() + offset[i];
    const SurfacePoint p = walker_.project(x, s.M);
    if (!walker_.isOutside(x, p)) apexes[i] = Apex{p, s.ratio, 0.0};
  }
  return apexes;
}

std::optional<Crossing> Laying::crossCurve(const LocalGeometry& g, const FlowLine& ell, const std::vector<double>& ellArc,
                                           const Row& L, int& hint) const {
  const int n = static_cast<int>(L.curve.size());
  const int segments = L.closed ? n : n - 1;
  if (segments < 1 || ell.points.size() < 2) return std::nullopt;
  auto index = [&](int j) { return L.closed ? ((j % n) + n) % n : j; };
  // The curve vertex nearest to l's start: a full scan first, then a window ahead of the previous one.
  const Vec3& m = ell.points.front().point();
  int lo = 0, hi = n - 1;
  if (hint >= 0) lo = hint - 8, hi = hint + 96;
  if (!L.closed) lo = std::max(lo, 0), hi = std::min(hi, n - 1);
  int nearest = -1;
  double best = std::numeric_limits<double>::infinity();
  for (int j = lo; j <= hi; ++j) {
    const double d = (L.curve[index(j)].point() - m).squaredNorm();
    if (d < best) best = d, nearest = j;
  }
  if (nearest < 0) return std::nullopt;
  hint = index(nearest);
  // Everything in the tangent plane at l's start, each point once; pairs of segments whose boxes are apart
  // cannot cross and are skipped (the boxes are padded far beyond round-off, so no crossing is missed).
  const int ellCount = static_cast<int>(ell.points.size());
  std::vector<Vec2>& q = ellPlane_;
  q.resize(ellCount);
  Eigen::AlignedBox2d ellBox;
  for (int k = 0; k < ellCount; ++k) ellBox.extend(q[k] = toTangentPlane(g, ell.points[k].point()));
  const double pad = 1e-9 * (ellBox.diagonal().norm() + o_.cell);
  ellBox.min().array() -= pad;
  ellBox.max().array() += pad;
  std::optional<Crossing> first;
  int planeIndex = std::numeric_limits<int>::min();  // the curve point whose tangent-plane image is in `next`
  Vec2 next = Vec2::Zero();
  for (int j = nearest - 24; j <= nearest + 24; ++j) {
    if (!L.closed && (j < 0 || j + 1 >= n)) continue;
    const int j0 = index(j), j1 = index(j + 1);
    const Vec2 p = planeIndex == j ? next : toTangentPlane(g, L.curve[j0].point());
    next = toTangentPlane(g, L.curve[j1].point());
    planeIndex = j + 1;
    const Vec2 r = next - p;
    if (std::max(p.x(), next.x()) < ellBox.min().x() || std::min(p.x(), next.x()) > ellBox.max().x() ||
        std::max(p.y(), next.y()) < ellBox.min().y() || std::min(p.y(), next.y()) > ellBox.max().y())
      continue;
    for (int k = 0; k + 1 < ellCount; ++k) {
      const Vec2 s = q[k + 1] - q[k];
      const double den = cross2(r, s);
      if (std::abs(den) < 1e-300) continue;
      const double t = cross2(q[k] - p, s) / den, u = cross2(q[k] - p, r) / den;
      if (t < 0 || t > 1 || u < 0 || u > 1) continue;
      const double arc = ellArc[k] + u * (ellArc[k + 1] - ellArc[k]);
      if (first && first->ellArc <= arc) continue;
      const double segmentLength = (L.curve[j1].point() - L.curve[j0].point()).norm();
      const double curveArc = (j0 + 1 < n ? L.curveArc[j0] : L.curveArc.back()) + t * segmentLength;
      first = Crossing{arc, (1 - u) * ell.points[k].point() + u * ell.points[k + 1].point(), curveArc};
    }
  }
  return first;
}

// Method 2 (§5.2, Fig. 16): apexes on the flow lines l_i of D_G through the midpoints; the next base curve is
// the D_F flow line fitting the ideal apexes (least squares over its start on the middle l), raised until its
// crossings with every l_i lie above DE (so every star is valid); crossings still below DE are dropped.
std::vector<std::optional<Apex>> Laying::prespecifiedApexes(const Row& row, const std::vector<Segment>& segments,
                                                            Row& next, bool recordConjugateLines, bool fromL0) {
  const int n = static_cast<int>(segments.size());
  // The l_i are traced lazily: first a little beyond the ideal step, where the next base curve crosses them
  // as a rule, and on to their full length kEllLength * step only where a crossing is not found on the part
  // traced (FlowTracer gives the very points of a trace in one go, so the apexes are the same).
  std::vector<std::optional<FlowTracer>> ells(n);
  std::vector<std::vector<double>> ellArcs(n);
  auto updateArcs = [&](int i) {
    const std::vector<SurfacePoint>& points = ells[i]->line().points;
    std::vector<double>& arc = ellArcs[i];
    if (arc.empty()) arc.push_back(0.0);
    for (std::size_t k = arc.size(); k < points.size(); ++k)
      arc.push_back(arc[k - 1] + (points[k].point() - points[k - 1].point()).norm());
  };
  auto finishEll = [&](int i) {
    ells[i]->finish();
    updateArcs(i);
  };
  std::vector<std::optional<Apex>> apexes(n);
  int middle = -1;
  // A segment ending on the boundary (a row extended onto it) may be much shorter than the others, and so
  // is its step; its l_i is traced as far as the row's mean step allows, so that it reaches the next row, and
  // its step is left out of the fit of the next row (which would otherwise shift with every such end).
  std::vector<char> toBoundary(n, 0);
  double meanStep = 0;
  int stepCount = 0;
  for (const Segment& s : segments)
    if (!s.degenerate && !s.asymptotic) meanStep += s.step, ++stepCount;
  meanStep = stepCount > 0 ? meanStep / stepCount : 0.0;
  for (int i = 0; i < n; ++i) {
    const Segment& s = segments[i];
    if (s.degenerate) continue;
    std::optional<Vec3> d = s.asymptotic ? std::nullopt : field_.direction(s.M, G_, &s.left);
    const Vec3 ab = vertices_[row.ids[(i + 1) % row.ids.size()]].point() - vertices_[row.ids[i]].point();
    bool asymptotic = s.asymptotic;
    if (d && d->cross(ab.normalized()).norm() < kMinConjugateSine) {
      const double k1 = std::abs(s.M.g.k1), k2 = std::abs(s.M.g.k2);
      // Near a parabolic curve the conjugate degenerates (§5.3), near an umbilic D_G is undefined: lay across
      // as Method 1 would. Elsewhere AB runs along an asymptotic direction.
      if (std::min(k1, k2) > kNearParabolic * std::max(k1, k2) && !field_.isUmbilic(s.M.g)) asymptotic = true;
      d = s.left;
    }
    if (asymptotic) {
      // On L0 the field runs along an asymptotic direction: no valid triangle anywhere along it. On a later
      // row a segment that left the field (a row end moved onto the boundary; on a helicoid of radius 3 at
      // 1150 faces, one at the tenth layer, which failed the whole lay) gets no apex, and its front splits.
      if (fromL0) cannotTile(s.M, asymptoticWhy());
      if (!s.asymptotic && !asymptoticStops_++) firstAsymptoticStop_ = describe(walker_, s.M);  // (else counted)
      continue;
    }
    if (!d) continue;  // a singularity of D_G: no apex here
    toBoundary[i] = onBoundary_[row.ids[i]] || onBoundary_[row.ids[(i + 1) % row.ids.size()]];
    ells[i].emplace(field_, G_, s.M, *d, kEllLength * (toBoundary[i] ? std::max(s.step, meanStep) : s.step), false);
  }
  // Each l_i on its own (over threads), past the step (strictly), so that whether it is longer than the step is
  // known.
  parallelRanges(n, kEllsPerThread, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      if (!ells[i]) continue;
      if (recordConjugateLines) ells[i]->finish();
      else ells[i]->advance(std::nextafter(kEllFirst * segments[i].step, std::numeric_limits<double>::infinity()));
    }
  });
  for (int i = 0; i < n; ++i) {
    if (!ells[i]) continue;
    updateArcs(i);
    if (ells[i]->line().length > segments[i].step && (middle < 0 || std::abs(i - n / 2) < std::abs(middle - n / 2))) middle = i;
    if (recordConjugateLines) {
      std::vector<Vec3> line;
      for (const SurfacePoint& p : ells[i]->line().points) line.push_back(p.point());
      fieldLines_.push_back(line);
    }
  }
  if (middle < 0) return apexes;
  finishEll(middle);  // the next base curve starts on it, anywhere along it
  const FlowLine& ellMiddle = ells[middle]->line();
  // The first crossing of l_i with `next`, tracing l_i on when the part traced does not reach it.
  auto crossing = [&](int i, int& hint) -> std::optional<Crossing> {
    if (!ells[i]) return std::nullopt;
    const int hint0 = hint;
    for (;;) {
      const FlowLine& ell = ells[i]->line();
      std::optional<Crossing> c =
          ell.points.size() > 1 ? crossCurve(segments[i].M.g, ell, ellArcs[i], next, hint) : std::nullopt;
      if (c || ells[i]->finished()) return c;
      hint = hint0;
      finishEll(i);
    }
  };

  const Vec3 rowDirection =
      vertices_[row.ids[(middle + 1) % row.ids.size()]].point() - vertices_[row.ids[middle]].point();
  const double rowAhead = row.closed ? row.curveLength : row.sampleArc.back() - row.sampleArc[middle];
  // A closed row whose next flow line does not close (it leaves the surface, e.g. a loop around a bump that
  // reaches the boundary) is traced backwards as far as forwards, so that the whole loop is followed.
  const double rowBehind = row.closed ? row.curveLength : row.sampleArc[middle] - row.sampleArc.front();
  std::vector<std::optional<Crossing>> crossings(n);
  double s0 = segments[middle].step;
  for (int iteration = 0; iteration < 6; ++iteration) {
    s0 = std::min(s0, ellMiddle.length);
    const SurfacePoint start = pointAtArc(walker_, ellMiddle.points, ellArcs[middle], false, ellMiddle.length, s0);
    // With threads to spare the backward line is traced beside the forward one, and used where that does not close.
    FlowLine forward, backward;
    const bool both = threadCount() > 1;
    auto traceBackward = [&] {
      backward = traceFlowLine(field_, F_, start, -rowDirection, 1.5 * rowBehind + 4 * o_.cell, false);
    };
    parallelTasks(both ? 2 : 1, [&](int k) {
      if (k == 1) return traceBackward();
      forward = traceFlowLine(field_, F_, start, rowDirection, 1.5 * rowAhead + 4 * o_.cell, row.closed);
    });
    next = Row{};
    if (forward.end == FlowLine::End::Closed) {
      next.closed = true;
      next.curve = forward.points;
    } else {
      if (!both) traceBackward();
      next.curve.assign(backward.points.rbegin(), backward.points.rend());
      next.curve.insert(next.curve.end(), forward.points.begin() + 1, forward.points.end());
    }
    next.curveArc = cumulativeArc(next.curve);
    next.curveLength = next.closed ? forward.length : next.curveArc.back();
    int hint = -1;
    double fit = 0, norm = 0, raise = 1;
    for (int i = 0; i < n; ++i) {
      crossings[i] = crossing(i, hint);
      if (!crossings[i]) continue;
      const double t = crossings[i]->ellArc;
      if (!toBoundary[i]) fit += segments[i].step * t, norm += t * t;
      if (t > 0) raise = std::max(raise, kValidMargin * segments[i].validStep / t);
    }
    if (norm <= 0 || iteration == 5) break;
    // Crossings move about in proportion to the start's distance s0 from the base: the least-squares scale of
    // s0 towards the ideal steps first, then the raise that lifts every crossing above DE.
    const double scale = iteration == 0 ? fit / norm : raise;
    if (std::abs(scale - 1) < 1e-3) break;
    s0 *= scale;
  }
  for (int i = 0; i < n; ++i) {
    if (!crossings[i]) continue;
    const Segment& s = segments[i];
    if (!(crossings[i]->ellArc > s.validStep)) {
      if (!invalidDrops_++) firstInvalidDrop_ = describe(walker_, s.M);
      continue;
    }
    const SurfacePoint p = walker_.project(crossings[i]->point, s.M);
    if (walker_.isOutside(crossings[i]->point, p)) continue;
    apexes[i] = Apex{p, crossings[i]->ellArc / s.base, crossings[i]->curveArc};
  }
  return apexes;
}

// Adds a vertex before the first (or after the last) of an open row, so that rows keep reaching the boundary
// instead of shrinking by one segment per layer: further along the row's curve where it goes on (Method 2's
// flow line), else by extrapolating the row (Method 1). Where Method 2's flow line ends on the boundary before
// that point, the vertex goes onto its end if that is at least kBoundaryMin of the spacing and kBoundaryMinCells
// cells away, and the row's end is moved onto it (snapRowEnd) if it is closer than kBoundaryMin of the spacing
// and the last segment is then no longer than kBoundaryMaxCells cells, so that rows end on the boundary where
// that makes no edge much shorter or longer than a cell. (Method 1's rows, whose polylines are their own curves,
// would bend at such an end and pass the bend on: they stop short as before.) Returns false when no vertex was
// added: there is no such point, it is taken, or the row end was moved or left.
bool Laying::extendRow(Row& row, bool atStart) {
  const int n = static_cast<int>(row.ids.size());
  if (row.closed || n < 2) return false;
  const int end = atStart ? 0 : n - 1, inner = atStart ? 1 : n - 2;
  const SurfacePoint& e = vertices_[row.ids[end]];
  const double spacing = std::abs(row.sampleArc[end] - row.sampleArc[inner]);
  double t = row.sampleArc[end] + (atStart ? -spacing : spacing);
  bool toBoundary = false;
  SurfacePoint p;
  if (t >= 0 && t <= row.curveLength && o_.method == LayingMethod::Prespecified) {
    p = pointAtArc(walker_, row.curve, row.curveArc, false, row.curveLength, t);
  } else if (o_.method == LayingMethod::Progressive) {
    const Vec3 x = 2 * e.point() - vertices_[row.ids[inner]].point();
    p = walker_.project(x, e);
    if (walker_.isOutside(x, p)) return false;
  } else if (row.curveLength > 0) {
    // Method 2: the row's flow line ends before the next sample; onto its end if that is on the boundary (just
    // beyond it along the line is outside) and the line crosses the boundary steeply: where it runs into it
    // slantwise, an end moved along it would skew the triangles at the end and the rows laid from them.
    const double curveEnd = atStart ? 0.0 : row.curveLength, gap = std::abs(curveEnd - row.sampleArc[end]);
    if (row.curve.size() < 2) return false;
    const SurfacePoint& last = atStart ? row.curve.front() : row.curve.back();
    const SurfacePoint& before = atStart ? row.curve[1] : row.curve[row.curve.size() - 2];
    const Vec3 along = last.point() - before.point();
    if (!(along.norm() > 0)) return false;
    // Beyond the boundary the projection stays on it: the offset from there, in the tangent plane, points
    // outward across the boundary.
    const Vec3 probe = last.point() + (0.25 * spacing / along.norm()) * along;
    const SurfacePoint foot = walker_.project(probe, last);
    Vec3 outward = probe - foot.point();
    outward -= outward.dot(foot.g.normal) * foot.g.normal;
    if (!(outward.norm() > walker_.outsideTolerance()) ||
        outward.dot(along) < kBoundaryCrossing * outward.norm() * along.norm())
      return false;
    if (!(gap >= kBoundaryMin * spacing)) {
      if (spacing + gap <= kBoundaryMaxCells * o_.cell) snapRowEnd(row, atStart, last, curveEnd);
      return false;
    }
    if (!(gap >= kBoundaryMinCells * o_.cell)) return false;
    t = curveEnd;
    p = last;
    toBoundary = true;
  } else {
    return false;
  }
  if (collides(p.point(), 0.5 * spacing)) return false;
  const int id = addVertex(p, vertexRatio_[row.ids[end]], vertexHeight_[row.ids[end]]);
  inBase_[id] = 1;
  onBoundary_[id] = toBoundary;
  if (atStart) {
    row.ids.insert(row.ids.begin(), id);
    row.sampleArc.insert(row.sampleArc.begin(), t);
  } else {
    row.ids.push_back(id);
    row.sampleArc.push_back(t);
  }
  if (o_.method == LayingMethod::Progressive) setOwnCurve(row);
  return true;
}

// A row end closer to the boundary than kBoundaryMin of the spacing is moved onto it (to `onto`, at arc
// `arc` along the row's curve), so that the row still ends on the boundary without a sliver segment: by less
// than its segment, not a vertex on the boundary already, not closer than half the segment to a vertex of
// another row (the collision test of extendRow), and where the end of the row below is on the boundary too
// (their edge then runs along it), only if that edge stays on the surface (chordOnSurface).
void Laying::snapRowEnd(Row& row, bool atStart, const SurfacePoint& onto, double arc) {
  const int n = static_cast<int>(row.ids.size());
  const int id = row.ids[atStart ? 0 : n - 1], inner = row.ids[atStart ? 1 : n - 2];
  const double shift = (onto.point() - vertices_[id].point()).norm();
  const double segment = (vertices_[inner].point() - vertices_[id].point()).norm();
  if (onBoundary_[id] || !(shift < segment) || collides(onto.point(), 0.5 * segment)) return;
  const int below = atStart ? row.belowStart : row.belowEnd;
  if (below >= 0 && onBoundary_[below] && !chordOnSurface(vertices_[below], onto)) return;
  vertices_[id] = onto;
  onBoundary_[id] = 1;
  grid_.insert(id, onto.point());  // (its old cell keeps it too: the collision test reads the new position)
  row.sampleArc[atStart ? 0 : n - 1] = arc;
  ++snappedEnds_;
}

// Whether the midpoint of the chord between two points on the boundary lies on the surface: its offset from
// its projection, in the tangent plane there, is at most kChordOffBoundary cells. A chord between two points of
// a boundary that bulges outward between them (a mesh's zigzag boundary polyline) leaves the surface, and with
// it the P-Hex vertex of the boundary edge (the tangent dual puts it at about the midpoint).
bool Laying::chordOnSurface(const SurfacePoint& a, const SurfacePoint& b) const {
  const Vec3 mid = 0.5 * (a.point() + b.point());
  const SurfacePoint foot = walker_.project(mid, a);
  Vec3 off = mid - foot.point();
  off -= off.dot(foot.g.normal) * foot.g.normal;
  return !(off.norm() > kChordOffBoundary * o_.cell);
}

// After extendRow added a vertex before the first (or after the last) of `row`: the triangle between it, the
// row's old end and the vertex of the row below beyond the old end's apex segment (Row::belowStart /
// belowEnd), which the layer below left open (a notch at every other row end along the boundary): only where
// both it and that vertex are on the boundary (the triangle's third edge runs along it), not where it would be
// folded or a sliver or that edge leaves the surface (chordOnSurface), and Method 2 only (like the ends on the
// boundary, extendRow).
void Laying::closeRowEnd(const Row& row, bool atStart) {
  const int n = static_cast<int>(row.ids.size());
  const int below = atStart ? row.belowStart : row.belowEnd;
  if (below < 0 || n < 3 || o_.method != LayingMethod::Prespecified) return;
  const int added = atStart ? row.ids[0] : row.ids[n - 1], old = atStart ? row.ids[1] : row.ids[n - 2];
  if (!onBoundary_[added] || !onBoundary_[below]) return;
  // CCW seen from the normal: the row runs forward with the row below to its right.
  const Eigen::Vector3i tri = atStart ? Eigen::Vector3i(below, old, added) : Eigen::Vector3i(below, added, old);
  const Vec3 &a = vertices_[tri(0)].point(), &b = vertices_[tri(1)].point(), &c = vertices_[tri(2)].point();
  const Vec3 normal = (b - a).cross(c - a);
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  if (!(longest > 0) || !(normal.dot(vertices_[old].g.normal) > 0.2 * longest * longest)) return;
  if (!chordOnSurface(vertices_[below], vertices_[added])) return;
  triangles_.push_back(tri);
  ++boundaryEnds_;
}

// Triangles between two rows running the same way, Q to the left of P: each step advances along P (triangle
// P_i P_i+1 Q_j) or along Q (triangle P_i Q_j+1 Q_j), whichever makes the shorter diagonal. Two loops of equal
// count alternate strictly, which gives every vertex three triangles on each side: valence 6 is kept.
void Laying::zip(std::vector<int> P, bool closedP, std::vector<int> Q, bool closedQ) {
  auto at = [&](int id) -> const Vec3& { return vertices_[id].point(); };
  auto nearestTo = [&](const std::vector<int>& row, const Vec3& x) {
    int best = 0;
    for (int k = 1; k < static_cast<int>(row.size()); ++k)
      if ((at(row[k]) - x).squaredNorm() < (at(row[best]) - x).squaredNorm()) best = k;
    return best;
  };
  if (P.size() < 2 || Q.size() < 2) return;
  if (closedP && closedQ) {
    const int n = static_cast<int>(P.size()), m = static_cast<int>(Q.size());
    std::rotate(Q.begin(), Q.begin() + nearestTo(Q, 0.5 * (at(P[0]) + at(P[1]))), Q.end());
    bool advanceP = (at(P[1]) - at(Q[0])).norm() <= (at(P[0]) - at(Q[1 % m])).norm();
    for (int i = 0, j = 0; i < n || j < m;) {
      if (i == n) advanceP = false;
      else if (j == m) advanceP = true;
      else if (n != m) advanceP = (at(P[(i + 1) % n]) - at(Q[j % m])).norm() <= (at(P[i % n]) - at(Q[(j + 1) % m])).norm();
      if (advanceP) addTriangle(P[i % n], P[(i + 1) % n], Q[j % m]), ++i;
      else addTriangle(P[i % n], Q[(j + 1) % m], Q[j % m]), ++j;
      advanceP = !advanceP;
    }
    return;
  }
  // Open rows (a loop facing an open row is unrolled at the point nearest the other's start).
  if (closedP) std::rotate(P.begin(), P.begin() + nearestTo(P, at(Q[0])), P.end()), P.push_back(P[0]);
  if (closedQ) std::rotate(Q.begin(), Q.begin() + nearestTo(Q, at(P[0])), Q.end()), Q.push_back(Q[0]);
  const int n = static_cast<int>(P.size()), m = static_cast<int>(Q.size());
  const int j0 = nearestTo(Q, at(P[0]));
  int i = j0 > 0 ? 0 : nearestTo(P, at(Q[0])), j = j0;
  const double limit = 2.5 * o_.cell;  // past the end of the shorter row the fan stops where the rows part
  while (i + 1 < n || j + 1 < m) {
    const double dP = i + 1 < n ? (at(P[i + 1]) - at(Q[j])).norm() : std::numeric_limits<double>::infinity();
    const double dQ = j + 1 < m ? (at(P[i]) - at(Q[j + 1])).norm() : std::numeric_limits<double>::infinity();
    if (std::min(dP, dQ) > limit) break;
    if (dP <= dQ) addTriangle(P[i], P[i + 1], Q[j]), ++i;
    else addTriangle(P[i], Q[j + 1], Q[j]), ++j;
  }
}

// Whether the bounding boxes of rows P and Q, P's grown by `pad`, overlap.
bool Laying::rowsWithin(const std::vector<int>& P, const std::vector<int>& Q, double pad) const {
  Box3 boxP, boxQ;
  for (int id : P) boxP.extend(vertices_[id].point());
  for (int id : Q) boxQ.extend(vertices_[id].point());
  return Box3(boxP.min() - Vec3::Constant(pad), boxP.max() + Vec3::Constant(pad)).intersects(boxQ);
}

// At P's k-th vertex: P's tangent there (central difference), its left across the row, and the offset to Q's
// nearest vertex with its length.
Laying::RowOffset Laying::offsetToRow(const std::vector<int>& P, int k, const std::vector<int>& Q) const {
  const int n = static_cast<int>(P.size());
  const SurfacePoint& p = vertices_[P[k]];
  RowOffset r;
  r.tangent = vertices_[P[std::min(k + 1, n - 1)]].point() - vertices_[P[std::max(k - 1, 0)]].point();
  r.left = p.g.normal.cross(r.tangent).normalized();
  for (int id : Q) {
    const double d = (vertices_[id].point() - p.point()).norm();
    if (d < r.distance) r.distance = d, r.offset = vertices_[id].point() - p.point();
  }
  return r;
}

// True when b's row lies just ahead of a's (to its left), closer than kZipGap steps along most of a.
bool Laying::facing(const Front& a, const Front& b) const {
  const std::vector<int>& P = a.row.ids;
  const std::vector<int>& Q = b.row.ids;
  if (P.size() < 2 || Q.size() < 2) return false;
  const double gap = kZipGap * std::max({a.lastStep, b.lastStep, 0.25 * o_.cell});
  if (!rowsWithin(P, Q, gap)) return false;
  const int n = static_cast<int>(P.size()), stride = std::max(1, n / 48);
  int samples = 0, near = 0;
  for (int k = 0; k < n; k += stride) {
    ++samples;
    const RowOffset r = offsetToRow(P, k, Q);
    near += r.distance < gap && r.offset.dot(r.left) > 0.2 * r.distance;
  }
  return 2 * near >= samples;
}

// How far b's row lies ahead of a's (to its left), in a's steps: the median over a's vertices of the gap across
// a's row to b's nearest vertex, divided by the height that vertex was laid at (about the step the next layer
// takes there). nullopt unless b's row lies ahead along most of a, within about kMeetReach steps.
std::optional<double> Laying::facingGap(const Front& a, const Front& b, bool& staggered) const {
  const std::vector<int>& P = a.row.ids;
  const std::vector<int>& Q = b.row.ids;
  if (P.size() < 2 || Q.size() < 2) return std::nullopt;
  const double fallback = std::max({a.lastStep, b.lastStep, 0.25 * o_.cell});
  auto stepAt = [&](int id) {
    const double h = vertexHeight_[id];
    return h > 0 ? std::max(h, 0.25 * o_.cell) : fallback;
  };
  double widest = 0;
  for (int id : P) widest = std::max(widest, stepAt(id));
  const double reach = kMeetReach + 0.5;  // the nearest vertex may be half a spacing along the row
  if (!rowsWithin(P, Q, reach * widest)) return std::nullopt;
  const int n = static_cast<int>(P.size()), stride = std::max(1, n / 48);
  int samples = 0, halfway = 0;
  std::vector<double> gaps;
  for (int k = 0; k < n; k += stride) {
    ++samples;
    const SurfacePoint& p = vertices_[P[k]];
    const RowOffset r = offsetToRow(P, k, Q);
    const Vec3 &tangent = r.tangent, &offset = r.offset;
    const double best = r.distance;
    const double step = stepAt(P[k]), across = offset.dot(r.left);
    // Ahead along the surface, not across a tube or a fold (the offset lies nearly in the tangent plane).
    if (best < reach * step && across > 0.2 * best && std::abs(offset.dot(p.g.normal)) < 0.5 * best) {
      gaps.push_back(across / step);
      // Half a spacing along the row (a regular zip) or level with it (its triangles would be right-angled).
      const double spacing = 0.5 * tangent.norm() * (k > 0 && k + 1 < n ? 1.0 : 2.0);
      halfway += std::abs(offset.dot(tangent.normalized())) > 0.25 * spacing;
    }
  }
  if (gaps.empty() || 2 * static_cast<int>(gaps.size()) < samples) return std::nullopt;
  staggered = 2 * halfway >= static_cast<int>(gaps.size());
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  return gaps[gaps.size() / 2];
}

// Zips front f to a front facing it. The rows of split fronts, and an open row meeting a closed one, are zipped
// to the first front within kZipGap steps. L0's two fronts, neither split, both open (going round a surface
// closed across L0, they meet at its seam) or both closed (loops around a tube, meeting on its far side), are
// zipped when the gap between them is about one layer high; when it is a few layers high, stepScale receives
// the factor that makes them equal, for f's next layer (else 1). Closed loops met at whatever gap was left
// before (kZipGap): on the uploaded torus at 1000 faces that left 24 self-intersecting faces (0 now), and by
// Method 1 on the torus at cell 0.035 a strip of apexes dropped as overlapping instead of a zip.
bool Laying::zipIfMeeting(std::size_t f, double& stepScale) {
  stepScale = 1;
  std::size_t nearest = fronts_.size();
  double gap = kMeetReach;
  bool staggered = true;
  const bool unsplit = fronts_.size() - systemFront0_ == 2;  // the two fronts of this system's L0, neither split yet
  for (std::size_t k = 0; k < fronts_.size() && gap > 0; ++k) {
    if (k == f || !fronts_[k].active) continue;
    // Two loops meet only as about equal loops around a tube; a loop shrunk onto an umbilic is no partner for
    // the ring around it (zipped all around, their triangles would span the region between them).
    if (fronts_[f].row.closed && fronts_[k].row.closed) {
      const std::size_t n = fronts_[f].row.ids.size(), m = fronts_[k].row.ids.size();
      if (std::min(n, m) < 3 || 2 * std::min(n, m) < std::max(n, m)) continue;
    }
    if (!unsplit || fronts_[f].row.closed != fronts_[k].row.closed) {
      if (facing(fronts_[f], fronts_[k])) gap = 0, nearest = k;
      continue;
    }
    // Each along most of the other. Where the gap cannot be measured so (one row across a tube from the
    // other), the kZipGap rule.
    bool s = true, t = true;
    const std::optional<double> g = facingGap(fronts_[f], fronts_[k], s);
    if (g && facingGap(fronts_[k], fronts_[f], t)) {
      if (*g < gap) gap = *g, nearest = k, staggered = s;
    } else if (facing(fronts_[f], fronts_[k])) {
      gap = 0, nearest = k;
    }
  }
  if (nearest == fronts_.size()) return false;
  // Whole layers no lower than a step: Method 2 cannot lay them much lower anyway (its rows are raised until every
  // star is valid), and a K < 0 star only stays valid with its apex far enough from the base. As many as keep the
  // rows zipped last half a spacing apart along them: an odd count from staggered rows, an even one from level rows.
  int layers = std::max(1, static_cast<int>(std::floor(gap)));
  if (layers > 1 && (layers % 2 == 1) != staggered) --layers;
  if (layers > 1) {
    stepScale = gap / layers;
    return false;
  }
  const Row& a = fronts_[f].row;
  Row b = reversed(fronts_[nearest].row);
  zip(a.ids, a.closed, b.ids, b.closed);
  std::ostringstream note;
  note << "two fronts met near " << describe(walker_, vertices_[a.ids[a.ids.size() / 2]]) << " and were zipped ("
       << a.ids.size() << " and " << b.ids.size() << " vertices"
       << (a.ids.size() == b.ids.size() && a.closed && b.closed ? ", valence 6 kept"
                                                                 : ", irregular vertices where the counts differ")
       << ")";
  zipNotes_.push_back(note.str());
  fronts_[f].active = fronts_[nearest].active = false;
  return true;
}

// stepScale < 1 or > 1 lays the layer lower or higher than §5.1 / §5.3 would (to share out a gap, zipIfMeeting).
void Laying::layLayer(std::size_t f, double stepScale) {
  Row A = fronts_[f].row;
  for (int id : A.ids) inBase_[id] = 1;
  for (int k = 0; k < 2; ++k) {
    if (extendRow(A, true) && k == 0) closeRowEnd(A, true);
    if (extendRow(A, false) && k == 0) closeRowEnd(A, false);
  }
  const int count = static_cast<int>(A.ids.size());
  const int n = A.closed ? count : count - 1;
  std::vector<Segment> segments;
  for (int i = 0; i < n; ++i) {
    segments.push_back(segment(A, i));
    if (!segments.back().asymptotic) continue;
    // From L0 this is the field's doing: fail. Later, Method 1's rows have turned there (§5.2: their
    // orientation is not controlled): that front stops there.
    if (fronts_[f].layers == 0 && systems_ == 1)
      cannotTile(segments.back().M, asymptoticWhy());
    if (!asymptoticStops_++) firstAsymptoticStop_ = describe(walker_, segments.back().M);
  }
  if (stepScale != 1)
    for (Segment& s : segments) {
      if (s.asymptotic || s.degenerate) continue;
      s.step *= stepScale;
      s.apexInPlane = s.M.point() + stepScale * (s.apexInPlane - s.M.point());
    }
  Row next;
  std::vector<std::optional<Apex>> apexes = o_.method == LayingMethod::Progressive
                                                ? progressiveApexes(A, segments)
                                                : prespecifiedApexes(A, segments, next, layers_ < 2,
                                                                     fronts_[f].layers == 0 && systems_ == 1);
  // A loop shrunk to a few vertices (closing onto an umbilic or a pole) lays its last rows over the ones before.
  const bool shrunk = A.closed && count < kShrunkLoop;
  for (int i = 0; i < n; ++i)
    if (apexes[i] && collides(apexes[i]->p.point(), std::max(0.5 * std::min(segments[i].step, segments[i].base),
                                                              shrunk ? 0.35 * o_.cell : 0.0))) {
      apexes[i].reset();
      ++collisions_;
    } else if (apexes[i] && (systems_ > 1 || shrunk) && overlapsLaid(A.ids[i], A.ids[(i + 1) % count], apexes[i]->p)) {
      apexes[i].reset();
      ++collisions_;
    }
  // A loop closing onto an umbilic can lay two neighbouring apexes onto each other (its fitted curve no
  // longer follows the apexes there): the second is dropped.
  if (A.closed && o_.method == LayingMethod::Prespecified)
    for (int i = 0; i < n; ++i) {
      const int j = (i + 1) % n;
      if (j != i && apexes[i] && apexes[j] &&
          (apexes[i]->p.point() - apexes[j]->p.point()).norm() < 0.2 * std::min(segments[i].base, segments[j].base)) {
        apexes[j].reset();
        ++collisions_;
      }
    }
  // A later system's rows may also turn over on themselves (a small ring around an umbilic shrinking onto it):
  // an apex whose triangles would face against the surface normal is dropped.
  if (systems_ > 1)
    for (int i = 0; i < n; ++i) {
      if (!apexes[i]) continue;
      const Vec3 &a = vertices_[A.ids[i]].point(), &b = vertices_[A.ids[(i + 1) % count]].point();
      const Vec3& c = apexes[i]->p.point();
      const Vec3& normal = apexes[i]->p.g.normal;
      bool upright = (b - a).cross(c - a).dot(normal) > 0;
      const int j = A.closed ? (i + 1) % n : i + 1;
      if (upright && j < n && apexes[j]) upright = (apexes[j]->p.point() - b).cross(c - b).dot(normal) > 0;
      if (!upright) {
        apexes[i].reset();
        ++collisions_;
      }
    }
  // A single missing apex between two laid ones (a collision, a crossing that failed, a drop below DE) would
  // split the row — a closed one into an open row whose ends then shrink layer by layer, leaving wedges of
  // the surface uncovered. It is filled in between its neighbours instead; the star check and the repair
  // judge it like any other vertex.
  for (int i = 0; i < n; ++i) {
    const int before = A.closed ? (i + n - 1) % n : i - 1, after = A.closed ? (i + 1) % n : i + 1;
    if (apexes[i] || before < 0 || after >= n || !apexes[before] || !apexes[after] || segments[i].asymptotic) continue;
    const Apex& a = *apexes[before];
    const Apex& b = *apexes[after];
    Apex filled;
    if (o_.method == LayingMethod::Prespecified) {
      if (next.curve.size() < 2) continue;
      double t = b.arc;
      if (next.closed && t < a.arc) t += next.curveLength;
      t = 0.5 * (a.arc + t);
      if (next.closed) t = std::fmod(t, next.curveLength);
      if (!next.closed && (t < 0 || t > next.curveLength)) continue;
      filled.p = pointAtArc(walker_, next.curve, next.curveArc, next.closed, next.curveLength, t);
      filled.arc = t;
    } else {
      const Vec3 x = 0.5 * (a.p.point() + b.p.point());
      filled.p = walker_.project(x, a.p);
      if (walker_.isOutside(x, filled.p)) continue;
    }
    filled.ratio = 0.5 * (a.ratio + b.ratio);
    const double spacing = 0.5 * (a.p.point() - b.p.point()).norm();
    if (!(spacing > 0) || collides(filled.p.point(), 0.5 * std::min(spacing, segments[i].base))) continue;
    // Between its neighbours: on a closed row whose neighbours' arcs came out in the wrong order (b a hair
    // before a), the middle of the arc from a to b is on the far side of the loop (a coarse torus refined at
    // 1000 faces: a vertex filled in across its hole, five triangles 3.2 long, a node 0.8 off the surface).
    const double reach = 2 * std::max(spacing, segments[i].base);
    if ((filled.p.point() - a.p.point()).norm() > reach || (filled.p.point() - b.p.point()).norm() > reach) continue;
    apexes[i] = filled;
    ++filledApexes_;
  }
  for (int id : A.ids) inBase_[id] = 0;

  bool bounded = false, reused = false;
  for (const Segment& s : segments) {
    bounded = bounded || s.bounded;
    reused = reused || s.reused;
    boundedSegments_ += s.bounded;
    reusedSegments_ += s.reused;
    if (s.reused && firstReuse_.empty()) firstReuse_ = describe(walker_, s.M);
  }
  boundedLayers_ += bounded;
  reusedLayers_ += reused;
  ++layers_;

  // Runs of consecutive apexes; each run of two or more becomes the row of a front.
  std::vector<std::pair<int, int>> runs;  // first segment, number of segments
  const bool complete = std::all_of(apexes.begin(), apexes.end(), [](const auto& a) { return a.has_value(); });
  if (A.closed && complete) {
    runs.emplace_back(0, n);
  } else {
    int begin = 0;
    if (A.closed) while (apexes[begin]) ++begin;  // start after a gap so no run wraps in two pieces
    for (int k = 0; k < n;) {
      const int i = (begin + k) % n;
      if (!apexes[i]) {
        ++k;
        continue;
      }
      int length = 0;
      while (k + length < n && apexes[(begin + k + length) % n]) ++length;
      runs.emplace_back(i, length);
      k += length;
    }
  }
  std::vector<Front> produced;
  bool alongParabolic = false;  // a run dropped for running along a parabolic curve (kMaxReusedLayers)
  for (const auto& [first, length] : runs) {
    if (length < 2) continue;
    const bool closedRun = A.closed && length == n;
    int explodedHere = 0;
    for (int k = 0; k < length; ++k) explodedHere += segments[(first + k) % n].exploded;
    const int explodedRun = 2 * explodedHere >= length ? fronts_[f].explodedLayers + 1 : 0;
    if (explodedRun > kMaxReusedLayers) {
      if (firstAlongParabolic_.empty()) firstAlongParabolic_ = describe(walker_, segments[first].M);
      alongParabolic = true;
      continue;
    }
    Front front;
    front.explodedLayers = explodedRun;
    Row& C = front.row;
    C.closed = closedRun;
    std::vector<Apex> run;
    std::vector<double> heights;  // of the apexes above their bases
    double step = 0, height = 0;
    for (int k = 0; k < length; ++k) {
      const int i = (first + k) % n;
      run.push_back(*apexes[i]);
      step += segments[i].step;
      const Vec3 &a = vertices_[A.ids[i]].point(), &b = vertices_[A.ids[(i + 1) % count]].point();
      heights.push_back((b - a).cross(run.back().p.point() - a).norm() / std::max((b - a).norm(), 1e-300));
      height += heights.back() / length;
    }
    front.lastStep = step / length;
    // The row's curve: Method 2's fitted flow line, or Method 1's apex polyline.
    if (o_.method == LayingMethod::Prespecified) {
      C.curve = next.curve;
      C.curveArc = next.curveArc;
      C.curveLength = next.curveLength;
      for (const Apex& a : run) C.sampleArc.push_back(a.arc);
      if (!closedRun) {  // arcs increase along an open row; a run may straddle the start of a closed curve
        for (std::size_t k = 1; k < C.sampleArc.size(); ++k)
          if (C.sampleArc[k] < C.sampleArc[k - 1]) C.sampleArc[k] += C.curveLength;
        if (next.closed) C.closed = false, C.curveLength = 0;  // unrolled below when resampled
      }
    } else {
      for (const Apex& a : run) C.curve.push_back(a.p);
      C.curveArc = cumulativeArc(C.curve);
      C.curveLength = C.curveArc.back() + (closedRun ? (C.curve.back().point() - C.curve.front().point()).norm() : 0.0);
      C.sampleArc = C.curveArc;
    }
    double spacing = 0;
    for (int k = 0; k + 1 < length; ++k) spacing += (run[k + 1].p.point() - run[k].p.point()).norm();
    if (closedRun) spacing += (run.front().p.point() - run.back().p.point()).norm();
    spacing /= closedRun ? length : length - 1;
    std::vector<int> below;  // the base vertices under the run
    for (int k = 0; k <= (closedRun ? length - 1 : length); ++k) below.push_back(A.ids[(first + k) % count]);

    const bool curveUsable = C.curveLength > 0 || o_.method == LayingMethod::Progressive;
    // Not on a row at a parabolic curve: the pentagons and heptagons a resample leaves where the counts
    // change would sit where the Dupin dual is least stable; the next rows past the curve take it.
    int parabolic = 0;
    const double nearParabolic = spacing > o_.cell ? kResampleParabolic : kNearParabolic;
    for (const Apex& a : run) {
      const double kmax = a.p.g.largestCurvature();
      parabolic += kmax > 0 && std::min(std::abs(a.p.g.k1), std::abs(a.p.g.k2)) < nearParabolic * kmax;
    }
    const bool atParabolic = 5 * parabolic > length && spacing < kResampleLimit * o_.cell;
    bool resampled = false;
    if (curveUsable && !atParabolic && (spacing < kResampleBelow * o_.cell || spacing > kResampleAbove * o_.cell)) {
      // The row's spacing drifted far from the cell: re-sample it evenly along its curve, zip it to the base.
      double ratio = 0;
      for (const Apex& a : run) ratio += a.ratio / length;
      // Samples about a cell apart over `span` of C's curve from `from` (a loop's whole length when closedRun).
      std::vector<double> arcs;
      std::vector<SurfacePoint> points;
      auto spread = [&](double from, double span) {
        const int m = closedRun ? std::max(3, static_cast<int>(std::lround(span / o_.cell)))
                                : std::max(2, static_cast<int>(std::lround(span / o_.cell)) + 1);
        arcs.clear();
        points.clear();
        for (int k = 0; k < m; ++k) arcs.push_back(from + span * k / (closedRun ? m : m - 1));
        for (double t : arcs) points.push_back(pointAtArc(walker_, C.curve, C.curveArc, C.closed, C.curveLength, t));
      };
      const double span = closedRun ? C.curveLength : C.sampleArc.back() - C.sampleArc.front();
      spread(C.sampleArc.front(), span);
      const int m = static_cast<int>(points.size());
      // A loop fitted around an umbilic can fold back on itself (points of it nearly coincide): the front
      // stops there instead of laying a fan onto doubled vertices, and the cap is left to the gap filling.
      bool folded = false;
      for (int k = 0; closedRun && m <= kShrunkLoop && k < m; ++k)
        for (int j = k + 1; j < m; ++j) folded = folded || (points[k].point() - points[j].point()).norm() < 0.25 * span / m;
      if (folded) continue;
      // The fitted curve may also run off where the apexes are not (a loop traced around another region; zipped
      // to it, the base would fan across the gap): then the row is resampled along the apexes' own polyline.
      bool faithful = true;
      const double reach = kResampleReach * std::max(o_.cell, spacing);
      for (const SurfacePoint& p : points) {
        double nearest = std::numeric_limits<double>::infinity();
        for (const Apex& a : run) nearest = std::min(nearest, (a.p.point() - p.point()).squaredNorm());
        faithful = faithful && nearest <= reach * reach;
      }
      if (!faithful && length >= 2) {
        C.curve.clear();
        for (const Apex& a : run) C.curve.push_back(a.p);
        C.curveArc = cumulativeArc(C.curve);
        C.curveLength = C.curveArc.back() + (closedRun ? (C.curve.back().point() - C.curve.front().point()).norm() : 0.0);
        C.closed = closedRun;
        spread(0.0, closedRun ? C.curveLength : C.curveArc.back());
        faithful = true;
      }
      if (faithful) {
        for (const SurfacePoint& p : points) C.ids.push_back(addVertex(p, ratio, height));
        C.sampleArc = arcs;
        zip(below, closedRun, C.ids, closedRun);
        resampled = true;
        if (!resampled_++) {
          std::ostringstream where;
          where << describe(walker_, vertices_[C.ids[C.ids.size() / 2]]) << " (spacing " << spacing / o_.cell
                << " cell, " << length << " -> " << points.size() << " vertices)";
          firstResample_ = where.str();
        }
      }
    }
    if (!resampled) {
      for (int k = 0; k < length; ++k) C.ids.push_back(addVertex(run[k].p, run[k].ratio, heights[k]));
      for (int k = 0; k < length; ++k) {
        const int i = (first + k) % n;
        addTriangle(A.ids[i], A.ids[(i + 1) % count], C.ids[k]);
        if (k + 1 < length || closedRun)
          addTriangle(A.ids[(i + 1) % count], C.ids[(k + 1) % length], C.ids[k]);
      }
      if (!closedRun) C.belowStart = A.ids[first], C.belowEnd = A.ids[(first + length) % count];
    }
    if (o_.method == LayingMethod::Progressive) setOwnCurve(C);
    if (o_.method == LayingMethod::Prespecified && layers_ <= 4 * static_cast<int>(fronts_.size())) {
      std::vector<Vec3> line;
      for (const SurfacePoint& p : C.curve) line.push_back(p.point());
      fieldLines_.push_back(line);
    }
    produced.push_back(std::move(front));
  }
  parabolicStops_ += alongParabolic;
  if (produced.empty()) {
    fronts_[f].active = false;
    if (!alongParabolic) ++boundaryStops_;
    return;
  }
  for (Front& p : produced) p.layers = fronts_[f].layers + 1;
  splits_ += static_cast<int>(produced.size()) - 1;
  fronts_[f] = std::move(produced.front());
  for (std::size_t k = 1; k < produced.size(); ++k) fronts_.push_back(std::move(produced[k]));
}

void Laying::addTriangle(int a, int b, int c) {
  if (systems_ > 1) {
    const std::int64_t e[3] = {edgeKey(a, b), edgeKey(b, c), edgeKey(c, a)};
    if (directedEdges_.count(e[0]) || directedEdges_.count(e[1]) || directedEdges_.count(e[2])) return;
    directedEdges_.insert(e, e + 3);
  }
  triangles_.emplace_back(a, b, c);
}

// Lays one system of rows: L0's two fronts and the fronts they split into, until none is active.
void Laying::laySystem(const Row& L0) {
  systemFront0_ = fronts_.size();
  if (++systems_ == 2) {
    for (const Eigen::Vector3i& t : triangles_)
      for (int k = 0; k < 3; ++k) directedEdges_.insert(edgeKey(t(k), t((k + 1) % 3)));
  }
  fronts_.push_back(Front{L0, true, kEquilateralRatio * o_.cell});
  fronts_.push_back(Front{reversed(L0), true, kEquilateralRatio * o_.cell});
  const double area = std::max(walker_.surface().bounds().diagonal().squaredNorm(), o_.cell * o_.cell);
  while (layers_ < o_.maxLayers) {
    bool any = false;
    for (std::size_t f = systemFront0_; f < fronts_.size() && layers_ < o_.maxLayers; ++f) {
      if (!fronts_[f].active) continue;
      checkCancel(cancel_);
      any = true;
      double stepScale = 1;
      if (!zipIfMeeting(f, stepScale)) layLayer(f, stepScale);
    }
    if (!any) break;
    if (progress_) {
      const double expected = area / (kEquilateralRatio * o_.cell * o_.cell);
      progress_({"triangulate", std::min(0.95, vertices_.size() / expected),
                 "layer " + std::to_string(layers_) + ", " + std::to_string(vertices_.size()) + " vertices"});
    }
  }
}

// Where a surface has no singularity-free conjugate network (round bumps: the rows around each top are closed
// rings, and no one family of rows reaches the next bump), the system laid from L0 covers one region and
// stops. The middle of the largest region it left uncovered — the sample of the surface farthest from every
// laid vertex (and from the seeds tried before), when that is at least kSeedHole cells away — seeds the next
// system, whose rows stop where they meet the laid ones (the collision test); nullopt when there is none.
std::optional<Vec3> Laying::uncoveredSeed(const std::vector<LocalGeometry>& samples, std::vector<Vec3>& tried) const {
  std::vector<Vec3> covered;
  std::vector<const LocalGeometry*> open;
  for (const LocalGeometry& g : samples) {
    bool near = false;
    grid_.forNear(g.point, o_.cell, [&](int id) { near = near || (vertices_[id].point() - g.point).norm() < o_.cell; });
    if (near) covered.push_back(g.point);
    else open.push_back(&g);
  }
  // A system that stopped within a cell of where it started (L0 a tiny loop around an umbilic: a hill's top
  // with its conjugate rows laid from there) may come near no sample: its vertices mark what it covers.
  if (covered.empty())
    for (const SurfacePoint& v : vertices_) covered.push_back(v.point());
  const double share = tried.empty() ? kSeedFirstShare : kSeedShare;
  if (covered.empty() || open.size() < share * samples.size()) return std::nullopt;
  for (const Vec3& t : tried) covered.push_back(t);
  const LocalGeometry *farthest = nullptr, *umbilic = nullptr;
  double widest = kSeedHole * o_.cell, umbilicRoom = 0, roundest = kSeedUmbilic;
  for (const LocalGeometry* g : open) {
    double room = std::numeric_limits<double>::infinity();
    for (const Vec3& q : covered) room = std::min(room, (g->point - q).norm());
    if (room < kSeedHole * o_.cell) continue;
    if (room > widest) widest = room, farthest = g;
    const double a = std::abs(g->k1), b = std::abs(g->k2);
    if (std::min(a, b) > 0.05 * std::max(a, b) && std::abs(g->k1 - g->k2) / (a + b) < roundest)
      roundest = std::abs(g->k1 - g->k2) / (a + b), umbilic = g, umbilicRoom = room;
  }
  // Around an umbilic the rows of a principal family close into rings: L0 is one of them, half-way from the
  // umbilic to the laid rows, and its two fronts lay inwards to the top and outwards to meet them.
  std::optional<Vec3> seed;
  if (umbilic) seed = umbilic->point + 0.5 * umbilicRoom * umbilic->d1;
  else if (farthest) seed = farthest->point;
  if (seed) tried.push_back(umbilic ? umbilic->point : *seed);
  return seed;
}

// L0 of a later system: the flow line through `start` as baseCurve samples it, cut where it comes within a cell
// of laid vertices (the run of free samples nearest the start is kept, unrolled if the loop was cut), or
// nullopt when fewer than three samples are free.
std::optional<Row> Laying::seedCurve(const SurfacePoint& start, const Vec3& initial) {
  Row row;
  std::vector<double> arcs;
  traceBase(start, initial, row, arcs);
  const int n = static_cast<int>(arcs.size());
  if (n < 3) return std::nullopt;
  std::vector<SurfacePoint> points;
  std::vector<char> free(n);
  int nearest = 0;
  for (int i = 0; i < n; ++i) {
    points.push_back(pointAtArc(walker_, row.curve, row.curveArc, row.closed, row.curveLength, arcs[i]));
    free[i] = !collides(points.back().point(), kSeedClearance * o_.cell);
    if ((points[i].point() - start.point()).squaredNorm() < (points[nearest].point() - start.point()).squaredNorm()) nearest = i;
  }
  if (!free[nearest]) return std::nullopt;
  std::vector<int> keep;
  if (row.closed && std::all_of(free.begin(), free.end(), [](char c) { return c != 0; })) {
    for (int i = 0; i < n; ++i) keep.push_back(i);
  } else {
    int first = nearest, last = nearest;
    auto wrap = [&](int i) { return row.closed ? ((i % n) + n) % n : i; };
    while (last - first + 1 < n && (row.closed || first > 0) && free[wrap(first - 1)]) --first;
    while (last - first + 1 < n && (row.closed || last + 1 < n) && free[wrap(last + 1)]) ++last;
    for (int i = first; i <= last; ++i) keep.push_back(i);
    if (row.closed) {
      // Unrolled, with arcs increasing from the first kept sample (as layLayer unrolls a cut loop).
      std::vector<double> unrolled;
      for (int i : keep) unrolled.push_back(arcs[wrap(i)] + (i < 0 ? -row.curveLength : i >= n ? row.curveLength : 0.0));
      if (unrolled.front() < 0)
        for (double& a : unrolled) a += row.curveLength;
      for (int& i : keep) i = wrap(i);
      row.closed = false;
      row.curveLength = 0;
      arcs.assign(unrolled.begin(), unrolled.end());
    } else {
      arcs.assign(arcs.begin() + first, arcs.begin() + last + 1);
    }
  }
  if (keep.size() < 3) return std::nullopt;
  for (int i : keep) row.ids.push_back(addVertex(points[i], std::numeric_limits<double>::quiet_NaN()));
  row.sampleArc = arcs;
  std::vector<Vec3> line;
  for (int i : keep) line.push_back(points[i].point());
  fieldLines_.push_back(line);
  if (o_.method == LayingMethod::Progressive) setOwnCurve(row);
  return row;
}

// Closes the gaps left where systems of rows (and split fronts) met. Each boundary edge a -> b (laid triangles
// on its left) looks for the boundary vertex q on its right making the roundest triangle with edges up to
// kFillEdge cells and angles of at least 30 degrees (valid at more corners first); the best such triangles are
// added first, if their new edges cross no edge and enclose no vertex (in the tangent plane), they lie on the
// surface (their centroid not beyond its boundary) and no directed edge is used twice; then the boundary is
// searched again. Where no laid vertex will do, a new vertex goes to the edge's ideal apex; holes left inside
// the surface close with blunter triangles. A vertex left pinched between two gaps (two fans meeting at it)
// loses its gap triangles, and the seams' edges are flipped where that makes more stars valid. Returns how
// many triangles it added.
int Laying::fillGaps() {
  int nv = static_cast<int>(vertices_.size());
  const double reach = kFillEdgeWide * o_.cell;  // the farthest any tier looks
  std::unordered_set<std::int64_t> open;  // the directed edges without their reverse
  std::vector<std::vector<int>> incident(nv);
  std::vector<char> used(nv, 0);
  // Passes are stamped, and an edge that found no triangle in a pass is looked at again only once a vertex near
  // it has changed since: got a triangle, or was put in the grid, in a later pass. A failed edge watches the grid
  // cells around it (`watchers`, by cell key, occupied or not), and a change in one of them in a later pass
  // takes it off the failed list. Looking at the cells around every failed edge in every pass instead cost half
  // of a lay at 100k faces on the uploaded bumps: the gaps between systems close like zips, a few triangles per
  // pass over some 150 passes, while thousands of boundary edges wait.
  int stamp = 0;
  struct Watch {
    std::int64_t edge;
    int kind, stamp;
  };
  std::unordered_map<std::int64_t, std::vector<Watch>> watchers;  // by cell key
  std::unordered_map<std::int64_t, int> failed[3];  // per kind of pass: edge -> the pass it found nothing in
  std::vector<std::int64_t> keyOfVertex(nv, 0);
  std::vector<char> inGrid(nv, 0);
  auto changed = [&](std::int64_t key) {  // a vertex of cell `key` changed in the current pass
    const auto it = watchers.find(key);
    if (it == watchers.end()) return;
    std::vector<Watch>& list = it->second;
    std::size_t kept = 0;
    for (const Watch& w : list) {
      // A change in the very pass the edge failed in does not count, as it never did (in `connect` such a
      // change comes after the edge was looked at, so it may hide a triangle; counting it changes the meshes).
      if (w.stamp == stamp) {
        list[kept++] = w;
        continue;
      }
      const auto f = failed[w.kind].find(w.edge);
      if (f != failed[w.kind].end() && f->second == w.stamp) failed[w.kind].erase(f);  // else failed since, or free
    }
    list.resize(kept);
  };
  auto touch = [&](int v) {
    if (inGrid[v]) changed(keyOfVertex[v]);
  };
  std::vector<double> longestEdge(nv, 0.0);  // each vertex's longest (clear skips vertices farther than it)
  auto addEdges = [&](int t) {
    const Eigen::Vector3i& tri = triangles_[t];
    for (int c = 0; c < 3; ++c) {
      const int x = tri(c), y = tri((c + 1) % 3);
      const double length = (vertices_[x].point() - vertices_[y].point()).norm();
      longestEdge[x] = std::max(longestEdge[x], length);
      longestEdge[y] = std::max(longestEdge[y], length);
      if (!open.erase(edgeKey(y, x))) open.insert(edgeKey(x, y));
      incident[tri(c)].push_back(t);
      used[tri(c)] = 1;
      touch(tri(c));
    }
  };
  for (int t = 0; t < static_cast<int>(triangles_.size()); ++t) addEdges(t);
  auto triangleWith = [&](int a, int b) {  // the triangle with the directed edge a -> b, or -1
    for (int t : incident[a])
      for (int k = 0; k < 3; ++k)
        if (triangles_[t](k) == a && triangles_[t]((k + 1) % 3) == b) return t;
    return -1;
  };
  auto has = [&](int a, int b) { return triangleWith(a, b) >= 0; };
  auto boundary = [&](int a, int b) { return has(a, b) && !has(b, a); };
  PointGrid grid(reach);
  auto gridInsert = [&](int v) {
    grid.insert(v, vertices_[v].point());
    keyOfVertex[v] = grid.keyAt(vertices_[v].point());
    inGrid[v] = 1;
    changed(keyOfVertex[v]);
  };
  for (int v = 0; v < nv; ++v)
    if (used[v]) gridInsert(v);
  auto at = [&](int v) -> const Vec3& { return vertices_[v].point(); };

  struct Candidate {
    double sine;  // the smallest angle's sine, plus one per corner whose star the triangle keeps valid
    int a, b, q;
  };
  // How many corners of the triangle (b, a, q) would find it valid as the fundamental triangle of their star
  // (Props 4, 5), or cannot judge it (K = 0): the seams' triangles follow no conjugate directions, so among
  // shapes alike the ones valid at more corners go first.
  auto validCorners = [&](int a, int b, int q) {
    const std::array<int, 3> c = {b, a, q};
    int valid = 0;
    for (int k = 0; k < 3; ++k) {
      const LocalGeometry& g = vertices_[c[k]].g;
      const StarValidity v =
          starValidity(g, {Vec2(0, 0), toTangentPlane(g, at(c[(k + 1) % 3])), toTangentPlane(g, at(c[(k + 2) % 3]))});
      valid += !v.judged || v.valid;
    }
    return valid;
  };
  // The triangle (b, a, q) on the right of the boundary edge a -> b, if it may be added now with angles whose
  // sine is at least minSine and edges up to maxEdge.
  double minSine = kFillSine, maxEdge = kFillEdge * o_.cell;
  auto shaped = [&](int a, int b, int q, double& sine) {
    if (q == a || q == b) return false;
    const Vec3 &A = at(a), &B = at(b), &Q = at(q);
    // The edge lengths first: most of the vertices a search visits are too far.
    const double ab = (B - A).norm(), aq = (Q - A).norm(), bq = (Q - B).norm();
    if (std::max({ab, aq, bq}) > maxEdge) return false;
    if (has(a, q) || has(q, b)) return false;
    const Vec3 n = (vertices_[a].g.normal + vertices_[b].g.normal + vertices_[q].g.normal).normalized();
    if ((A - B).cross(Q - B).dot(n) <= 0) return false;  // not on the right of a -> b, seen from the normal
    const double twiceArea = (A - B).cross(Q - B).norm();
    sine = std::min({twiceArea / (ab * aq), twiceArea / (ab * bq), twiceArea / (aq * bq)});
    return sine >= minSine;
  };
  // ... and whether it would cross no edge and cover no vertex, on the surface.
  auto clear = [&](int a, int b, int q) {
    const Vec3 n = (vertices_[a].g.normal + vertices_[b].g.normal + vertices_[q].g.normal).normalized();
    const Vec3 &A = at(a), &B = at(b), &Q = at(q);
    // In the plane through the centroid across n: no edge crossed, no vertex inside.
    const Vec3 c = (A + B + Q) / 3;
    const Vec3 e1 = (B - A - (B - A).dot(n) * n).normalized(), e2 = n.cross(e1);
    auto flat = [&](const Vec3& x) { return Vec2((x - c).dot(e1), (x - c).dot(e2)); };
    const Vec2 a2 = flat(A), b2 = flat(B), q2 = flat(Q);
    const Vec2 lo = a2.cwiseMin(b2).cwiseMin(q2), hi = a2.cwiseMax(b2).cwiseMax(q2);
    bool clear = true;
    int near = 0;
    grid.forNear(c, reach, [&](int x) {
      if (!clear) return;
      // Layers piled onto each other there (kPiledVertices): no triangle is added to the pile.
      if (++near > kPiledVertices) {
        clear = false;
        return;
      }
      const Vec3& X = at(x);
      if (std::abs((X - c).dot(n)) > reach) return;
      const Vec2 x2 = flat(X);
      // Farther from the triangle's box than its longest edge (flattening shortens edges): x is not inside,
      // and none of its edges reaches the triangle.
      const Vec2 gap = (lo - x2).cwiseMax(x2 - hi).cwiseMax(0.0);
      if (gap.norm() > longestEdge[x] * (1 + 1e-9) + 1e-12 * reach) return;
      if (x != a && x != b && x != q && cross2(b2 - a2, x2 - a2) <= 0 && cross2(q2 - b2, x2 - b2) <= 0 &&
          cross2(a2 - q2, x2 - q2) <= 0)
        clear = false;
      // Every edge once: from its start, or from its end when it has no twin (its start may be out of reach).
      for (int t : incident[x]) {
        for (int k = 0; k < 3 && clear; ++k) {
          const int u = triangles_[t](k), w = triangles_[t]((k + 1) % 3);
          if (u != x && (w != x || has(w, u))) continue;
          const Vec2 u2 = u == x ? x2 : flat(at(u)), w2 = w == x ? x2 : flat(at(w));
          if (std::max(u2.x(), w2.x()) < lo.x() || std::min(u2.x(), w2.x()) > hi.x() ||
              std::max(u2.y(), w2.y()) < lo.y() || std::min(u2.y(), w2.y()) > hi.y())
            continue;
          if (u != a && u != q && w != a && w != q && segmentsCross(a2, q2, u2, w2)) clear = false;
          if (u != b && u != q && w != b && w != q && segmentsCross(b2, q2, u2, w2)) clear = false;
        }
      }
    });
    if (!clear) return false;
    const SurfacePoint foot = walker_.project(c, vertices_[a]);
    return !walker_.isOutside(c, foot) && (foot.point() - c).norm() < 0.5 * reach;
  };
  auto admissible = [&](int a, int b, int q, double& sine) { return shaped(a, b, q, sine) && clear(a, b, q); };

  // Whether the right of a -> b lies beyond the surface boundary (the edge runs along it).
  auto alongBoundary = [&](int a, int b) {
    const Vec3 n = (vertices_[a].g.normal + vertices_[b].g.normal).normalized();
    const Vec3 x = 0.5 * (at(a) + at(b)) + 0.5 * o_.cell * (at(b) - at(a)).cross(n).normalized();
    return walker_.isOutside(x, walker_.project(x, vertices_[a]));
  };
  // The boundary edges, in a fixed order (the hash set's differs between standard libraries).
  auto openEdges = [&]() {
    std::vector<std::int64_t> list(open.begin(), open.end());
    std::sort(list.begin(), list.end());
    return list;
  };
  auto worthLooking = [&](int kind, int a, int b) { return failed[kind].find(edgeKey(a, b)) == failed[kind].end(); };
  auto fail = [&](int kind, std::int64_t e) {
    failed[kind][e] = stamp;
    const int a = static_cast<int>(e >> 32), b = static_cast<int>(e & 0xFFFFFFFF);
    grid.forNearKeys(0.5 * (at(a) + at(b)), reach, [&](std::int64_t key) { watchers[key].push_back({e, kind, stamp}); });
  };
  std::unordered_map<std::int64_t, bool> outside;  // alongBoundary, once per edge
  // One pass of triangles on laid vertices: the best candidate of every boundary edge, best first.
  auto connect = [&](bool interiorOnly) {
    const int kind = interiorOnly ? 1 : 0;
    ++stamp;
    std::vector<Candidate> candidates;
    for (const std::int64_t e : openEdges()) {
        const int a = static_cast<int>(e >> 32), b = static_cast<int>(e & 0xFFFFFFFF);
        if (interiorOnly) {
          const auto it = outside.find(e);
          if (it == outside.end() ? (outside[e] = alongBoundary(a, b)) : it->second) continue;
        }
        if (!worthLooking(kind, a, b)) continue;
        std::vector<Candidate> shapes;
        int near = 0;
        grid.forNear(0.5 * (at(a) + at(b)), maxEdge, [&](int q) {
          double sine = 0;
          if (++near <= kPiledVertices && shaped(a, b, q, sine)) shapes.push_back({sine + validCorners(a, b, q), a, b, q});
        });
        if (near > kPiledVertices) shapes.clear();  // piled layers (see clear)
        std::sort(shapes.begin(), shapes.end(),
                  [](const Candidate& x, const Candidate& y) { return x.sine != y.sine ? x.sine > y.sine : x.q < y.q; });
        Candidate best{0, a, b, -1};
        for (const Candidate& k : shapes)
          if (clear(a, b, k.q)) {
            best = k;
            break;
          }
        if (best.q >= 0) candidates.push_back(best);
        else fail(kind, e);
      }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
      return x.sine != y.sine ? x.sine > y.sine : std::tie(x.a, x.b) < std::tie(y.a, y.b);
    });
    int added = 0;
    for (const Candidate& k : candidates) {
      double sine = 0;
      if (!boundary(k.a, k.b) || !admissible(k.a, k.b, k.q, sine)) continue;
      triangles_.emplace_back(k.b, k.a, k.q);
      addEdges(static_cast<int>(triangles_.size()) - 1);
      ++added;
    }
    return added;
  };
  // One pass of new vertices: where no laid vertex will do (a gap wider than kFillEdge cells), a vertex at the
  // apex of a boundary edge, on the surface and at least kFillClearance cells from every vertex.
  auto insert = [&]() {
    int inserted = 0;
    ++stamp;
    for (const std::int64_t e : openEdges()) {
        const int a = static_cast<int>(e >> 32), b = static_cast<int>(e & 0xFFFFFFFF);
        if (!boundary(a, b) || !worthLooking(2, a, b)) continue;
        fail(2, e);  // whatever happens: a success closes the edge
        // The apex of the ideal triangle on a -> b (§5.1), on its right, with the §5.3 lower bound on the step;
        // equilateral where there is none (K = 0, a base along an asymptotic direction, an exploding step).
        const Vec3 n = (vertices_[a].g.normal + vertices_[b].g.normal).normalized();
        const Vec3 along = at(b) - at(a), right = along.cross(n).normalized();
        const double side = std::clamp(along.norm(), 0.8 * o_.cell, 1.2 * o_.cell);
        Vec3 x = 0.5 * (at(a) + at(b)) + kEquilateralRatio * side * right;
        const SurfacePoint m = walker_.project(0.5 * (at(a) + at(b)), vertices_[a]);
        const Vec2 a2 = toTangentPlane(m.g, at(a)), b2 = toTangentPlane(m.g, at(b));
        const IdealApex ideal = idealApex(m.g, a2, b2, Side::Right);
        if (ideal.ok() && ideal.step <= o_.maxStepRatio * (b2 - a2).norm()) {
          const double ratio = stepLowerBound(ideal.step / (b2 - a2).norm(), o_.lowerBound);
          x = fromTangentPlane(m.g, 0.5 * (a2 + b2) + ratio * side * ideal.direction);
        }
        const SurfacePoint p = walker_.project(x, vertices_[a]);
        if (walker_.isOutside(x, p) || (p.point() - x).norm() > 0.5 * o_.cell) continue;
        bool crowded = false;  // by vertices of triangles (a laid vertex in none does not count)
        grid.forNear(p.point(), kFillClearance * o_.cell, [&](int v) {
          crowded = crowded || (used[v] && (vertices_[v].point() - p.point()).norm() < kFillClearance * o_.cell);
        });
        if (crowded) continue;
        const int q = static_cast<int>(vertices_.size());
        vertices_.push_back(p);
        incident.emplace_back();
        used.push_back(0);
        longestEdge.push_back(0);
        keyOfVertex.push_back(0);
        inGrid.push_back(0);
        double sine = 0;
        const bool fits = admissible(a, b, q, sine);
        vertices_.pop_back();  // addVertex puts it back with the rest of the laying's bookkeeping
        if (!fits) {
          incident.pop_back();
          used.pop_back();
          longestEdge.pop_back();
          keyOfVertex.pop_back();
          inGrid.pop_back();
          continue;
        }
        addVertex(p, std::numeric_limits<double>::quiet_NaN());
        gridInsert(q);
        triangles_.emplace_back(b, a, q);
        addEdges(static_cast<int>(triangles_.size()) - 1);
        ++inserted;
      }
    return inserted;
  };

  const int laid = static_cast<int>(triangles_.size());
  for (int sweep = 0; sweep < 256; ++sweep) {
    checkCancel(cancel_);
    minSine = kFillSine, maxEdge = kFillEdge * o_.cell;
    if (connect(false) > 0 || insert() > 0) continue;
    // What is left inside the surface (holes, notches) closes with blunter triangles. Slivers would close the
    // last slits and three- or four-sided holes too, but their stars are invalid and their Dupin hexagons fold
    // (bumps at 5000 faces: 92 invalid stars left instead of 53, 60 folded faces instead of 55).
    minSine = kFillSineBlunt, maxEdge = kFillEdgeWide * o_.cell;
    if (connect(true) == 0) break;
  }
  // Pinched vertices: more boundary edges leave them than one fan has.
  nv = static_cast<int>(vertices_.size());
  for (int round = 0; round < 8; ++round) {
    std::vector<int> out(nv, 0);
    for (int t = 0; t < static_cast<int>(triangles_.size()); ++t)
      for (int k = 0; k < 3; ++k)
        if (!has(triangles_[t]((k + 1) % 3), triangles_[t](k))) ++out[triangles_[t](k)];
    std::vector<Eigen::Vector3i> kept(triangles_.begin(), triangles_.begin() + laid);
    bool dropped = false;
    for (int t = laid; t < static_cast<int>(triangles_.size()); ++t) {
      const Eigen::Vector3i& tri = triangles_[t];
      if (out[tri(0)] > 1 || out[tri(1)] > 1 || out[tri(2)] > 1) dropped = true;
      else kept.push_back(tri);
    }
    if (!dropped) break;
    triangles_ = std::move(kept);
    open.clear();
    for (auto& list : incident) list.clear();
    for (int t = 0; t < static_cast<int>(triangles_.size()); ++t) addEdges(t);
  }
  // Flips of the seams' edges (an edge of a triangle added here) that leave fewer triangles failing Prop. 4 / 5
  // in the stars of the four corners concerned: the seams' triangles are not laid along conjugate directions,
  // and which diagonal a quad of them takes decides whether its corners' stars are valid.
  auto failing = [&](int v) {
    if (!used[v]) return 0;
    const LocalGeometry& g = vertices_[v].g;
    int bad = 0;
    for (int t : incident[v]) {
      const Eigen::Vector3i& tri = triangles_[t];
      int k = 0;
      while (tri(k) != v) ++k;
      bad += !starIsValid(g, {Vec2(0, 0), toTangentPlane(g, at(tri((k + 1) % 3))), toTangentPlane(g, at(tri((k + 2) % 3)))});
    }
    return bad;
  };
  auto upright = [&](int x, int y, int z) {
    const Vec3 n = vertices_[x].g.normal + vertices_[y].g.normal + vertices_[z].g.normal;
    const Vec3 e = at(y) - at(x), f = at(z) - at(x);
    const double area2 = e.cross(f).dot(n) / n.norm();
    const double longest = std::max({e.squaredNorm(), f.squaredNorm(), (at(z) - at(y)).squaredNorm()});
    return area2 > 0.3 * longest;  // no sliver: its height at least 0.3 of its longest edge
  };
  auto detach = [&](int t) {
    for (int k = 0; k < 3; ++k) {
      std::vector<int>& list = incident[triangles_[t](k)];
      list.erase(std::find(list.begin(), list.end(), t));
    }
  };
  auto attach = [&](int t) {
    for (int k = 0; k < 3; ++k) {
      incident[triangles_[t](k)].push_back(t);
    }
  };
  for (int sweep = 0; sweep < 8; ++sweep) {
    int flipped = 0;
    for (int t1 = laid; t1 < static_cast<int>(triangles_.size()); ++t1)
      for (int k = 0; k < 3; ++k) {
        const int x = triangles_[t1](k), y = triangles_[t1]((k + 1) % 3), p = triangles_[t1]((k + 2) % 3);
        const int t2 = triangleWith(y, x);
        if (t2 < 0) continue;
        int j = 0;
        while (triangles_[t2](j) != y) ++j;
        const int q = triangles_[t2]((j + 2) % 3);
        if (q == p || has(p, q) || has(q, p) || !upright(x, q, p) || !upright(q, y, p)) continue;
        const int before = failing(x) + failing(y) + failing(p) + failing(q);
        if (before == 0) continue;
        const Eigen::Vector3i old1 = triangles_[t1], old2 = triangles_[t2];
        detach(t1);
        detach(t2);
        triangles_[t1] = Eigen::Vector3i(x, q, p);
        triangles_[t2] = Eigen::Vector3i(q, y, p);
        attach(t1);
        attach(t2);
        if (failing(x) + failing(y) + failing(p) + failing(q) < before) {
          ++flipped;
          break;  // t1 changed: on to the next triangle
        }
        detach(t1);
        detach(t2);
        triangles_[t1] = old1;
        triangles_[t2] = old2;
        attach(t1);
        attach(t2);
      }
    if (flipped == 0) break;
  }
  return static_cast<int>(triangles_.size()) - laid;
}

Triangulation Laying::run(const SurfacePoint& start, const Vec3& initial) {
  Row L0 = baseCurve(start, initial);
  laySystem(L0);
  std::vector<Vec3> tried;
  std::vector<std::string> seeds;
  std::vector<LocalGeometry> samples;  // of the surface, taken once for all the seeds
  for (int attempt = 0; attempt < kMaxSeeds && layers_ < o_.maxLayers; ++attempt) {
    if (samples.empty()) samples = walker_.surface().samples(kSeedSamples);
    const std::optional<Vec3> seed = uncoveredSeed(samples, tried);
    if (!seed) break;
    const SurfacePoint p = walker_.project(*seed);
    std::optional<Vec3> d = field_.direction(p, F_);
    if (!d) continue;  // a singularity of the field: the next seed lies elsewhere
    const std::optional<Row> L = seedCurve(p, *d);
    if (!L) continue;
    laySystem(*L);
    seeds.push_back(describe(walker_, p));
  }
  if (systems_ > 1) gapTriangles_ = fillGaps();
  if (triangles_.empty())
    cannotTile(start, "no layer of triangles could be laid from the base curve (every apex fell outside the "
                      "surface); choose a smaller cell or another start");

  // Vertices in no triangle (row extensions whose apexes fell outside) are left out.
  Triangulation t;
  std::vector<int> index(vertices_.size(), -1);
  for (const Eigen::Vector3i& tri : triangles_)
    for (int c = 0; c < 3; ++c) index[tri(c)] = 0;
  int nv = 0;
  for (int& i : index)
    if (i == 0) i = nv++;
  t.mesh.V.resize(nv, 3);
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    if (index[v] < 0) continue;
    t.mesh.V.row(index[v]) = vertices_[v].point().transpose();
    if (walker_.parametric()) t.uv.push_back(vertices_[v].uv);
  }
  t.mesh.F.resize(static_cast<int>(triangles_.size()), 3);
  for (int k = 0; k < static_cast<int>(triangles_.size()); ++k)
    for (int c = 0; c < 3; ++c) t.mesh.F(k, c) = index[triangles_[k](c)];
  t.fieldLines = std::move(fieldLines_);
  t.systems = systems_;

  std::ostringstream s;
  s << layingMethodName(o_.method) << " conjugation, field " << fieldSpecName(field_.spec()) << ", base curves along "
    << (F_ == Family::First ? "the field" : "its conjugate") << ": L0 " << (L0.closed ? "closed, " : "open, ")
    << L0.ids.size() << " samples through " << describe(walker_, start) << "; " << layers_ << " layers";
  t.notes.push_back(s.str());
  auto note = [&](bool when, const std::string& text) {
    if (when) t.notes.push_back(text);
  };
  note(boundedLayers_ > 0, "§5.3 lower bound b = " + std::to_string(o_.lowerBound) + " active on " +
                               std::to_string(boundedLayers_) + " layers (" + std::to_string(boundedSegments_) +
                               " triangles)");
  note(reusedSegments_ > 0, "§5.3 step re-used from the previous layer across a parabolic curve on " +
                                std::to_string(reusedLayers_) + " layers (" + std::to_string(reusedSegments_) +
                                " triangles), first near " + firstReuse_);
  note(widenedL0_ > 0, "L0 moved " + std::to_string(widenedL0_ * kUmbilicRing) + " cells out from the start, where "
                           "the base family closes into a loop of a few cells (around an umbilic): the rows grow "
                           "from a wider ring, and its inner front lays inwards");
  note(resampled_ > 0, "rows resampled " + std::to_string(resampled_) +
                           " times where their spacing drifted from the cell, first near " + firstResample_);
  note(filledApexes_ > 0, std::to_string(filledApexes_) + " missing apexes filled in between their neighbours");
  note(boundaryStops_ > 0, std::to_string(boundaryStops_) + " fronts stopped at the boundary");
  note(parabolicStops_ > 0, std::to_string(parabolicStops_) + " fronts stopped where they ran along a parabolic "
                            "curve (the ideal step exploding on most of their segments for more than " +
                            std::to_string(kMaxReusedLayers) + " layers), first near " + firstAlongParabolic_);
  note(boundaryEnds_ > 0, std::to_string(boundaryEnds_) + " notches between row ends on the boundary closed");
  note(snappedEnds_ > 0, std::to_string(snappedEnds_) + " row ends moved onto the boundary, which was less than " +
                             std::to_string(kBoundaryMin).substr(0, 3) + " of a spacing beyond them");
  note(splits_ > 0, std::to_string(splits_) + " rows split where apexes fell outside or collided");
  note(collisions_ > 0, std::to_string(collisions_) + " apexes dropped where they would overlap laid triangles");
  note(invalidDrops_ > 0, "Method 2: " + std::to_string(invalidDrops_) +
                              " apexes dropped where the D_F flow line could not be kept above DE (the star would "
                              "be invalid), first near " + firstInvalidDrop_ + "; laying stopped there");
  note(asymptoticStops_ > 0, std::string(o_.method == LayingMethod::Progressive ? "Method 1" : "Method 2") +
                                 " rows turned onto an asymptotic direction (no valid triangle there) on " +
                                 std::to_string(asymptoticStops_) + " segments, first near " + firstAsymptoticStop_ +
                                 (o_.method == LayingMethod::Progressive
                                      ? "; those fronts stopped there (the prespecified method keeps rows on the field)"
                                      : "; no apex there (a row end that left the field), the row split there"));
  note(layers_ >= o_.maxLayers, "stopped at maxLayers = " + std::to_string(o_.maxLayers));
  if (!seeds.empty()) {
    std::string list;
    for (const std::string& p : seeds) list += (list.empty() ? "" : ", ") + p;
    t.notes.push_back(std::to_string(seeds.size()) + " more systems of rows laid from regions the first left uncovered " +
                      "(no one family of rows reaches them), from L0s through " + list +
                      "; seams of irregular vertices where the systems meet (" + std::to_string(gapTriangles_) +
                      " triangles close the gaps between them)");
  }
  for (const std::string& z : zipNotes_) t.notes.push_back(z);
  return t;
}

// §5.3, §3: at a parabolic point the Dupin indicatrix degenerates into two parallel lines along the
// zero-curvature direction, and a planar face there is inscribed in them: a "brick" with two sides along
// that direction (the quad-shaped hexagons of a developable). Bricks stack in courses along it, and the
// courses are the duals of the triangulation's rows, so the rows should follow the zero-curvature direction
// where they meet a parabolic curve. On a torus that direction runs along the parabolic circles (the
// parallels: laid along its meridians a torus has no valid laying, Fig. 19); on a vase or a wave-shaped roof
// it crosses the parabolic curve, and so do the rows, turning hexagons into bricks and bricks into the
// bow-ties of the hyperbolic side. The family whose direction is nearer the zero-curvature one at the
// surface's near-parabolic samples wins when the vote is clear (two thirds, from at least three samples).
// nullopt on surfaces without parabolic points.
// `samples`: the surface's kParabolicSamples samples.
std::optional<Family> familyAlongZeroCurvature(const SurfaceWalker& walker, const DirectionField& field,
                                               const std::vector<LocalGeometry>& samples) {
  int first = 0, conjugate = 0;
  for (const LocalGeometry& g : samples) {
    const double kmax = g.largestCurvature();
    if (!(kmax > 0) || std::abs(g.k1 * g.k2) > kNearParabolic * kmax * kmax) continue;
    const Vec3 zero = std::abs(g.k1) <= std::abs(g.k2) ? g.d1 : g.d2;
    const SurfacePoint p = walker.project(g.point);
    const std::optional<Vec3> dF = field.direction(p, Family::First), dG = field.direction(p, Family::Conjugate);
    if (!dF || !dG) continue;
    (std::abs(dF->dot(zero)) >= std::abs(dG->dot(zero)) ? first : conjugate) += 1;
  }
  if (first + conjugate < 3) return std::nullopt;
  if (3 * first >= 2 * (first + conjugate)) return Family::First;
  if (3 * conjugate >= 2 * (first + conjugate)) return Family::Conjugate;
  return std::nullopt;
}

// Every option in range, else Error(InvalidParameter) naming it.
void checkOptions(const LayingOptions& options) {
  auto invalid = [](const std::string& name, double value, const std::string& range) {
    std::ostringstream msg;
    msg << "laying option " << name << " = " << value << " is out of range (" << range << ")";
    throw Error(ErrorCode::InvalidParameter, msg.str());
  };
  if (!(options.cell > 0) || !std::isfinite(options.cell)) invalid("cell", options.cell, "must be > 0");
  if (!(options.lowerBound >= 0 && options.lowerBound <= 2)) invalid("lowerBound", options.lowerBound, "[0, 2]");
  if (!(options.maxStepRatio >= 1 && options.maxStepRatio <= 100))
    invalid("maxStepRatio", options.maxStepRatio, "[1, 100]");
  if (options.maxLayers < 1) invalid("maxLayers", options.maxLayers, ">= 1");
  if (options.maxVertices < 3) invalid("maxVertices", options.maxVertices, ">= 3");
  if (options.start && !options.start->allFinite()) throw Error(ErrorCode::InvalidParameter, "laying option start is not finite");
  if (options.baseDirection && !(options.baseDirection->allFinite() && options.baseDirection->norm() > 0))
    throw Error(ErrorCode::InvalidParameter, "laying option baseDirection must be a finite non-zero vector");
}

}  // namespace

double stepLowerBound(double r, double b) {
  if (!(b > 0) || r >= 2 * b) return r;
  return b + r * r / (4 * b);
}

BaseFamily parabolicBaseFamily(const Surface& surface, const LayingOptions& options) {
  checkOptions(options);
  const SurfaceWalker walker(surface, options.cell);
  const DirectionField field(walker, parseFieldSpec(options.field));
  const std::optional<Family> family = familyAlongZeroCurvature(walker, field, surface.samples(kParabolicSamples));
  if (!family) return BaseFamily::Auto;
  return *family == Family::First ? BaseFamily::First : BaseFamily::Conjugate;
}

LayingMethod parseLayingMethod(const std::string& name) {
  if (name == "progressive") return LayingMethod::Progressive;
  if (name == "prespecified") return LayingMethod::Prespecified;
  throw Error(ErrorCode::InvalidParameter,
              "unknown laying method '" + name + "' (known: progressive, prespecified)");
}

const char* layingMethodName(LayingMethod method) {
  return method == LayingMethod::Progressive ? "progressive" : "prespecified";
}

Triangulation layTriangulation(const Surface& surface, const LayingOptions& options, const ProgressFn& progress,
                               const CancelFlag* cancel) {
  checkOptions(options);

  const SurfaceWalker walker(surface, options.cell);
  const DirectionField field(walker, parseFieldSpec(options.field));
  SurfacePoint start = walker.project(options.start.value_or(surface.bounds().center()));
  // On a developable whose profile has inflections (a corrugated vault) the middle may fall on an inflection
  // ruling, made of planar points: there the principal directions are arbitrary, and L0 ran across the
  // rulings (a sampled wavy cylinder at 10000 faces: no solve converged). L0 starts on the nearest ruling
  // that is clearly curved instead, where its direction is the ruling's.
  const std::vector<LocalGeometry> samples = surface.samples(kParabolicSamples);
  const bool developable = isDevelopable(surface, &samples);
  std::string startNote;
  if (developable && !samples.empty()) {
    const double curved = planarBelow(samples);
    if (start.g.largestCurvature() < curved) {
      const LocalGeometry* nearest = nullptr;
      for (const LocalGeometry& s : samples)
        if (s.largestCurvature() >= curved &&
            (!nearest || (s.point - start.point()).norm() < (nearest->point - start.point()).norm()))
          nearest = &s;
      if (nearest) {
        startNote = "L0 starts at " + describe(walker, walker.project(nearest->point)) + ", the nearest clearly curved "
                    "point: the start " + describe(walker, start) + " is a planar point of the developable (an "
                    "inflection of its profile), where the ruling direction is undetermined";
        start = walker.project(nearest->point);
      }
    }
  }
  const LocalGeometry& g = start.g;

  // The family of the base curves and its direction at the start.
  Vec3 hint = options.baseDirection.value_or(std::abs(g.normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY());
  hint -= hint.dot(g.normal) * g.normal;
  // By label here (no `previous`): principal lines follow continuity only once traced.
  std::optional<Vec3> dF = field.direction(start, Family::First), dG = field.direction(start, Family::Conjugate);
  if (!dF && !dG) dF = field.direction(start, Family::First, &hint);  // umbilic / planar start: any direction
  for (std::optional<Vec3>* d : {&dF, &dG})
    if (*d && (*d)->dot(hint) < 0) **d = -**d;
  if (!dF && !dG)
    throw Error(ErrorCode::CannotTile, "direction field '" + options.field + "' is singular at the start point " +
                                           describe(walker, start) + "; choose another start point or field");
  auto normalCurvature = [&](const Vec3& d) {
    const Vec2 t = tangentVector(g, d);
    return std::abs(secondFundamentalForm(g, t, t));
  };
  Family family;
  if (!dF || !dG) {
    family = dF ? Family::First : Family::Conjugate;
  } else if (options.baseDirection) {
    family = std::abs(dF->dot(hint)) >= std::abs(dG->dot(hint)) ? Family::First : Family::Conjugate;
  } else if (options.base == BaseFamily::Auto) {
    // A tie (as everywhere on a sphere) goes to the conjugate family whatever the round-off, so that native
    // and wasm builds lay alike.
    // On a developable the rows follow the rulings, the start's zero-curvature direction (below). The
    // vote by label would not do where the profile has inflections: there k1 and k2 swap (the curved
    // direction's curvature changes sign), and so do the labels of the ruling.
    const std::optional<Family> alongZero =
        developable ? std::nullopt : familyAlongZeroCurvature(walker, field, samples);
    family = alongZero ? *alongZero
                            : normalCurvature(*dF) < (1 - 1e-9) * normalCurvature(*dG) ? Family::First
                                                                                       : Family::Conjugate;
  } else {
    family = options.base == BaseFamily::First ? Family::First : Family::Conjugate;
  }
  const Vec3 initial = family == Family::First ? *dF : *dG;

  Laying laying(walker, field, options, family, progress, cancel);
  Triangulation t = laying.run(start, initial);
  if (!startNote.empty()) t.notes.insert(t.notes.begin(), startNote);
  try {
    vertexRings(t.mesh);
  } catch (const Error& e) {
    // Layers laid over each other: the cell is too coarse for how fast the directions turn here.
    throw Error(ErrorCode::CannotTile, "the layers laid with cell " + std::to_string(options.cell) +
                                           " fold onto each other (" + e.what() +
                                           "); the cell is too coarse for this surface: ask for more faces or a "
                                           "smaller cell");
  }
  trimBoundarySlivers(t);
  repairLaidTriangulation(t, surface, options.repairSweeps, cancel);
  if (progress) progress({"triangulate", 1.0, std::to_string(t.mesh.F.rows()) + " triangles laid"});
  return t;
}

bool isDevelopable(const Surface& surface, const std::vector<LocalGeometry>* samples) {
  if (const auto* mesh = dynamic_cast<const MeshSurface*>(&surface)) return mesh->developable();
  const double curvedAbove = MeshSurface::kCurvedScale / surface.bounds().diagonal().norm();
  return samplesDevelopable(samples ? *samples : surface.samples(kParabolicSamples), curvedAbove);
}

void repairLaidTriangulation(Triangulation& triangulation, const Surface& surface, int repairSweeps,
                             const CancelFlag* cancel) {
  if (repairSweeps <= 0) return;
  checkCancel(cancel);
  repairStars(triangulation, surface, repairSweeps);
  openInvalidBoundaryStars(triangulation, surface);
}

}  // namespace phex
