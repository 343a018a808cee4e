// phex — one call from parameters to a P-Hex mesh (phex/pipeline.hpp): the stages, the lays again and the trial
// lays; the global method's rounds against folds are fold_rounds.cpp's.
#include "phex/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "fold_rounds.hpp"
#include "phex/direction_field.hpp"
#include "phex/duality.hpp"
#include "phex/dupin.hpp"
#include "phex/error.hpp"
#include "phex/global_triangulation.hpp"
#include "phex/laying.hpp"
#include "phex/mesh_io.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/metrics.hpp"
#include "phex/parallel.hpp"
#include "phex/planarize.hpp"
#include "phex/subdivision.hpp"

namespace phex {

using detail::FoldFlips;
using detail::SolvedDual;
using detail::flipFoldsAway;
using detail::planarizeOptions;
using detail::smoothRepairs;

namespace {

class StageClock {
 public:
  explicit StageClock(std::vector<StageTiming>& out) : out_(out) {}
  // A stage done again (a second dual tried) adds to its time.
  void done(const std::string& stage) {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    for (StageTiming& t : out_)
      if (t.stage == stage) {
        t.milliseconds += ms;
        return;
      }
    out_.push_back({stage, ms});
  }

 private:
  std::vector<StageTiming>& out_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

Duality parseDuality(const std::string& name) {
  if (name == "dupin") return Duality::Dupin;
  if (name == "tangent") return Duality::Tangent;
  if (name == "auto") return Duality::Auto;
  throw Error(ErrorCode::InvalidParameter, "duality must be 'auto', 'dupin' or 'tangent' (got '" + name + "')");
}

const char* dualityName(Duality d) { return d == Duality::Dupin ? "dupin" : d == Duality::Tangent ? "tangent" : "auto"; }

TriangulationMethod parseTriangulationMethod(const std::string& name) {
  if (name == "auto") return TriangulationMethod::Auto;
  if (name == "lattice") return TriangulationMethod::Lattice;
  if (name == "progressive") return TriangulationMethod::Progressive;
  if (name == "prespecified") return TriangulationMethod::Prespecified;
  if (name == "subdivision") return TriangulationMethod::Subdivision;
  if (name == "global") return TriangulationMethod::Global;
  throw Error(ErrorCode::InvalidParameter,
              "method must be 'auto', 'global', 'progressive', 'prespecified', 'subdivision' or 'lattice' (got '" + name + "')");
}

const char* triangulationMethodName(TriangulationMethod m) {
  switch (m) {
    case TriangulationMethod::Auto: return "auto";
    case TriangulationMethod::Lattice: return "lattice";
    case TriangulationMethod::Progressive: return "progressive";
    case TriangulationMethod::Prespecified: return "prespecified";
    case TriangulationMethod::Subdivision: return "subdivision";
    case TriangulationMethod::Global: return "global";
  }
  return "progressive";
}

const std::vector<std::string>& subdivisionControls() {
  static const std::vector<std::string> names = {"icosahedron", "egg", "flattened-icosahedron"};
  return names;
}

namespace {

TriMesh controlMesh(const std::string& name) {
  if (name == "icosahedron") return icosahedronControl(1.0);
  if (name == "egg") return eggControl(1.3, 0.8);
  if (name == "flattened-icosahedron") return stretchedIcosahedronControl(Vec3(1.2, 1.0, 0.45));
  std::string known;
  for (const std::string& n : subdivisionControls()) known += (known.empty() ? "" : ", ") + n;
  throw Error(ErrorCode::InvalidParameter,
              "subdivision needs a convex control mesh: upload one or name a built-in control (" + known + "), not '" +
                  name + "'");
}

TriMesh uploadedMesh(const MeshInput& in) {
  return readMeshBytes(in.bytes.data(), in.bytes.size(), in.format, in.name.empty() ? "mesh" : in.name);
}

// The last upload's MeshSurface, kept for the next run on the same bytes (see clearUploadCache). The bytes
// are named by two independent 64-bit hashes and their length, with the format and the name.
struct UploadKey {
  std::uint64_t a = 0, b = 0;
  std::size_t size = 0;
  std::string format, name;
  bool operator==(const UploadKey& o) const {
    return a == o.a && b == o.b && size == o.size && format == o.format && name == o.name;
  }
};

UploadKey uploadKey(const MeshInput& in) {
  UploadKey k;
  k.size = in.bytes.size();
  k.format = in.format;
  k.name = in.name;
  // Eight bytes at a time (a 50 MB STL in about 20 ms): an FNV-style lane and a multiply-rotate one.
  std::uint64_t a = 0xcbf29ce484222325ULL ^ k.size, b = 0x9e3779b97f4a7c15ULL + k.size;
  auto mix = [&](std::uint64_t w) {
    a = (a ^ w) * 0x100000001b3ULL;
    a ^= a >> 29;
    b += w * 0xbf58476d1ce4e5b9ULL;
    b = ((b << 31) | (b >> 33)) * 0x94d049bb133111ebULL;
  };
  const std::uint8_t* p = in.bytes.data();
  std::size_t i = 0;
  for (; i + 8 <= k.size; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    mix(w);
  }
  std::uint64_t tail = 0;
  for (std::size_t j = 0; i + j < k.size; ++j) tail |= std::uint64_t(p[i + j]) << (8 * j);
  mix(tail);
  k.a = a;
  k.b = b;
  return k;
}

struct UploadCache {
  std::mutex mutex;
  UploadKey key;
  std::shared_ptr<const MeshSurface> surface;
  Vec3 origin = Vec3::Zero();
  // The upload refined (refinedUpload), and how finely (k x k per triangle).
  std::shared_ptr<const MeshSurface> refined;
  int refinedBy = 0;
};

// An upload far from the origin (site coordinates: a 20 m roof some 5000 km from it) is computed about the
// centre of its box, where its coordinates keep their digits: at 5.4e6 a unit in the last place is 9e-10,
// 3e-8 of an edge of 3 cm, so a planarity of 1e-9 of the edge could not even be written down (such a roof
// stalled at 4e-9, exit 2, and its lay differed from the same roof's at the origin). Far: the centre more
// than kFarFromOrigin diagonals away. The results come back in the file's coordinates (toFileFrame).
constexpr double kFarFromOrigin = 10;

Vec3 localOrigin(const TriMesh& mesh) {
  if (mesh.V.rows() == 0) return Vec3::Zero();
  const Vec3 lo = mesh.V.colwise().minCoeff().transpose(), hi = mesh.V.colwise().maxCoeff().transpose();
  const Vec3 centre = 0.5 * (lo + hi);
  return centre.norm() > kFarFromOrigin * (hi - lo).norm() ? centre : Vec3::Zero();
}

UploadCache& uploadCache() {
  static UploadCache cache;
  return cache;
}

// The MeshSurface of an upload: the cached one when the bytes are the same (`reused`), else built (and kept);
// in the upload's local frame: the file's coordinates less `origin` (localOrigin).
std::shared_ptr<const MeshSurface> uploadedSurface(const MeshInput& in, bool& reused, Vec3& origin) {
  const UploadKey key = uploadKey(in);
  UploadCache& cache = uploadCache();
  {
    const std::lock_guard<std::mutex> lock(cache.mutex);
    if (cache.surface && cache.key == key) {
      reused = true;
      origin = cache.origin;
      return cache.surface;
    }
    cache.surface.reset();  // the previous upload's goes first, so that two are never held at once
    cache.refined.reset();
    cache.refinedBy = 0;
  }
  TriMesh mesh = uploadedMesh(in);
  origin = localOrigin(mesh);
  if (origin != Vec3::Zero()) mesh.V.rowwise() -= origin.transpose();
  auto surface = std::make_shared<const MeshSurface>(std::move(mesh), in.name);
  const std::lock_guard<std::mutex> lock(cache.mutex);
  cache.key = key;
  cache.surface = surface;
  cache.origin = origin;
  reused = false;
  return surface;
}

// A coarse upload (a sketch's mesh, a few hundred triangles) laid finer than its triangles: the lay's points
// sit on flat facets that bend at every edge, while its directions come from curvature fitted smoothly
// across them. Panels across the facets' edges cannot be planar and near the surface at once: a dome
// sampled 24 x 24 (1152 triangles) stalled at 2e-3 at 3000 faces (exit 2), a wave 12 x 12 ended 1.5 % of the
// diagonal off at 1000 faces. Where its triangles are over kCoarseUpload cells in size (TriMesh::triangleSize: by
// the mean edge, 0.2 x 0.02 triangles on a 20 m vault were refined 4 x 4 for nothing, three times the time), the
// lay runs on the upload refined into a smooth surface near its vertices (MeshSurface::refined), k x k per
// triangle for edges of about kRefinedEdge of a cell.
constexpr double kCoarseUpload = 1.5, kRefinedEdge = 0.5;
// An uneven upload (its edges' 90th percentile over kUnevenSpread times their 10th: a marching-tetrahedra mesh, slivers
// among its triangles, whose facets' normals scatter) is refined from kCoarseUneven cells on instead. The generated
// genus 2 at 50k and 100k faces and genus 3 at 100k (triangles of 1.0-1.4 cells, laid on their facets before):
// hexagons 92.75 / 87.89 / 88.40 -> 95.59 / 95.43 / 93.90 %, faces cut 50 / 302 / 222 -> 20 / 109 / 80, in 8.2 /
// 14.3 / 16.1 -> 10.9 / 15.6 / 16.6 s (METHOD.md, Fine uploads). Regular uploads keep kCoarseUpload: at 1.0 the
// bench's upload at 10k faces was refined 3 x 3 for 0.4 s more (1.2 s against the 1 s goal) and 0.2 points of
// hexagons, and the noisy shared models changed both ways (the intersection shell at 1000 and 1500 faces +4.6 and
// +8.9 points, the car at 1000 reaching a P-Hex mesh by cutting 94 faces, 1.5 % of the diagonal off).
// A noisy upload (noisyUpload: a scan, a faceted model) is refined from kCoarseUneven cells on too (stop 31): laid
// finer than its triangles, its facets' kinks fold the dual. The Concerthall at 10000 faces (triangles of 1.2 cells):
// 2703 -> 675 invalid stars, 73.9 -> 77.2 % hexagons, 218 -> 144 nodes of four, 46 -> 16 s; over the six shared
// models at 1000-10000 faces the nodes of four 414 -> 282, the same hexagons (METHOD.md, Coarse uploads). From 0.8
// cells the Concerthall at 5000 faces (0.87) lost 6 points.
constexpr double kCoarseUneven = 1.0, kUnevenSpread = 4.0;
// The finer refinements refinementFor weighs against the global method's field mesh, and how far (a ratio either way)
// the field mesh's edge may come out of the two splits from its own before they are weighed.
constexpr int kRefineChoices = 3;
constexpr double kFieldEdgeRange = 1.25;

// Whether `mesh`'s edges spread over more than kUnevenSpread between their 10th and 90th percentiles.
bool unevenEdges(const TriMesh& mesh) {
  std::vector<double> lengths = mesh.edgeLengths();
  if (lengths.size() < 10) return false;
  const auto at = [&](std::size_t k) {
    std::nth_element(lengths.begin(), lengths.begin() + static_cast<std::ptrdiff_t>(k), lengths.end());
    return lengths[k];
  };
  const double low = at(lengths.size() / 10), high = at(lengths.size() * 9 / 10);
  return high > kUnevenSpread * low;
}

// Whether `mesh` has a crease that a refinement would round off (MeshSurface::Creases::sharp): not on a noisy
// upload, whose sharpest turns are its faceting's (PH-CPF's car, genus-3 model and intersection shell: 77, 174 and 143
// edges turning by over 30 degrees, up to 48-69, scattered over the mesh). Refined, they reach a P-Hex mesh at
// 10000 faces where their facets stalled every lay (METHOD.md).
bool creased(const MeshSurface& mesh) { return mesh.creases().sharp() && !noisyUpload(mesh); }

}  // namespace

namespace detail {

// Whether the repairs that trade hexagons for cuts on a noisy upload apply on `surface` (the solver's fairness, the
// rounds' changes at folded boundary panels, the dislocation glides): on any surface but a noisy upload, and on that
// too where PipelineParams::noisyRepairs asks for them (its second lay, withNoisyRepairs).
bool smoothRepairs(const PipelineParams& params, const Surface& surface) {
  return params.noisyRepairs || !noisyUpload(surface);
}

}  // namespace detail

namespace {

// How finely to refine `mesh`, whose triangles are of `size` (TriMesh::triangleSize), for `cell` (1: not at all).
// Neither a plane (nothing to smooth) nor a mesh with a sharp crease (which the jets would round off: it gets
// its note instead); a low-poly mesh whose facets turn by 30 degrees here and there, about as much as
// elsewhere, is refined. With the blend it is refined by: an uneven upload's slivers would turn over under the
// smooth blend's moved vertices, so it takes the barycentric one (MeshSurface::Blend).
struct Refinement {
  int k = 1;
  MeshSurface::Blend blend = MeshSurface::Blend::Smooth;
};
Refinement refinementFor(const MeshSurface& mesh, double size, double cell) {
  if (mesh.planar() || creased(mesh) || !(cell > 0) || !(size > kCoarseUneven * cell)) return {};
  const bool uneven = unevenEdges(mesh.mesh());  // a pass over every edge: only where a refinement may follow
  if (!(size > kCoarseUpload * cell) && !uneven && !noisyUpload(mesh)) return {};
  const MeshSurface::Blend blend = uneven ? MeshSurface::Blend::Barycentric : MeshSurface::Blend::Smooth;
  const double most = std::floor(std::sqrt(double(MeshSurface::kMaxRefinedTriangles) / double(mesh.mesh().F.rows())));
  const int smooth = static_cast<int>(std::clamp(std::ceil(size / (kRefinedEdge * cell)), 1.0, std::max(1.0, most)));
  // The global method's field mesh splits the refined triangles again, j x j (globalFieldSplit), so its edge is the
  // upload's over k j: where the refined edges fell just past a whole number of field-mesh edges, j took one more
  // and the field mesh came out up to 2.5 times as fine as it needs (the bench's upload at 60k faces: refined 5 x
  // 5, then 2 x 2, 1.0M field-mesh vertices, 17 per lattice point against 7 at 50k and 100k; slower than at 100k).
  // Where the field mesh of `smooth` has edges within kFieldEdgeRange of its own, it stands; else of it and up to
  // kRefineChoices finer refinements, the one whose field mesh's edge comes nearest (by ratio), the first of those.
  const double median = mesh.mesh().medianEdgeLength(), edge = globalFieldEdge(mesh, cell);
  auto away = [&](int k) { return std::abs(std::log(median / (k * globalFieldSplit(median / k, edge)) / edge)); };
  if (away(smooth) <= std::log(kFieldEdgeRange)) return {smooth, blend};
  int best = smooth;
  for (int k = smooth + 1; k <= std::min(static_cast<int>(most), smooth + kRefineChoices); ++k)
    if (away(k) < away(best)) best = k;
  return {best, blend};
}

// The cached upload `coarse` refined as `by` says (kept with it for the next run).
std::shared_ptr<const MeshSurface> refinedUpload(const std::shared_ptr<const MeshSurface>& coarse, Refinement by) {
  const int k = by.k;
  UploadCache& cache = uploadCache();
  {
    const std::lock_guard<std::mutex> lock(cache.mutex);
    if (cache.surface == coarse && cache.refined && cache.refinedBy == k) return cache.refined;  // blend: the upload's
    if (cache.surface == coarse) cache.refined.reset();
  }
  auto made = std::make_shared<MeshSurface>(coarse->refined(k, by.blend), coarse->name());
  made->setRefinement(coarse->mesh(), k);
  std::shared_ptr<const MeshSurface> refined = std::move(made);
  const std::lock_guard<std::mutex> lock(cache.mutex);
  if (cache.surface == coarse) cache.refined = refined, cache.refinedBy = k;
  return refined;
}

// "(x, y, z)" in a note or message, in the local frame, written in the file's coordinates (with the digits
// that the offset takes).
std::string inFileFrame(const std::string& text, const Vec3& origin) {
  if (origin == Vec3::Zero()) return text;
  // A hand scan rather than std::regex, which adds 40 kB (gzipped) to the WebAssembly module.
  std::string out;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t open = text.find('(', at);
    if (open == std::string::npos) break;
    double x[3];
    const char* p = text.c_str() + open + 1;
    bool triple = true;
    for (int k = 0; k < 3 && triple; ++k) {
      char* end = nullptr;
      x[k] = std::strtod(p, &end);
      triple = end != p && (*end == (k < 2 ? ',' : ')'));
      p = end + 1;
      if (triple && k < 2) triple = *p == ' ', ++p;
    }
    if (!triple) {
      out.append(text, at, open + 1 - at);
      at = open + 1;
      continue;
    }
    char buf[128];
    std::snprintf(buf, sizeof buf, "(%.10g, %.10g, %.10g)", x[0] + origin.x(), x[1] + origin.y(), x[2] + origin.z());
    out.append(text, at, open - at);
    out += buf;
    at = static_cast<std::size_t>(p - text.c_str());
  }
  out.append(text, at, std::string::npos);
  return out;
}

void toFileFrame(Triangulation& t, const Vec3& origin) {
  if (origin == Vec3::Zero()) return;
  t.mesh.V.rowwise() += origin.transpose();
  for (std::vector<Vec3>& line : t.fieldLines)
    for (Vec3& p : line) p += origin;
  for (FieldSingularity& s : t.singularities) s.position += origin;
  for (std::string& note : t.notes) note = inFileFrame(note, origin);
}

}  // namespace

void validate(const PipelineParams& p) {
  auto fail = [](const std::string& m) { throw Error(ErrorCode::InvalidParameter, m); };
  if (!std::isfinite(p.cell) || p.cell < 0) fail("cell must be a positive length (got " + number(p.cell) + ")");
  if (p.cell == 0 && (p.faces < 12 || p.faces > kMaxFaces))
    fail("faces must be between 12 and " + std::to_string(kMaxFaces) + " (got " + std::to_string(p.faces) + ")");
  if (!(p.tolerance > 0 && p.tolerance <= 0.1)) fail("tolerance must be in (0, 0.1] (got " + number(p.tolerance) + ")");
  if (!(p.lambda >= 0 && p.lambda <= 1e6)) fail("lambda must be in [0, 1e6] (got " + number(p.lambda) + ")");
  if (!(p.mu >= 0 && p.mu <= 1e6)) fail("mu must be in [0, 1e6] (got " + number(p.mu) + ")");
  if (!(p.fairness >= 0 && p.fairness <= 1)) fail("fairness must be in [0, 1] (got " + number(p.fairness) + ")");
  if (!(p.cutShare >= 0 && p.cutShare <= 1)) fail("cutShare must be in [0, 1] (got " + number(p.cutShare) + ")");
  if (!(p.foldRoundsShare >= 0 && p.foldRoundsShare <= 1))
    fail("foldRoundsShare must be in [0, 1] (got " + number(p.foldRoundsShare) + ")");
  if (p.foldAlignRounds < 0 || p.foldAlignRounds > 100)
    fail("foldAlignRounds must be between 0 and 100 (got " + std::to_string(p.foldAlignRounds) + ")");
  if (p.maxIterations < 1 || p.maxIterations > 10000)
    fail("maxIterations must be between 1 and 10000 (got " + std::to_string(p.maxIterations) + ")");
  if (!(p.lowerBound >= 0 && p.lowerBound <= 2)) fail("lowerBound must be in [0, 2] (got " + number(p.lowerBound) + ")");
  if (p.start && !p.start->allFinite()) fail("start must be a point of three finite numbers");
  if (p.direction && (!p.direction->allFinite() || !(p.direction->norm() > 0)))
    fail("direction must be a non-zero vector of three finite numbers");
  if (p.method != TriangulationMethod::Subdivision) parseFieldSpec(p.field);
  if (p.mesh && p.mesh->bytes.empty()) fail("the uploaded mesh '" + p.mesh->name + "' is empty (0 bytes)");
  validate(globalOptions(p, p.cell > 0 ? p.cell : 1.0));
  if (p.mesh && p.method == TriangulationMethod::Lattice)
    fail("the lattice method needs an analytic surface; use method 'progressive' or 'prespecified' for an uploaded mesh");
}

GlobalOptions globalOptions(const PipelineParams& p, double cell, const Surface* surface) {
  GlobalOptions o;
  o.cell = cell;
  o.faces = cell > 0 ? 0 : p.faces;
  o.anisotropy = p.anisotropy;
  o.alignment = p.alignment;
  o.curvatureSizing = p.curvatureSizing;
  o.curvatureFloor = p.curvatureFloor;
  // Dislocations glided together only where the surface is smooth, unless asked: on the noisy shared models (20
  // runs) they gave 1.7-2.4 points more hexagons but cut 114 -> 122-155 interior faces, none converging either way.
  o.glideDislocations = !surface || smoothRepairs(p, *surface);
  o.freeAlignedBoundary = !surface || !noisyUpload(*surface);
  o.cancelDislocations = p.cancelDislocations;
  o.principalTrial = p.principalTrial;
  return o;
}

double farNodeDistance(const PolyMesh& hex, double diagonal) {
  return diagonal > 0 ? std::max(kFarNodeDistance, hex.meanEdgeLength() / diagonal) : kFarNodeDistance;
}

int countFarNodes(const std::vector<double>& distance, double farOff, int* farthest) {
  int far = 0, worst = 0;
  for (int v = 0; v < static_cast<int>(distance.size()); ++v) {
    far += distance[v] > farOff;
    if (distance[v] > distance[worst]) worst = v;
  }
  if (farthest) *farthest = worst;
  return far;
}

void clearUploadCache() {
  UploadCache& cache = uploadCache();
  const std::lock_guard<std::mutex> lock(cache.mutex);
  cache.surface.reset();
  cache.refined.reset();
  cache.refinedBy = 0;
  cache.key = UploadKey{};
}

SurfacePreview surfacePreview(const PipelineParams& params) {
  validate(params);
  SurfacePreview out;
  std::vector<LocalGeometry> geo;
  if (params.method == TriangulationMethod::Subdivision) {
    const TriMesh control = checkConvexControl(params.mesh ? uploadedMesh(*params.mesh) : controlMesh(params.surface));
    const SubdivisionTriangulation st = subdivisionTriangulation(control, 3);
    out.mesh = st.surface->mesh();
    geo = st.surface->vertexGeometries();
  } else if (params.mesh) {
    bool reused = false;
    Vec3 origin;
    const std::shared_ptr<const MeshSurface> s = uploadedSurface(*params.mesh, reused, origin);
    out.mesh = s->mesh();
    out.mesh.V.rowwise() += origin.transpose();
    geo = s->vertexGeometries();
  } else {
    const ParametricSurfacePtr s = makeSurface(params.surface, params.surfaceParams);
    Triangulation t = latticeTriangulation(*s, cellForFaceCount(*s, 6000));
    geo = vertexGeometry(t, *s);
    out.mesh = std::move(t.mesh);
  }
  for (const LocalGeometry& g : geo) out.k1.push_back(g.k1), out.k2.push_back(g.k2);
  return out;
}

namespace {

// The analytic surface's spec, for what `auto` recommends; nullptr for other names (makeSurface names them).
const SurfaceSpec* analyticSpec(const std::string& name) {
  for (const SurfaceSpec& s : analyticSurfaces())
    if (s.name == name) return &s;
  return nullptr;
}

}  // namespace

TriangulationMethod resolveMethod(const PipelineParams& params) {
  if (params.method != TriangulationMethod::Auto) return params.method;
  if (params.mesh) return TriangulationMethod::Prespecified;
  const SurfaceSpec* spec = analyticSpec(params.surface);
  return spec ? parseTriangulationMethod(spec->method) : TriangulationMethod::Progressive;
}

namespace {

// How far (as a ratio) a lay's vertex count may miss the faces asked for before it is laid again.
constexpr double kCount = 1.1;
// How far it may miss when the counts do not follow the cell smoothly (thirdLayExponent).
constexpr double kCountLoose = 1.15;

// The parameter lattice at `cell`, and where its vertex count (the P-Hex mesh's faces) misses `faces` by more than
// kLatticeCountMiss, again (at most twice) at the cell scaled by the miss; the closest count is kept. The cell comes
// from the surface's area, the lattice's counts from its parameter lines' mean lengths: on a surface of revolution
// whose radius varies much along a parameter not proportional to arc length they differ (a hyperboloid with waist
// 0.2 and height 4: 732 faces for 1000 asked, now 1000).
constexpr double kLatticeCountMiss = 1.05;
Triangulation latticeLaidToCount(const ParametricSurface& surface, double cell, int faces) {
  Triangulation best = latticeTriangulation(surface, cell);
  if (faces <= 0) return best;
  auto miss = [faces](const Triangulation& t) {
    const double count = std::max(1.0, static_cast<double>(t.mesh.V.rows()));
    return std::max(count / faces, faces / count);
  };
  double bestMiss = miss(best);
  for (int again = 0; again < 2 && bestMiss > kLatticeCountMiss; ++again) {
    cell *= std::sqrt(std::max(1.0, static_cast<double>(best.mesh.V.rows())) / faces);
    Triangulation t = latticeTriangulation(surface, cell);
    const double m = miss(t);
    if (m >= bestMiss) break;
    best = std::move(t), bestMiss = m;
  }
  return best;
}

// About how many faces (vertices of the triangulation) `cell` gives on `surface`: cellForFaceCount inverted.
double facesAtCell(const Surface& surface, double cell) { return std::pow(cellForFaceCount(surface, 1) / cell, 2); }

// Whether a trial lay of `trialVertices` vertices at `trialCell` predicts that `cell` misses `faces` vertices by
// more than kCount (counts go as cell^-2).
bool trialPredictsMiss(double trialCell, double trialVertices, double cell, int faces) {
  return std::abs(std::log(trialVertices * trialCell * trialCell / (cell * cell) / faces)) > std::log(kCount);
}

// The cell a trial lay of `trialVertices` vertices at `trialCell` predicts for `faces` vertices (counts go as
// cell^-2), within a factor 2 of the area estimate's cell `estimate`, which it is where it would pass kMaxFaces.
double predictedCell(const Surface& surface, double trialCell, double trialVertices, int faces, double estimate) {
  const double cell = std::clamp(trialCell * std::sqrt(trialVertices / faces), 0.5 * estimate, 2 * estimate);
  return facesAtCell(surface, cell) > kMaxFaces ? estimate : cell;
}

// Where L0 should start, and along which family, when the caller did not say. The middle of the bounds,
// projected, suits a patch; on a ring (torus, cyclide, their meshes) it lands on the inner side, where rows
// along the parallels must be resampled as they grow and cross the parabolic circles badly. So a few
// candidates — that point, and the most elliptic and the most hyperbolic of some 150 samples of the surface —
// are laid at a half the size (at most 1000 faces), and the one whose triangulation covers most of the
// surface with the fewest invalid stars and self-intersecting faces of its Dupin dual wins.
// On a surface with parabolic curves the rows follow the zero-curvature direction there (BaseFamily::Auto);
// where that network cannot cover the surface (round bumps, whose parabolic rings no singularity-free
// network contains) the other family is laid from the same candidates and kept if it scores better.
constexpr double kPoorTrial = 0.8;  // a trial score (coverage minus 5x the bad share) below which more is tried
// Trials of the two families whose scores differ by more than this decide without full-size lays. On the bumps
// the other family's trial scores 0.092 higher (trials at 1000 faces, for 2000 faces asked and more) or 0.035
// (at 500, for 1000 asked), and at all 12 sizes from 1000 to 20000 faces its full lay scored higher too (by
// 0.009-0.19): one lay of 0.7 s fewer at 10k faces.
constexpr double kClearTrial = 0.03;
// A fourth candidate lies on a parabolic curve (the sample of smallest kmin / kmax, where under
// kParabolicStart; Method 2 only, see chooseStart): on a ring its rows along the parallels start on the
// parabolic circle, whose length lies between the inner and the outer equator's, so they grow and shrink
// within the resampling bounds and are never resampled, where from the inner equator they are resampled
// twice, leaving rings of pentagons and heptagons (the torus by Method 2 at 2000 faces: 92 % valence 6, and
// 100 % from the parabolic circle; the uploaded torus alike). It replaces the best of the others where it
// ranks higher with their share of interior vertices of valence 6 counted too (kIrregularPrice per unit
// missing), which coverage and invalid stars do not see.
constexpr double kParabolicStart = 0.1;
constexpr int kParabolicStartSamples = 1000;  // a 32 x 32 grid on a parametric surface: within 6 degrees of the circle
constexpr double kIrregularPrice = 1.0;
constexpr double kOverlapPrice = 5.0;  // per unit of coverage over 1 (overlapping triangles), in a trial's score

// The most nearly umbilic of some 400 samples of the surface (relative k1 - k2 under kNearUmbilic) where it
// is curved (not on a plane or a developable), or nullopt.
constexpr double kNearUmbilic = 0.05;
std::optional<Vec3> umbilicWithinCurvedPart(const Surface& surface) {
  std::optional<Vec3> best;
  double lowest = kNearUmbilic;
  for (const LocalGeometry& g : surface.samples(400)) {
    const double a = std::abs(g.k1), b = std::abs(g.k2);
    if (!(std::min(a, b) > 0.05 * std::max(a, b))) continue;  // flat in a direction: not an umbilic
    const double gap = std::abs(g.k1 - g.k2) / (a + b);
    if (gap < lowest) lowest = gap, best = g.point;
  }
  return best;
}

// How much of the surface bends the other way along the plane sections (field "section") than most of it:
// of some 400 samples where the sections' normal curvature is clearly not zero (over 5 % of kmax), the
// share of the less common sign. Where it changes sign the section direction is asymptotic somewhere and has
// no conjugate there (the bumps, a hill's flanks); where it keeps one sign — a dome, or a cushion whose
// corners are saddles but bend down along the sections all the same — the sections and their conjugate lines
// make a network with no singularity.
double sectionBendingMixed(const Surface& surface, double degrees) {
  const Vec3 planes = sectionPlaneNormal(surface, degrees);
  int up = 0, down = 0;
  for (const LocalGeometry& g : surface.samples(400)) {
    const Vec3 d = g.normal.cross(planes);
    if (!(d.norm() > 1e-9)) continue;
    const Vec2 t = tangentVector(g, d.normalized());
    const double kn = secondFundamentalForm(g, t, t), kmax = g.largestCurvature();
    if (std::abs(kn) > 0.05 * kmax) ++(kn > 0 ? up : down);
  }
  return up + down == 0 ? 0.0 : double(std::min(up, down)) / double(up + down);
}

// Plane sections instead of curvature lines (field "section"), where "principal" was not chosen by the user.
// A dome's top is an umbilic: its curvature lines (the meridians and parallels of a dome of revolution) turn
// around it, so the rows of "principal" cannot cover it in one system, and the seams between several leave
// irregular vertices (an uploaded dome at 2000 faces: 7 systems, 87 % valence 6 and 4 invalid stars, in
// 0.76 s). The sections by parallel planes standing on the dome and their conjugate lines form a conjugate
// network with no singularity on an elliptic height field (the same dome: one system, 100 % valence 6, no
// invalid star, 0.17 s). So where the principal trials took several systems around an umbilic and the
// surface bends mostly one way along the sections (sectionBendingMixed under kSectionMixed, along the plan's
// longest extent or across it), the section trials are laid too, and the field whose best trial scores
// higher with its irregular vertices counted (seams included) wins. A dome: 0. A cushion, whose corners are
// saddles, along its diagonals (a square plan's longest extent comes out as one): 0.21, and its sections lay
// 100 % hexagons where its curvature lines lay 79-92 %. Not where the bending changes sign over much more of
// the surface (the bumps 0.31-0.45, a hill 0.29): there section lines run along asymptotic directions, which
// have no conjugate, and their lays covered less (an uploaded bumps mesh at 2000 faces: 70 % for 88 %), so
// their trials would only cost time.
constexpr double kSectionMixed = 0.25;
// Below this share of the surface covered a triangulation is an error (CannotTile), not a result.
constexpr double kMinCoverage = 0.25;

// The trial lays' size (chooseStart) for `faces` asked: half of them, within [50, 1000].
int trialFacesFor(int faces) { return std::clamp(faces / 2, 50, 1000); }

// Uploads under auto keep Method 2 only where its trial lays take one system of rows (the wave roof, a cylinder);
// on the free-form models they take several and the global method tiles them, so the trials (four to nine lays
// of up to 1000 faces, some at full size) only found that out. So where they would be larger, one lay from the
// middle of the bounds at about this many faces comes first (quickSystems); where it takes several systems of
// rows, and so does one along plane sections where these are in question (kSectionMixed), the global method
// tiles the upload without the trials; and where the curvature lines' trials take several systems, the plane
// sections' trials run only where one quick lay along them takes one. The same method and mesh on 16 uploads of
// the analytic surfaces, the six shared models and the bumps upload at 1000, 3000 and 10000 faces (69 runs, 35 of
// them kept by Method 2), the trials left out on 15 of the 34 tiled globally: the bubble at 1000, 3000 and 10000
// faces 0.90 -> 0.30, 1.93 -> 0.68, 4.37 -> 2.68 s, six_s0 1.52 -> 0.52 s at 3000, the Concerthall 1.43 -> 1.00,
// the bumps upload at 10k faces 1.57 -> 1.37 s; the sections' trials on the intersection shell (its quick lay
// along them cannot be laid) 3.24 -> 1.90 s at 3000. The uploads kept by Method 2 pay the quick lay (a few
// hundredths of a second at 10k faces).
constexpr int kQuickTrialFaces = 250;

// The systems of rows one lay takes from the middle of the bounds at about kQuickTrialFaces where `faces` are
// asked for at `options.cell` (0 where it cannot be laid).
int quickSystems(const Surface& surface, const LayingOptions& options, int faces, const CancelFlag* cancel) {
  LayingOptions o = options;
  if (o.base == BaseFamily::Auto && !o.baseDirection) o.base = parabolicBaseFamily(surface, options);
  o.cell = options.cell * std::sqrt(double(faces) / kQuickTrialFaces);
  o.start = surface.bounds().center();
  o.repairSweeps = 0;  // the rows' systems are what is asked
  try {
    return layTriangulation(surface, o, {}, cancel).systems;
  } catch (const Error& e) {
    if (e.code() == ErrorCode::Cancelled) throw;
    return 0;
  }
}

struct StartChoice {
  std::optional<Vec3> start;        // nullopt: the default start (nothing to choose between)
  BaseFamily base = BaseFamily::Auto;
  double trialCell = 0, trialVertices = 0;  // the winning trial lay's cell and vertex count (else 0)
  // Where the two families were compared at full size, the winner's lay (from `start` along `base` at
  // `laidCell`): the full lay itself, so it is not laid again.
  std::optional<Triangulation> laid;
  double laidCell = 0;
  std::string note;
  // The best trial's score with the price of its irregular vertices, seams included (-inf: no trial), and
  // how many systems of rows it took: what compares two fields (plane sections against curvature lines).
  double quality = -std::numeric_limits<double>::infinity();
  int systems = 0;
};

// `cellGiven`: the cell in `options` was asked for (the full-size lays use it as it is); else a face count
// was, and they use the cell each family's trial predicts for it.
StartChoice chooseStart(const Surface& surface, const LayingOptions& options, int faces, bool cellGiven,
                        const CancelFlag* cancel) {
  StartChoice choice;
  LayingOptions trial = options;
  const bool pickFamily = options.base == BaseFamily::Auto && !options.baseDirection;
  if (pickFamily) trial.base = choice.base = parabolicBaseFamily(surface, options);
  const std::vector<LocalGeometry> samples = surface.samples(150);  // a 12 x 12 grid on a parametric surface
  if (samples.empty()) return choice;
  std::vector<Vec3> candidates = {surface.bounds().center()};
  const auto byK = [](const LocalGeometry& a, const LocalGeometry& b) { return a.gaussianCurvature() < b.gaussianCurvature(); };
  const LocalGeometry& most = *std::max_element(samples.begin(), samples.end(), byK);
  const LocalGeometry& least = *std::min_element(samples.begin(), samples.end(), byK);
  if (most.gaussianCurvature() > 0) candidates.push_back(most.point);
  if (least.gaussianCurvature() < 0) candidates.push_back(least.point);
  const int trialFaces = trialFacesFor(faces);
  trial.cell = options.cell * std::sqrt(double(faces) / trialFaces);
  int laid = 0;
  // The score of a trial lay (`rank`; `plain` without the price of irregular vertices), or nullopt where it
  // cannot be laid.
  struct Trial {
    double rank, plain, vertices;
    int systems;
    double regular;  // the share of interior vertices of valence 6
  };
  // Thread-safe: `o` is the caller's own (parallelTasks runs several at once).
  auto score = [&](const LayingOptions& o, Triangulation* keep = nullptr) -> std::optional<Trial> {
    Triangulation t;
    try {
      t = layTriangulation(surface, o, {}, cancel);
    } catch (const Error& e) {
      if (e.code() == ErrorCode::Cancelled) throw;
      return std::nullopt;  // this start cannot be laid from; the others may
    }
    const TriangulationCheck check = checkTriangulation(t, surface);
    // The dual as §6 builds it, without untangling: the count judges the triangulation.
    const int folded = measure(dupinDual(t, surface, false).mesh).selfIntersectingCount;
    const double bad = double(check.invalidStars.size() + folded) / std::max<Eigen::Index>(t.mesh.V.rows(), 1);
    // Coverage over 1 is triangles laid over each other, not more surface covered: it counts against the lay
    // (a half ring closed around its tube, by Method 1 at 2500 faces, scored its overlapping lay at 1.39 and
    // chose it).
    const double coverage = check.coverage >= 0 ? check.coverage : 1.0;
    const double plain = (coverage <= 1 ? coverage : 1 - kOverlapPrice * (coverage - 1)) - 5 * bad;
    // Where the lay took several systems of rows (the bumps), their seams' irregular vertices at a trial's
    // size say little about the full lay's: there coverage and validity alone rank.
    const double irregular = t.systems > 1 ? 0.0 : 1 - check.regularFraction;
    const Trial result{plain - kIrregularPrice * irregular, plain, double(t.mesh.V.rows()), t.systems,
                       check.regularFraction};
    if (keep) *keep = std::move(t);
    return result;
  };
  // Every candidate laid along trial.base; the best start, its score and vertex count. The middle of the
  // bounds (the first candidate) keeps the start unless another is clearly better: at a quarter of the size
  // small differences are noise.
  struct Best {
    std::optional<Vec3> start;
    double score = -std::numeric_limits<double>::infinity(), vertices = 0;
    int systems = 0;
    double rank = score;  // the score less the price of irregular vertices
    double regular = 0;
  };
  // The trial lays from `starts` along `base`, laid at once (parallelTasks), each less the handicap of a start
  // other than the middle of the bounds; nullopt where one cannot be laid.
  auto trialsFrom = [&](const std::vector<Vec3>& starts, BaseFamily base) {
    std::vector<std::optional<Best>> trials(starts.size());
    parallelTasks(static_cast<int>(starts.size()), [&](int i) {
      LayingOptions o = trial;
      o.start = starts[i];
      o.base = base;
      const auto s = score(o);
      if (!s) return;
      const double handicap = starts[i] == candidates.front() ? 0.0 : 0.05;
      trials[i] = Best{starts[i], s->plain - handicap, s->vertices, s->systems, s->rank - handicap, s->regular};
    });
    return trials;
  };
  // The best of the first `count` trials, in order (the first of equal scores), counting those laid.
  auto bestOf = [&](const std::vector<std::optional<Best>>& trials, std::size_t count) {
    Best b;
    for (std::size_t i = 0; i < count; ++i) {
      if (!trials[i]) continue;
      ++laid;
      if (trials[i]->score > b.score) b = *trials[i];
    }
    return b;
  };
  // The start on a parabolic curve (below) is a candidate only where the best of the others took one system
  // of rows; with threads to spare it is laid along with them, and its lay used only then.
  std::optional<Vec3> parabolic;
  if (options.method == LayingMethod::Prespecified &&
      most.gaussianCurvature() - least.gaussianCurvature() > 0) {  // not a developable, parabolic throughout
    double lowest = kParabolicStart;
    for (const LocalGeometry& g : surface.samples(kParabolicStartSamples)) {
      const double a = std::abs(g.k1), b = std::abs(g.k2), kmax = std::max(a, b);
      if (!(kmax > 0)) continue;
      const double ratio = std::min(a, b) / kmax;
      if (ratio < lowest) lowest = ratio, parabolic = g.point;
    }
  }
  std::vector<Vec3> starts = candidates;
  const bool ahead = parabolic && threadCount() > 1;
  if (ahead) starts.push_back(*parabolic);
  std::vector<std::optional<Best>> trials = trialsFrom(starts, trial.base);
  Best best = bestOf(trials, candidates.size());
  const bool poor = best.score < kPoorTrial;
  // The start on a parabolic curve replaces the best where it ranks higher with the price of irregular
  // vertices. Not on the bumps, whose lays take several systems of rows from every start (one from their
  // parabolic rings laid fewer hexagons at 2000-4000 faces, 0.81 -> 0.76, and more at 5000-13000), nor by
  // Method 1, whose ideal step explodes along a base curve on a parabolic curve (on the torus its rows from
  // there left 1-5 invalid stars from 5000 faces on, and the counts followed the cell poorly). The three
  // other candidates are still ranked as before: ranked by irregular vertices too, the uploaded cyclide at
  // 1500 faces started from its outer equator instead, with 96 % hexagons for 91 % but its farthest node at
  // 0.38 % of the diagonal for 0.14 %.
  if (best.systems == 1 && parabolic) {
    if (!ahead) trials.push_back(trialsFrom({*parabolic}, trial.base).front());
    const std::optional<Best>& there = trials.back();
    laid += there.has_value();
    if (there && there->rank > best.rank) best = *there;
  }
  // Only when the family along the zero-curvature direction leaves much of the surface uncovered or invalid
  // (a score below kPoorTrial) is the other family tried, from every candidate: on surfaces whose network
  // contains the parabolic curves it costs no lay. On such a surface the half-size trials predict the full
  // lay poorly (a laying that covers 44 % at half the size may cover 28 % at full size), so unless the trials
  // differ clearly (kClearTrial) the two families' best starts are laid once more at full size, and the better
  // of those decides. Each at the cell its trial predicts for the face count asked (as the full lay is, see
  // `triangulate`), and the winner's lay is kept as the full lay: one lay fewer (on the bumps at 10k faces,
  // before kClearTrial let the trials decide there, about 0.45 s).
  // Method 2's rows only where the curved part has an umbilic, around which a singularity-free network may
  // not exist (the bumps): elsewhere its rows along the zero-curvature direction are §5.3's, and the other
  // family crosses the parabolic curves the infeasible way (Fig. 19). On the whole cyclide at 1000 faces (no
  // umbilic) its trial happened to score higher, and the full lay, across both parabolic circles, stopped at
  // 6e-3 (exit 2). Method 1's rows find their own conjugates, and on the wave roof its lays from the other
  // family's start are better (96-98 % hexagons at 1000-5000 faces, 90-95 % without).
  bool otherFamily = false;
  if (poor && best.start && (choice.base == BaseFamily::First || choice.base == BaseFamily::Conjugate) &&
      (options.method != LayingMethod::Prespecified || umbilicWithinCurvedPart(surface))) {
    const BaseFamily rule = choice.base, other = rule == BaseFamily::First ? BaseFamily::Conjugate : BaseFamily::First;
    const Best alternative = bestOf(trialsFrom(candidates, other), candidates.size());
    if (alternative.start && alternative.score > best.score + kClearTrial) {
      best = alternative;
      choice.base = other;
      otherFamily = true;
    } else if (alternative.start) {
      const double trialCell = trial.cell;
      auto fullCell = [&](double vertices) {  // as `triangulate` picks the full lay's cell
        return cellGiven || !trialPredictsMiss(trialCell, vertices, options.cell, faces)
                   ? options.cell
                   : predictedCell(surface, trialCell, vertices, faces, options.cell);
      };
      // Both full-size lays at once.
      Triangulation layRule, layOther;
      LayingOptions ruleOptions = trial, otherOptions = trial;
      ruleOptions.cell = fullCell(best.vertices);
      ruleOptions.start = best.start;
      ruleOptions.base = rule;
      otherOptions.cell = fullCell(alternative.vertices);
      otherOptions.start = alternative.start;
      otherOptions.base = other;
      std::optional<Trial> full, fullOther;
      parallelTasks(2, [&](int i) {
        if (i == 0) full = score(ruleOptions, &layRule);
        else fullOther = score(otherOptions, &layOther);
      });
      const double ruleCell = ruleOptions.cell, otherCell = otherOptions.cell;
      if (fullOther && (!full || fullOther->plain > full->plain)) {
        best = alternative;
        choice.base = other;
        otherFamily = true;
        choice.laid = std::move(layOther);
        choice.laidCell = otherCell;
      } else if (full) {
        choice.laid = std::move(layRule);
        choice.laidCell = ruleCell;
      }
    }
  }
  choice.quality = best.score - kIrregularPrice * (1 - best.regular);
  choice.systems = best.systems;
  if ((laid < 2 && !otherFamily) || !best.start) return choice;  // nothing to choose between: the default start
  choice.start = best.start;
  choice.trialCell = trial.cell;
  choice.trialVertices = best.vertices;
  std::ostringstream s;
  s << "start chosen among " << laid << " candidates by trial lays at about " << trialFaces << " faces: near ("
    << best.start->x() << ", " << best.start->y() << ", " << best.start->z() << ")";
  if (otherFamily)
    s << "; rows along the family across the zero-curvature direction, which laid better than the family along "
         "it (no singularity-free network contains these parabolic curves)";
  choice.note = s.str();
  return choice;
}

}  // namespace

namespace {

// The local solver's fairness for `method` on `surface` (PipelineParams::fairness): the global method's solves, but
// not on a noisy upload. The paper's methods lay rows whose duals their figures were measured without it. On the
// noisy shared models it turned stalls into convergence by cutting many faces (3holes at 3000 faces: 4 -> 48 cut,
// 88.6 -> 78.9 % hexagons; six_s0 at 5000: 9 -> 406; METHOD.md), which is not the trade asked for.
double fairnessFor(const PipelineParams& params, TriangulationMethod method, const Surface& surface) {
  return method == TriangulationMethod::Global && smoothRepairs(params, surface) ? params.fairness : 0.0;
}

}  // namespace

namespace detail {

// The solver's options as the run's parameters ask for them, for a triangulation laid by `method` on `surface`.
PlanarizeOptions planarizeOptions(const PipelineParams& params, TriangulationMethod method, const Surface& surface) {
  PlanarizeOptions po;
  po.method = params.solver;
  po.lambda = params.lambda;
  po.mu = params.mu;
  po.fairness = fairnessFor(params, method, surface);
  po.tolerance = params.tolerance;
  po.maxIterations = params.maxIterations;
  po.preventFolds = params.preventFolds;
  po.fitSurface = params.fitSurface;
  po.surface = &surface;
  return po;
}

}  // namespace detail

std::string resolveField(const PipelineParams& params) {
  if (params.method != TriangulationMethod::Auto || params.mesh || params.field != "principal") return params.field;
  const SurfaceSpec* spec = analyticSpec(params.surface);
  return spec ? spec->field : params.field;
}

namespace {
// The exponent e of vertices ~ cell^-e between two lays.
double countExponent(double cell0, double count0, double cell1, double count1) {
  return -std::log(count1 / count0) / std::log(cell1 / cell0);
}
}  // namespace

std::optional<double> thirdLayExponent(double cell0, double count0, double cell1, double count1, double closestMiss) {
  const double measured = countExponent(cell0, count0, cell1, count1);
  // Counts that hardly change with the cell (an exponent below 1, where a covering gives 2) come from lays
  // that cover the surface in different ways — on the uploaded bumps, whether the first system of rows runs
  // on past the saddle or leaves the second bump to a system of its own (about 12.5 and 9.7 vertices per unit
  // cell area). The secant then reaches far beyond both lays, and the third lay is as likely to land farther
  // off: the bumps at 100k faces laid 117k then 111k vertices (exponent 0.8), and the third lay (3-4 s) gave
  // 82k and was not kept. A steep exponent is different: the two lays lie on both sides of the count asked
  // for, and the third lay falls between them (the analytic bumps at 4000 faces: 4553 and 2828 vertices,
  // exponent 7.4; the third lay gives 3908 faces, and without it 4736).
  if (!(measured >= 1) && closestMiss <= kCountLoose) return std::nullopt;
  return std::clamp(std::isfinite(measured) ? measured : 2.0, 0.5, 4.0);
}

double relayCell(double cell, double count, int faces, double exponent, double estimateCell) {
  // Within a factor 2 of the area estimate's cell, as the trial's prediction is: a lay that stopped short
  // (a handful of vertices) with a flat exponent sent the cell down by the square of the ratio (an uploaded
  // cyclide at 64 faces: 7 triangles, then 350k in 6 s, then 711).
  return std::clamp(cell * std::pow(std::max(count, 1.0) / faces, 1 / exponent), 0.5 * estimateCell, 2 * estimateCell);
}

namespace {

// Creases of fewer edges than this (a stray pair of flipped slivers) go unmentioned.
constexpr int kCreaseEdges = 3;

// The points the coverage is measured at: an upload's vertices (about 10000 of them at most), else 2000 samples
// of the analytic surface.
std::vector<Vec3> coverageSamples(const Surface& surface) {
  std::vector<Vec3> points;
  if (const auto* mesh = dynamic_cast<const MeshSurface*>(&surface)) {
    const int n = mesh->vertexCount(), stride = std::max(1, n / 10000);
    for (int v = 0; v < n; v += stride) points.push_back(mesh->mesh().V.row(v).transpose());
  } else {
    for (const LocalGeometry& g : surface.samples(2000)) points.push_back(g.point);
  }
  return points;
}

// A lay of rows leaving a point of the upload this many mean triangle edges from any triangle has left it bare
// (triangulateOn).
constexpr double kBareGap = 2.0;

// The largest distance from the coverage samples of `surface` to the triangles of `t`, over their mean edge, and
// the sample farthest off: where a lay left part of the surface bare.
double bareGap(const Triangulation& t, const Surface& surface, Vec3* where) {
  PolyMesh tri;
  tri.V = t.mesh.V;
  for (int f = 0; f < t.mesh.F.rows(); ++f) tri.addFace({t.mesh.F(f, 0), t.mesh.F(f, 1), t.mesh.F(f, 2)});
  const std::vector<Vec3> points = coverageSamples(surface);
  const double edge = t.mesh.meanEdgeLength();
  int farthest = -1;
  const double gap = edge > 0 ? largestGapToMesh(tri, points, &farthest) / edge : 0.0;
  if (where && farthest >= 0) *where = points[static_cast<std::size_t>(farthest)];
  return gap;
}

// What a noisy uploaded mesh (MeshSurface::noise), or one with a crease, does to the method, said in the notes
// and in the errors of a lay that fails on it; empty for any other surface.
std::string uploadNote(const Surface* surface) {
  const auto* mesh = dynamic_cast<const MeshSurface*>(surface);
  if (!mesh) return "";
  std::ostringstream s;
  s.precision(2);
  if (!(mesh->noise() > MeshSurface::kNoisyMesh)) {
    // A ridge or fold (a gable roof): the method needs a tangent plane everywhere (§3), and a panel across
    // the crease cannot be planar. A noisy mesh's sharp edges are its noise, said below instead.
    const MeshSurface::Creases& c = mesh->creases();
    if (c.edges < kCreaseEdges || !c.sharp()) return "";
    std::ostringstream at;
    at.precision(4);
    at << "(" << c.at.x() << ", " << c.at.y() << ", " << c.at.z() << ")";
    s << "the uploaded mesh has a crease: " << c.edges << " edges where its triangles turn by more than "
      << MeshSurface::kCreaseDegrees << " degrees, the sharpest by " << std::lround(c.degrees) << " near " << at.str()
      << "; phex tiles smooth surfaces (§3: there is no tangent plane on a crease), and a panel across it "
         "cannot be planar: tile the parts on either side as meshes of their own, or round the crease off";
    return s.str();
  }
  s << "the uploaded mesh is noisy: its vertices lie " << 100 * mesh->noise()
    << " % of an edge (median) off smooth cubic fits of their neighbourhoods, so its curvature was fitted over "
    << mesh->curvatureRings()
    << " rings of neighbours instead of 2 (fewer where the surface folds within them); conjugate directions from a "
       "noisy mesh are unreliable, and its P-Hex nodes are held near a rough surface: smooth the mesh before "
       "uploading it for better panels";
  return s.str();
}

// `dupinDual`, where given, gets the Dupin dual of the triangulation where the stage built it on the way (the
// global method's fold flips solve it), so that runPipeline need not build it again.
struct StageDual {
  std::optional<DualMesh> dual;  // the Dupin dual of the triangulation, where the stage built it
  int folded = -1;  // its interior faces crossing themselves once solved with folds allowed (-1: not solved)
  std::optional<SolvedDual> solved;  // that dual as flipFoldsAway solved it (folds allowed, no fit)
};
TriangulationStage triangulateOn(const PipelineParams& given, const ProgressFn& progress, const CancelFlag* cancel,
                                 SurfacePtr& made, Vec3& origin, StageDual* dupinDual);

// triangulate in the upload's local frame (stage.origin), for runPipeline to go on in it.
TriangulationStage triangulateLocal(const PipelineParams& given, const ProgressFn& progress, const CancelFlag* cancel,
                                    StageDual* dupinDual = nullptr) {
  SurfacePtr surface;
  Vec3 origin = Vec3::Zero();
  try {
    return triangulateOn(given, progress, cancel, surface, origin, dupinDual);
  } catch (const Error& e) {
    const std::string note = uploadNote(surface.get());
    if (e.code() != ErrorCode::CannotTile || note.empty()) throw Error(e.code(), inFileFrame(e.what(), origin));
    throw Error(ErrorCode::CannotTile, inFileFrame(std::string(e.what()) + " (" + note + ")", origin));
  }
}

}  // namespace

TriangulationStage triangulate(const PipelineParams& given, const ProgressFn& progress, const CancelFlag* cancel) {
  TriangulationStage t = triangulateLocal(given, progress, cancel);
  toFileFrame(t.triangulation, t.origin);
  return t;
}

namespace {

TriangulationStage triangulateOn(const PipelineParams& given, const ProgressFn& progress, const CancelFlag* cancel,
                                 SurfacePtr& made, Vec3& origin, StageDual* dupinDual) {
  validate(given);
  PipelineParams params = given;
  params.method = resolveMethod(given);
  params.field = resolveField(given);
  TriangulationStage t;
  t.method = params.method;
  if (params.method == TriangulationMethod::Progressive || params.method == TriangulationMethod::Prespecified)
    t.field = params.field;
  std::string surfaceNote;
  std::optional<TriangulationCheck> checked;  // of a triangulation checked on the way (the geodesic route)
  auto checkCell = [&](const Surface& surface) {
    const double cell = params.cell > 0 ? params.cell : cellForFaceCount(surface, params.faces);
    const double expected = facesAtCell(surface, cell);
    if (expected > kMaxFaces)
      throw Error(ErrorCode::InvalidParameter, "cell " + number(cell) + " would give about " + number(std::round(expected)) +
                                                   " faces, more than the limit of " + std::to_string(kMaxFaces));
    return cell;
  };
  // A closed convex polyhedron of fewer vertices than the faces asked for (an icosahedron-like model of a
  // pebble, a control mesh uploaded as such) is no sampling of a surface to lay finer than it: faceted, its
  // fits see noise (the built-in egg control: vertices half an edge off cubic fits), and Method 2 covered 8 %
  // of it (exit 1). Under auto it is §7's control mesh, tiled on its Loop limit surface as method
  // subdivision does (98-99.5 % hexagons, 12 pentagons).
  std::shared_ptr<const MeshSurface> upload;  // read once (and kept: uploadedSurface)
  if (params.mesh && params.method != TriangulationMethod::Subdivision)
    upload = uploadedSurface(*params.mesh, t.surfaceReused, origin);
  std::optional<TriMesh> polyhedron;  // the upload so taken, checked as a control mesh, in its local frame (origin)
  if (given.method == TriangulationMethod::Auto && upload) {
    const double faces = params.cell > 0 ? facesAtCell(*upload, params.cell) : double(params.faces);
    if (upload->isClosed() && upload->creases().edges > 0 && upload->vertexCount() < faces) {
      try {
        polyhedron = checkConvexControl(upload->mesh());
      } catch (const Error&) {
        // not a convex control mesh: laid as an upload (polyhedron stays empty)
      }
      if (polyhedron) {
        params.method = t.method = TriangulationMethod::Subdivision;
        t.field.clear();
        std::ostringstream s;
        s << "the upload is a closed convex polyhedron of " << upload->vertexCount()
          << " vertices, faceted (edges turning by up to " << std::lround(upload->creases().degrees) << " degrees) and coarser than the "
          << std::lround(faces) << " faces asked for: taken as the control mesh of a Loop subdivision surface and "
             "tiled on its limit surface (§7), as method subdivision does; upload a finer mesh of the surface, or "
             "choose method prespecified, to have its facets laid as they are";
        surfaceNote = s.str();
      }
    }
  }
  if (params.method == TriangulationMethod::Subdivision) {
    // About its centre when far from the origin, as an upload is (localOrigin): an egg control 5400 km from
    // the origin, subdivided and solved in the file's coordinates, stalled at planarity 5e-8 (exit 2).
    TriMesh control;
    if (polyhedron) {
      control = std::move(*polyhedron);
    } else {
      TriMesh given = params.mesh ? uploadedMesh(*params.mesh) : controlMesh(params.surface);
      origin = localOrigin(given);
      if (origin != Vec3::Zero()) given.V.rowwise() -= origin.transpose();
      control = checkConvexControl(given);
    }
    t.origin = origin;
    SubdivisionTriangulation st = subdivisionTriangulation(control, subdivisionLevels(control, params.faces, params.cell));
    t.triangulation = std::move(st.triangulation);
    t.surface = st.surface;
  } else {
    if (params.mesh) {
      t.surface = upload;
      t.origin = origin;
      if (params.start) *params.start -= origin;
      const double cellAsked = params.cell > 0 ? params.cell : cellForFaceCount(*upload, params.faces);
      const double size = upload->mesh().triangleSize();
      if (const Refinement by = refinementFor(*upload, size, cellAsked); by.k > 1) {
        const int k = by.k;
        const bool uneven = by.blend == MeshSurface::Blend::Barycentric;
        const std::shared_ptr<const MeshSurface> refined = refinedUpload(upload, by);
        std::ostringstream s;
        s.precision(3);
        s << "the uploaded mesh is coarse for this lay (its triangles' size " << size << " against a cell of " << cellAsked
          << (size > kCoarseUpload * cellAsked || uneven ? "" : "; a noisy mesh's facets kink the lay from one cell on")
          << "): ";
        // Too coarse for its fits to agree (a steep dome sampled 4 x 4, whose fits around a corner span most
        // of it): their blend would crease where the mesh does not, so the facets are laid as they are. A noisy
        // upload's facets turn sharply themselves: refined where that turns less sharply than they do (PH-CPF's
        // car, genus-3 model and intersection shell: 48 -> 31, 58 -> 40 and 69 -> 53 degrees at 3000 faces).
        const bool smoother = noisyUpload(*upload) && refined->creases().degrees < upload->creases().degrees;
        if (refined->creases().sharp() && !smoother) {
          s << "too coarse to be refined smoothly (the fits around its vertices disagree: the refinement would turn by "
            << std::lround(refined->creases().degrees) << " degrees between neighbouring triangles), so laid on its facets; "
               "upload a finer mesh for panels that follow the surface";
        } else {
          t.surface = refined;
          s << "laid on a smooth surface " << (uneven ? "through" : "near") << " its " << upload->vertexCount()
            << " vertices, each of its " << upload->mesh().F.rows() << " triangles split " << k << " x " << k
            << (uneven ? " onto the cubic fits around its corners"
                       : " onto the smooth blend of the cubic fits around its vertices")
            << ", so that panels need not bend over its facets' edges";
        }
        surfaceNote = s.str();
      }
    } else {
      t.surface = makeSurface(params.surface, params.surfaceParams);
    }
    made = t.surface;
    // §5.3: on a developable K = 0 everywhere, so Method 1 has no ideal triangle to take a step from; its
    // rows, stepped off a ruling by a fixed ratio, drift off the rulings where these fan out (a cone), and
    // the conjugate of a drifting row is the ruling itself, along the row: 89-92 % hexagons on the cone, not
    // converged, 3 s at 2500 faces. The paper tiles developables along their rulings whatever the method,
    // which Method 2 along the principal field does (100 %, planar as laid).
    if (params.method == TriangulationMethod::Progressive && params.field == "principal" && isDevelopable(*t.surface)) {
      params.method = t.method = TriangulationMethod::Prespecified;
      surfaceNote += std::string(surfaceNote.empty() ? "" : "; ") +
          "progressive conjugation (Method 1) has no ideal triangles on a developable (K = 0 everywhere, §5.3): "
          "laid along its rulings by Method 2 (pre-specified conjugation, principal field) instead";
    }
    // An uploaded plane (a flat façade, a sloping roof): any hexagon tiling of it is planar (§3), and its
    // principal directions are undefined everywhere. Under the umbilics' convention they ran as meridians
    // through one point, rows on top of each other: a sloping plane at 3000 faces had 104 triangles of no
    // area, 71 % hexagons and stopped at 6e-4 (exit 2). Straight rows along plane sections tile it as the
    // analytic plane's lattice does: 100 % hexagons, planar as laid.
    if (const auto* mesh = dynamic_cast<const MeshSurface*>(t.surface.get());
        mesh && mesh->planar() && params.method == TriangulationMethod::Prespecified && params.field == "principal") {
      params.field = t.field = "section";
      surfaceNote += std::string(surfaceNote.empty() ? "" : "; ") +
                     "the uploaded mesh is a plane (no curvature over 1e-6 of its diagonal's inverse anywhere): "
                     "every hexagon tiling of it is planar (§3), and its principal directions are undefined; "
                     "laid in straight rows along plane sections (field section) instead";
    }
    const double cell = checkCell(*t.surface);
    // §7 for an upload: a closed convex surface (a pebble, an egg, an ellipsoid) has umbilics and no regular
    // conjugate network around them; Method 2 laid an uploaded ellipsoid at 3000 faces in two systems with
    // eight zipped seams, overlapping (coverage 1.09), 86 % hexagons, 0.35 % of the diagonal off. The geodesic
    // icosahedron mapped onto it gives valence 6 everywhere but at 12 vertices (its pentagons).
    // Kept only where it leaves no more invalid stars than a hundredth of its vertices (else laid as below).
    const auto* closedMesh = dynamic_cast<const MeshSurface*>(t.surface.get());
    if (given.method == TriangulationMethod::Auto && closedMesh && closedConvexUpload(*closedMesh)) {
      const double faces = params.cell > 0 ? facesAtCell(*t.surface, cell) : double(params.faces);
      const int frequency = std::max(1, static_cast<int>(std::lround(std::sqrt(std::max(faces - 2, 10.0) / 10))));
      Triangulation g = geodesicTriangulation(*closedMesh, frequency);
      repairStars(g, *t.surface);
      TriangulationCheck check = checkTriangulation(g, *t.surface);
      if (check.invalidStars.size() <= 0.01 * double(g.mesh.V.rows())) {
        params.method = t.method = TriangulationMethod::Subdivision;
        t.field.clear();
        t.triangulation = std::move(g);
        checked = std::move(check);
      }
    }
    if (checked) {
      // Laid above, by the geodesic route.
    } else if (params.method == TriangulationMethod::Global) {
      t.triangulation = globalTriangulation(*t.surface, globalOptions(params, params.cell > 0 ? params.cell : 0, t.surface.get()), progress, cancel);
      // The lattice's stars are near-equilateral in the bounded Dupin frame; where a defect or the bound leaves one
      // failing Props. 4, 5, the local repair mends it (the shared models at 3000 faces: 120-500 invalid stars
      // to 1-140).
      repairStars(t.triangulation, *t.surface);
      // A re-lay of a run under auto that chose the global method: its notes say why, as the first lay's did.
      if (!params.globalBecause.empty()) {
        surfaceNote += (surfaceNote.empty() ? "" : "; ") + params.globalBecause;
        t.globalBecause = params.globalBecause;
      }
    } else if (params.method == TriangulationMethod::Lattice) {
      t.triangulation = latticeLaidToCount(dynamic_cast<const ParametricSurface&>(*t.surface), cell, params.cell > 0 ? 0 : params.faces);
      repairStars(t.triangulation, *t.surface);
    } else {
      LayingOptions lo;
      lo.method = params.method == TriangulationMethod::Progressive ? LayingMethod::Progressive : LayingMethod::Prespecified;
      lo.field = params.field;
      lo.cell = cell;
      lo.lowerBound = params.lowerBound;
      lo.start = params.start;
      lo.baseDirection = params.direction;
      StartChoice choice;
      // With a cell given, the trial lays are sized by the faces that cell gives (about), not by the default
      // face count: a fine cell on an uploaded mesh had its trials laid at half its full size.
      const int trialSizing = params.cell > 0 ? int(std::lround(facesAtCell(*t.surface, cell))) : params.faces;
      // An upload under auto that no family of rows can be laid on (a base curve along an asymptotic direction)
      // is tiled by the global method instead (below).
      bool unlaid = false;
      // A closed upload whose Euler characteristic is not 0 (2 for a sphere, -4 for genus 3) carries no conjugate
      // network without singular points (Poincare-Hopf), so no single system of rows covers it: the trial lays,
      // which would only find that out (the genus-3 shared model at 3000 faces: 3.0 s, 0.7 s without them; the
      // car 1.9 s, 0.7 s), are skipped and the global method tiles it.
      const int euler = closedMesh && closedMesh->isClosed() ? closedMesh->eulerCharacteristic() : 0;
      const bool singularNetwork = given.method == TriangulationMethod::Auto && params.mesh && !lo.start && euler != 0;
      const bool principalAuto = given.method == TriangulationMethod::Auto && given.field == "principal" &&
                                 !params.direction && params.field == "principal";
      // Of the sections along the plan's longest extent and across it, the field of those bending more nearly one
      // way where the upload has an umbilic in its curved part (below); else nothing. Judged once (some 400 samples
      // each), when first asked.
      struct Sections {
        std::string field;
        Vec3 umbilic;
      };
      std::optional<std::optional<Sections>> sectionsJudged;
      auto sectionsInQuestion = [&]() -> const std::optional<Sections>& {
        if (!sectionsJudged) {
          const std::optional<Vec3> umbilic = umbilicWithinCurvedPart(*t.surface);
          const double along = umbilic ? sectionBendingMixed(*t.surface, 0) : 1.0;
          const double across = umbilic && along > 0 ? sectionBendingMixed(*t.surface, 90) : 1.0;
          sectionsJudged.emplace();
          if (std::min(along, across) < kSectionMixed)
            *sectionsJudged = Sections{across < along ? "section:90" : "section", *umbilic};
        }
        return *sectionsJudged;
      };
      // An upload under auto: one quick lay first (kQuickTrialFaces), where the trials would be larger.
      const bool quickFirst = given.method == TriangulationMethod::Auto && params.mesh && !lo.start && !singularNetwork &&
                              trialFacesFor(trialSizing) > kQuickTrialFaces;
      int quick = 0;
      int sectionSystems = -1;  // the systems of rows of a quick lay along plane sections (0: none laid; -1: none tried)
      auto quickSections = [&](const Sections& sections) {  // laid once, from the middle of the bounds as any quick lay
        if (sectionSystems < 0) {
          LayingOptions so = lo;
          so.field = sections.field;
          so.base = BaseFamily::Auto;
          sectionSystems = quickSystems(*t.surface, so, trialSizing, cancel);
        }
        return sectionSystems;
      };
      if (quickFirst) {
        quick = quickSystems(*t.surface, lo, trialSizing, cancel);
        if (quick > 1 && principalAuto)
          if (const std::optional<Sections>& sections = sectionsInQuestion())
            if (quickSections(*sections) == 1) quick = 0;
      }
      if (!lo.start && !singularNetwork && quick <= 1) {
        try {
          choice = chooseStart(*t.surface, lo, trialSizing, params.cell > 0, cancel);
        } catch (const Error& e) {
          if (e.code() != ErrorCode::CannotTile || given.method != TriangulationMethod::Auto || !params.mesh) throw;
          unlaid = true;
        }
        lo.start = choice.start;
        lo.base = choice.base;
      }
      if (!singularNetwork && principalAuto && choice.systems > 1) {
        if (const std::optional<Sections>& sections = sectionsInQuestion()) {
          LayingOptions so = lo;
          so.field = sections->field;
          so.start = params.start;
          so.base = BaseFamily::Auto;
          // On an upload the sections matter only where their rows take one system (several send it global
          // whichever field scores higher, below): where one quick lay along them takes several or cannot be
          // laid, as in the quick choice above, their trials are left out.
          StartChoice section;
          if (!(quickFirst && quickSections(*sections) != 1))
            section = chooseStart(*t.surface, so, trialSizing, params.cell > 0, cancel);
          if (section.quality > choice.quality) {
            std::ostringstream s;
            s << "rows along plane sections (field " << so.field << ") and their conjugate lines, not the curvature lines: "
                 "these turn around an umbilic (k1 = k2) near ("
              << sections->umbilic.x() << ", " << sections->umbilic.y() << ", " << sections->umbilic.z() << ") and took " << choice.systems
              << " systems of rows in the trial lays, the sections " << section.systems
              << "; scores with irregular vertices counted " << section.quality << " against " << choice.quality;
            section.note = section.note.empty() ? s.str() : section.note + "; " + s.str();
            choice = std::move(section);
            params.field = lo.field = so.field;
            t.field = params.field;
            lo.start = choice.start;
            lo.base = choice.base;
          }
        }
      }
      // Uploads under auto: where the trial lays took several systems of rows (no singularity-free conjugate
      // network covers the surface, §7: their seams leave irregular vertices and faces cut) or none could be laid,
      // the global method tiles the surface with singular vertices instead. On the shared free-form models at
      // 1500 faces it laid 5-13 points more hexagons, fewer nodes of four beams and no seams; where one system of
      // rows covers the upload (a wave roof, a cylinder, a plane, an ellipsoid) Method 2 stays: 100 % hexagons.
      const bool global = given.method == TriangulationMethod::Auto && params.mesh &&
                          (singularNetwork || quick > 1 || unlaid || choice.systems > 1 || choice.quality < kPoorTrial);
      auto layGlobal = [&](const std::string& why) {
        params.method = t.method = TriangulationMethod::Global;
        t.field.clear();
        t.triangulation = globalTriangulation(*t.surface, globalOptions(params, params.cell > 0 ? params.cell : 0, t.surface.get()), progress, cancel);
        repairStars(t.triangulation, *t.surface);
        surfaceNote += (surfaceNote.empty() ? "" : "; ") + why;
        t.globalBecause = why;
      };
      if (global) {
        std::ostringstream s;
        if (singularNetwork)
          s << "the upload is closed with Euler characteristic " << euler << " (genus " << (2 - euler) / 2
            << "), so every conjugate network on it has singular points (§7): it was tiled by the global method, with "
               "singular vertices instead of seams";
        else if (quick > 1)
          s << "a trial lay at about " << kQuickTrialFaces << " faces took " << quick
            << " systems of rows (no singularity-free conjugate network covers the upload, §7), so it was tiled by the "
               "global method, with singular vertices instead of seams";
        else if (unlaid)
          s << "no family of rows could be laid on the upload (§5.2), so it was tiled by the global method";
        else
          s << (choice.systems > 1 ? "the trial lays took " + std::to_string(choice.systems) +
                                         " systems of rows (no singularity-free conjugate network covers the upload, §7)"
                                   : "the trial lays scored poorly (they covered too little of the upload or left too "
                                     "many stars invalid)")
            << (sectionSystems == 0   ? " and a lay along plane sections could not be laid"
                : sectionSystems > 1 ? " and a lay along plane sections took " + std::to_string(sectionSystems) + " systems"
                                     : std::string())
            << ", so it was tiled by the global method, with singular vertices instead of seams";
        layGlobal(s.str());
      } else {
      const std::string& startNote = choice.note;
      const double trialCell = choice.trialCell, trialVertices = choice.trialVertices;
      // The trial lay from the chosen start already measured how far the vertex count misses the area estimate
      // (layers stopping short leave parts uncovered; ideal triangles along a conjugate network are not
      // equilateral, and on the uploaded wave roof they are so much smaller that the area estimate's cell gave
      // 18k vertices for 10k asked): when by more than 10 %, start from the cell it predicts, and the secant
      // below takes it as its first point, which saves a lay (the wave roof at 10k faces: one lay, not two).
      // If that cell cannot be laid, the area estimate's is, as without the trial. Analytic surfaces too: the
      // analytic wave roof laid 17.8k vertices for 10k asked from the area estimate's cell, then a second lay
      // (1077 -> 773 ms at 10k faces; the hyperboloid 1083 -> 575, the vase 991 -> 653).
      // The lays below are laid without the star repair, which only the kept one gets: a repair moves vertices
      // and opens a few boundary stars but hardly changes the count the lays are compared by (on the uploaded
      // bumps at 10k faces, three lays with repairs of about 0.1 s each).
      bool repaired = false, laid = false;
      auto layBare = [&] {
        LayingOptions bare = lo;
        bare.repairSweeps = 0;
        return layTriangulation(*t.surface, bare, progress, cancel);
      };
      bool fromTrial = params.cell == 0 && trialVertices > 0 && trialCell > cell &&
                       trialPredictsMiss(trialCell, trialVertices, cell, params.faces);
      if (choice.laid) {
        // The families were compared at full size (chooseStart): the winner's lay is this lay.
        fromTrial = params.cell == 0;
        lo.cell = choice.laidCell;
        t.triangulation = std::move(*choice.laid);
        choice.laid.reset();
        repaired = laid = true;
      } else if (fromTrial) {
        lo.cell = predictedCell(*t.surface, trialCell, trialVertices, params.faces, cell);
        try {
          t.triangulation = layBare();
        } catch (const Error& e) {
          if (e.code() != ErrorCode::CannotTile) throw;
          fromTrial = false;
          lo.cell = cell;
        }
      }
      // The start choice's lay is kept with a cell given too (it was laid a second time, the same).
      if (!fromTrial && !laid) t.triangulation = layBare();
      // Layers of ideal triangles are not equilateral, and they may leave parts of the surface uncovered, so
      // the vertex count (one hexagon each) differs from the area estimate. When a face count was asked for
      // and missed by more than 10 %, lay again (at most twice): first with the cell scaled by the square root
      // of the ratio, then by the exponent the two lays measured (a secant in log-log). The closest lay wins.
      auto miss = [&](const Triangulation& tr) {
        return std::abs(std::log(double(std::max<Eigen::Index>(tr.mesh.V.rows(), 1)) / params.faces));
      };
      double cells[3] = {lo.cell, 0, 0}, counts[3] = {double(t.triangulation.mesh.V.rows()), 0, 0};
      for (int attempt = 1; attempt < 3 && params.cell == 0 && miss(t.triangulation) > std::log(kCount); ++attempt) {
        double exponent = 2;  // vertices ~ cell^-2 on a fully covered surface
        if (attempt == 2 && counts[1] > 0 && counts[0] > 0 && std::abs(std::log(cells[1] / cells[0])) > 1e-3) {
          const std::optional<double> e =
              thirdLayExponent(cells[0], counts[0], cells[1], counts[1], std::exp(miss(t.triangulation)));
          if (!e) break;
          exponent = *e;
        } else if (attempt == 1 && fromTrial && counts[0] > 0 && std::abs(std::log(trialCell / cells[0])) > 1e-3)
          exponent = std::clamp(countExponent(cells[0], counts[0], trialCell, trialVertices), 0.5, 4.0);
        lo.cell = relayCell(cells[attempt - 1], counts[attempt - 1], params.faces, exponent, cell);
        cells[attempt] = lo.cell;
        if (facesAtCell(*t.surface, lo.cell) > kMaxFaces) break;
        Triangulation again;
        try {
          again = layBare();
        } catch (const Error& e) {
          if (e.code() != ErrorCode::CannotTile) throw;
          break;  // keep the lay that worked
        }
        counts[attempt] = double(again.mesh.V.rows());
        if (miss(again) < miss(t.triangulation)) t.triangulation = std::move(again), repaired = false;
      }
      if (!repaired) repairLaidTriangulation(t.triangulation, *t.surface, lo.repairSweeps, cancel);
      if (!startNote.empty()) t.triangulation.notes.insert(t.triangulation.notes.begin(), startNote);
      // Under auto, a lay of one system of rows that left part of the upload bare (rows stopping short of the
      // boundary or of each other) gives way to the global method, which covers the whole surface: uploaded
      // samples of the ellipsoid band and the elliptic paraboloid at 1000 / 10000 faces left holes 6.5 / 19.7
      // and 6.9 / 12.0 mean panel edges wide (the global method: 0.13 / 0.03 and 0.16 / 0.04, none or 5 faces
      // cut), the uploaded wave roof at 30k and 100k faces a strip (23 edges at 100k). Lays that end about an
      // edge short of the boundary (1-1.55 mean triangle edges: the cylinder, sphere, vase, hyperboloid, the
      // wave roof up to 10k faces) keep Method 2's all-hexagon rows.
      if (given.method == TriangulationMethod::Auto && params.mesh) {
        Vec3 at = Vec3::Zero();
        const double gap = bareGap(t.triangulation, *t.surface, &at);
        if (gap > kBareGap) {
          std::ostringstream s;
          s.precision(3);
          s << "Method 2's rows left the upload near (" << at.x() << ", " << at.y() << ", " << at.z() << ") " << gap
            << " mean triangle edges from any triangle (they stopped short there), so it was tiled by the global "
               "method, which covers it";
          layGlobal(s.str());
        }
      }
      }
    }
  }
  if (params.method == TriangulationMethod::Global && !checked && params.foldFlips) {
    std::optional<DualMesh> dual;
    std::optional<SolvedDual> solved;
    const FoldFlips f = flipFoldsAway(t.triangulation, *t.surface, params, progress, cancel, dual, solved);
    if (f.flips > 0 || f.collapses > 0 || f.aligned > 0 || f.drops > 0) {
      std::string note = "where the dual, solved with folds allowed, had faces crossing themselves (each such face would "
                         "otherwise be cut, making two nodes of four faces), " + std::to_string(f.aligned) +
                         " vertices were moved in line with a neighbour along the flatter principal direction, " +
                         std::to_string(f.collapses) + " merged with their neighbour along it and " +
                         std::to_string(f.flips) + " edges flipped" +
                         (f.drops > 0 ? ", " + std::to_string(f.drops) +
                                            " boundary vertices nearly on the chord between their neighbours dropped"
                                      : "") +
                         "; the stars around them repaired by moving " +
                         std::to_string(f.repair.moved) + " vertices within the surface";
      if (f.repair.flips > 0) note += " and flipping " + std::to_string(f.repair.flips) + " edges more";
      t.triangulation.notes.push_back(note);
    }
    if (dupinDual) dupinDual->dual = std::move(dual), dupinDual->folded = f.folded, dupinDual->solved = std::move(solved);
  }
  t.check = checked ? std::move(*checked) : checkTriangulation(t.triangulation, *t.surface);
  // A lay that covers next to nothing is no result to hand on (a hill laid from a tiny loop around its top:
  // 11 faces for 5000 asked, before further systems were seeded from there).
  if (t.check.coverage >= 0 && t.check.coverage < kMinCoverage)
    throw Error(ErrorCode::CannotTile,
                "the triangulation covers only " + std::to_string(int(std::round(100 * t.check.coverage))) +
                    " % of the surface (" + std::to_string(t.triangulation.mesh.F.rows()) +
                    " triangles): its layers stopped short. Try another direction field, method or start point");
  const bool partial = t.check.coverage >= 0 && t.check.coverage < 0.8;
  if (partial)
    t.triangulation.notes.push_back("the triangulation covers only " + std::to_string(int(std::round(100 * t.check.coverage))) +
                                    " % of the surface: its layers stopped short (see the notes above); another "
                                    "field, method or start point may cover more");
  if ((partial || t.triangulation.systems > 1) && t.field == "principal") {
    const std::optional<Vec3> umbilic = umbilicWithinCurvedPart(*t.surface);
    if (umbilic) {
      std::ostringstream s;
      s << "the principal directions turn around an umbilic (k1 = k2) near (" << umbilic->x() << ", "
        << umbilic->y() << ", " << umbilic->z() << "): the curvature lines have a singularity there, and §5.2's "
           "methods need a regular conjugate network (§7). Around a bump whose parabolic curve closes into a "
           "ring no such network exists; ";
      if (t.triangulation.systems > 1)
        s << "the rows were laid as " << t.triangulation.systems
          << " systems, each from its own base curve, with seams of irregular vertices where they meet";
      else
        s << "tile such a surface in patches, or choose a field without the singularity where there is one (e.g. "
             "param on a height field that is elliptic throughout)";
      t.triangulation.notes.push_back(s.str());
    }
  }
  if (const std::string note = uploadNote(t.surface.get()); !note.empty()) t.triangulation.notes.push_back(note);
  if (!surfaceNote.empty()) t.triangulation.notes.insert(t.triangulation.notes.begin(), surfaceNote);
  if (const auto* mesh = dynamic_cast<const MeshSurface*>(t.surface.get()); mesh && mesh->developable())
    t.triangulation.notes.push_back(
        "the uploaded mesh is a developable (one principal curvature under 1 % of the other nearly everywhere): "
        "that curvature is taken as 0, as on an analytic cylinder or cone, so the rows run along its rulings "
        "(§5.3), and the dual gives the vertices of each ruling one shared tangent plane, so its hexagons are "
        "quad-shaped and planar as laid (§3)");
  return t;
}

}  // namespace

namespace {

// The polygon through `ids` of `V` as a mesh of its own.
PolyMesh polygonAlone(const Points& V, const std::vector<int>& ids) {
  PolyMesh piece;
  piece.V.resize(static_cast<int>(ids.size()), 3);
  std::vector<int> local(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) piece.V.row(static_cast<int>(i)) = V.row(ids[i]), local[i] = static_cast<int>(i);
  piece.addFace(local);
  return piece;
}
double polygonPlanarity(const Points& V, const std::vector<int>& ids) { return facePlanarity(polygonAlone(V, ids), 0); }
// 1 when the polygon crosses itself (a triangle never does, unless degenerate), else 0.
double polygonCrosses(const Points& V, const std::vector<int>& ids) {
  return faceSelfIntersects(polygonAlone(V, ids), 0) ? 1.0 : 0.0;
}

// Boundary panels the solve leaves off planar (a panel closing a boundary fan where the boundary meets a
// parabolic curve can be left with no planar shape that does not fold) or crossing themselves (a quad whose
// edge points ended on either side of its triangle point), and interior faces crossing themselves, are cut
// in two along the diagonal that leaves the pieces simple and most nearly planar, in `r.hex` and `r.initial` alike; the dual's bookkeeping follows
// (both pieces belong to the same vertex). Where an interior face away from such panels is off planar too,
// and only a few interior faces are off in all (kFewInteriorOff, or one in kFewInteriorShare of the faces on
// a larger mesh), each of them is cut the same way: the solve
// stopped short there because only folding would make them planar (on the uploaded wave roof at 100k
// faces, a pentagon and two hexagons where a row along the boundary was resampled close to the parabolic
// curve: the pentagon needle-thin, the edge between the hexagons shrunk to nothing, every further step
// folding one of them). Those touching a panel are cut too: cutting only the panel left one there folded.
// Where more are off, only the crossing panels are cut (the solve may only be slow there) — unless it
// stalled (`stalled`, kStalledShare below), or the surface was laid in several systems of rows (`seams`): where systems meet, and where their rows run along
// a parabolic ring, the faces are not shaped for planarity and every one left off is cut (on the bumps at
// 2000 faces, 36 of 1963; the solve then reaches the tolerance instead of stalling at 3e-3). `resolve` says
// whether solving again can reach the tolerance: a face off planar was cut and no interior face away from
// the panels is left off uncut. With `crossingOnly` (after the last solve) only the crossing panels are cut.
constexpr std::size_t kFewInteriorOff = 8;
// The uploaded wave roof at 100k faces, its rows ending on the boundary, left 13 interior faces off planar
// at 1.3e-4 (0.013 % of its faces), where it had left 5 with its rows stopping short of the boundary.
constexpr std::size_t kFewInteriorShare = 5000;
// Rounds of cuts and solves: two, and on a surface of several systems four (each solve can stall at faces
// the previous one left shaped for folding: the bumps at 8000 faces stopped at 1e-7 after two).
constexpr int kSeamRounds = 4;
// A solve that stalled (it stopped before its iteration cap, short of the tolerance) cannot get further
// from where it is: its faces off planar are cut wherever they are at most one in kStalledShare of the
// faces, on any surface, with as many rounds as on seams. The uploaded cyclide laid at cell 0.23 (909
// faces, 13 invalid stars left by the coarse lay) stalled at 9e-5 with 19 of its faces off planar; cut,
// it converges. (A solve stopped by the cap is only slow there: it keeps the few-faces rule.)
constexpr std::size_t kStalledShare = 20;
// On seams, every face left off planar is cut as long as all the cuts together stay within PipelineParams::cutShare
// of the faces (default a tenth; the bumps cut 2-4 %). Method 1 forced onto a cone laid two systems of layers whose
// Dupin dual no solve could make planar: without the budget four rounds cut 5676 interior faces of 5420, cutting the
// pieces again, and left a mesh of 6883 triangles.
std::size_t cutBudget(std::size_t uncut, double share) {
  // (At the default share, a tenth, this is uncut / 10: the fixed budget it replaced.)
  return static_cast<std::size_t>(std::floor(static_cast<double>(uncut) * share + 1e-9));
}
// Of two solves from the two duals that both stopped short of the tolerance, the one with fewer interior faces
// cut is kept where the counts differ by more than one face in this many; else the one nearer planar. Kept by
// planarity alone, the tangent dual's solve won on four of the five shared models the global method tiles
// short of the tolerance at 3000 faces, having cut 274-609 faces (8-17 % of them, each cut making two nodes of
// four faces) for a planarity 1.2-4.5 times lower, where the Dupin dual's cut 1-6 (60-76 % hexagons against
// 89-92 %).
constexpr std::size_t kCutsApart = 100;
// An interior face off planar is cut only where it is at least this share as far off as the worst one: the
// faces nearer planar still mostly reach planarity in the next solve, once the worst are cut. Cutting every
// face off planar after the first solve of the uploaded bumps at 10k faces cut 177 (half of them 1e-9 to
// 2e-7 off, against 8e-4 for the worst); with this share 123, for 90.3 % hexagons instead of 89.4 %. Over
// the 192-run sweep 29 runs changed, 28 with more hexagons (the bumps and the uploaded cyclide, +1.3 points
// on average) and none over the distance goal; at 0.03 the bumps at 6000 faces went 0.08 % -> 0.23 % off.
constexpr double kCutBelowWorst = 0.01;
// Of two diagonals, one whose ends are already corners of more than three faces is taken only where it leaves
// the pieces this much nearer planar (per such end), so that cuts spread rather than pile up at a vertex.
constexpr double kCrowdedCut = 1.0;
struct PanelCut {
  int panels = 0, interior = 0;  // boundary panels and interior faces cut
  bool resolve = false;
  bool stalledRule = false;  // interior faces were cut only because the solve stalled (kStalledShare)
};
// The faces of `r` before any cut (each cut made one face two).
std::size_t facesBeforeCuts(const PipelineResult& r) {
  return static_cast<std::size_t>(r.hex.faceCount() - r.interiorFacesSplit - r.boundaryPanelsSplit);
}
PanelCut splitBoundaryPanels(PipelineResult& r, double tolerance, bool crossingOnly, bool seams, bool stalled,
                             double cutShare) {
  // The faces before any cut, and the interior faces cut so far: the seams' and the stall's cuts are budgeted
  // over all rounds together.
  const std::size_t uncut = facesBeforeCuts(r);
  const std::size_t cutSoFar = static_cast<std::size_t>(r.interiorFacesSplit);
  std::vector<char> cut(r.hex.faceCount(), 0), crossing(r.hex.faceCount(), 0), held(r.hex.V.rows(), 0);
  std::vector<double> planarity(r.hex.faceCount());
  std::vector<int> interiorOff;
  int count = 0;
  bool offPlanarCut = false;
  for (int f = 0; f < r.hex.faceCount(); ++f) {
    planarity[f] = facePlanarity(r.hex, f);
    const bool offPlanar = planarity[f] > tolerance;
    const bool boundaryPanel = r.dual.boundaryFace[f] && r.hex.faceSize(f) >= 4;
    // So is an interior face the dual left crossing itself (untangleDual could not mend it): the solve never
    // unfolds it, and cut it may become two simple pieces.
    crossing[f] = r.hex.faceSize(f) >= 4 && faceSelfIntersects(r.hex, f);
    if (!offPlanar && !crossing[f]) continue;
    if (!boundaryPanel) {
      interiorOff.push_back(f);
      continue;
    }
    cut[f] = 1, ++count;
    offPlanarCut = offPlanarCut || offPlanar;
    for (int k = 0; k < r.hex.faceSize(f); ++k) held[r.hex.face(f)[k]] = 1;
  }
  bool away = false;  // an interior face off planar away from the panels
  for (int f : interiorOff) {
    bool touches = false;
    for (int k = 0; k < r.hex.faceSize(f); ++k) touches = touches || held[r.hex.face(f)[k]];
    away = away || !touches;
  }
  int interior = 0;
  bool stalledRule = false;
  const std::size_t fewOff = std::max(kFewInteriorOff, static_cast<std::size_t>(r.hex.faceCount()) / kFewInteriorShare);
  const bool few = (seams && cutSoFar + interiorOff.size() <= cutBudget(uncut, cutShare)) || interiorOff.size() <= fewOff ||
                   (stalled && cutSoFar + interiorOff.size() <= uncut / kStalledShare);
  if (crossingOnly || (away && !few)) {  // only the crossing panels (and faces)
    count = 0;
    for (int f = 0; f < r.hex.faceCount(); ++f) {
      cut[f] = crossing[f];
      if (crossing[f]) ++(r.dual.boundaryFace[f] ? count : interior);
    }
  } else if (away || (seams && few && !interiorOff.empty())) {
    // Faces far nearer planar than the worst are left to the next solve (kCutBelowWorst).
    double worst = 0;
    for (int f : interiorOff) worst = std::max(worst, planarity[f]);
    for (int f : interiorOff)
      if (crossing[f] || planarity[f] >= kCutBelowWorst * worst) cut[f] = 1, ++interior;
    stalledRule = !seams && interiorOff.size() > fewOff;
  }
  // An interior face crossing itself is cut whatever else is: the solve never unfolds it. (Next to a cut
  // panel it was left whole: the uploaded cyclide at 122 faces kept a planar pentagon crossing itself.)
  for (int f : interiorOff)
    if (crossing[f] && !cut[f]) cut[f] = 1, ++interior;
  if (count + interior == 0) return {};
  std::vector<int> faces(r.hex.V.rows(), 0);  // faces at each vertex, cuts so far included
  for (int f = 0; f < r.hex.faceCount(); ++f)
    for (int k = 0; k < r.hex.faceSize(f); ++k) ++faces[r.hex.face(f)[k]];
  PolyMesh hex;  // the new faces; r.initial (and the dual's copy of it) take the same ones
  hex.V = r.hex.V;
  std::vector<int> faceVertex;
  std::vector<std::uint8_t> boundary;
  for (int f = 0; f < r.hex.faceCount(); ++f) {
    const std::vector<int> ids(r.hex.face(f), r.hex.face(f) + r.hex.faceSize(f));
    std::vector<std::vector<int>> parts;
    if (cut[f]) {
      const int n = static_cast<int>(ids.size());
      double best = std::numeric_limits<double>::infinity();
      for (int i = 0; i < n; ++i)
        for (int j = i + 2; j < n; ++j) {
          if (i == 0 && j == n - 1) continue;
          std::vector<int> a(ids.begin() + i, ids.begin() + j + 1), b(ids.begin() + j, ids.end());
          b.insert(b.end(), ids.begin(), ids.begin() + i + 1);
          const double crossing = polygonCrosses(r.hex.V, a) + polygonCrosses(r.hex.V, b);
          const double crowded = (faces[ids[i]] > 3) + (faces[ids[j]] > 3);
          const double score =
              crossing + (1 + kCrowdedCut * crowded) * std::max(polygonPlanarity(r.hex.V, a), polygonPlanarity(r.hex.V, b));
          if (score < best) best = score, parts = {a, b};
        }
      ++faces[parts[0].front()], ++faces[parts[0].back()];
    } else {
      parts = {ids};
    }
    for (const std::vector<int>& part : parts) {
      hex.addFace(part);
      faceVertex.push_back(r.dual.faceVertex[f]);
      boundary.push_back(r.dual.boundaryFace[f]);
    }
  }
  r.initial.offsets = hex.offsets;
  r.initial.indices = hex.indices;
  r.dual.mesh = r.initial;
  r.hex = std::move(hex);
  r.dual.faceVertex = std::move(faceVertex);
  r.dual.boundaryFace = std::move(boundary);
  return {count, interior, !crossingOnly && (offPlanarCut || interior > 0) && (!away || few), stalledRule};
}

// Boundary panels cut in two (splitBoundaryPanels: off planar or crossing themselves), dropped before the clip
// together with their pieces: the cut's inner end, a node of four faces with both pieces, is a node of two on the
// outline without them, which the clip moves along the edge it keeps to the boundary curve (with a filler where that
// edge runs along the curve), as it does every node of two panels; so the edge as drawn still follows the curve, one
// panel in, and no node of four faces is left there. Only where the mesh stays a manifold (each of their nodes still
// on faces ends two outline edges). Returns the panels dropped; `mesh` and `dual`'s face arrays lose them (their nodes
// stay until the clip renumbers), and the faces then on the outline are marked boundary faces.
struct CutPanelsDropped {
  int panels = 0;
  int cuts = 0;  // the cuts that made their pieces (a piece cut again: two)
};
// How much farther (in mean edges) the edge as drawn and the boundary nodes may end from the boundary curve with the
// cut panels left out than with them (the pipeline's clip).
constexpr double kCutDroppedGap = 0.25;
CutPanelsDropped dropCutPanels(PolyMesh& mesh, DualMesh& dual) {
  const int F = mesh.faceCount();
  CutPanelsDropped out;
  if (static_cast<int>(dual.faceVertex.size()) != F || static_cast<int>(dual.boundaryFace.size()) != F) return out;
  std::unordered_map<int, int> piecesOf;  // dual vertex -> its faces among the boundary panels
  for (int f = 0; f < F; ++f)
    if (dual.boundaryFace[f] && dual.faceVertex[f] >= 0) ++piecesOf[dual.faceVertex[f]];
  std::vector<char> drop(static_cast<std::size_t>(F), 0);
  for (int f = 0; f < F; ++f) drop[f] = dual.boundaryFace[f] && dual.faceVertex[f] >= 0 && piecesOf[dual.faceVertex[f]] > 1;
  // Of cut panels that share a node, only the first (in face order) is left out: where cut panels stand side by side
  // (the helicoid, its rims near its asymptotic directions, at 3800 faces cut most of them) the clip cannot take
  // the panels behind them to the curve (its boundary nodes 1.4 edges off).
  std::vector<int> owner(static_cast<std::size_t>(mesh.V.rows()), -1);  // the first cut panel (dual vertex) at a node
  std::unordered_set<int> crowded;
  for (int f = 0; f < F; ++f)
    for (int i = 0; drop[f] && i < mesh.faceSize(f); ++i) {
      int& o = owner[mesh.face(f)[i]];
      if (o < 0) o = dual.faceVertex[f];
      else if (o != dual.faceVertex[f]) crowded.insert(dual.faceVertex[f]);
    }
  std::unordered_set<int> panels;
  for (int f = 0; f < F; ++f) {
    if (drop[f] && crowded.count(dual.faceVertex[f])) drop[f] = 0;
    if (drop[f]) panels.insert(dual.faceVertex[f]);
  }
  if (panels.empty()) return out;
  PolyMesh rest;
  rest.V = mesh.V;
  std::vector<int> restOf;
  for (int f = 0; f < F; ++f)
    if (!drop[f]) rest.addFace(std::vector<int>(mesh.face(f), mesh.face(f) + mesh.faceSize(f))), restOf.push_back(f);
  if (restOf.empty()) return out;
  // Still a manifold: every node of a dropped panel still on faces ends two outline edges.
  const std::vector<std::pair<int, int>> outline = outlineEdges(rest);
  std::vector<int> ends(static_cast<std::size_t>(mesh.V.rows()), 0), on(ends.size(), 0);
  for (const auto& [a, b] : outline) ++ends[a], ++ends[b];
  for (int id : rest.indices) ++on[id];
  for (int f = 0; f < F; ++f)
    for (int i = 0; drop[f] && i < mesh.faceSize(f); ++i)
      if (const int v = mesh.face(f)[i]; on[v] > 0 && ends[v] != 2) return out;
  // The faces now on the outline are boundary panels (clipped as such, and not counted among the interior faces).
  auto key = [](int a, int b) { return (std::uint64_t(std::min(a, b)) << 32) | std::uint32_t(std::max(a, b)); };
  std::unordered_set<std::uint64_t> onOutline;
  for (const auto& [a, b] : outline) onOutline.insert(key(a, b));
  std::vector<int> faceVertex;
  std::vector<std::uint8_t> boundaryFace;
  for (int k = 0; k < rest.faceCount(); ++k) {
    const int f = restOf[k];
    faceVertex.push_back(dual.faceVertex[f]);
    boundaryFace.push_back(dual.boundaryFace[f]);
    for (int i = 0, n = rest.faceSize(k); i < n; ++i)
      if (onOutline.count(key(rest.face(k)[i], rest.face(k)[(i + 1) % n]))) boundaryFace.back() = 1;
  }
  dual.faceVertex = std::move(faceVertex);
  dual.boundaryFace = std::move(boundaryFace);
  mesh = std::move(rest);
  out.cuts = F - static_cast<int>(restOf.size()) - static_cast<int>(panels.size());
  out.panels = static_cast<int>(panels.size());
  return out;
}

}  // namespace

// Mesh vertices per lay vertex from which an uploaded surface laid in several systems starts from the tangent
// dual (runPipeline).
constexpr Eigen::Index kTangentSampling = 4;

namespace {

// Reached a P-Hex mesh: converged, no face crossing itself, no node far off (the command line's exit 0).
bool reached(const PipelineResult& r) {
  return r.solve.converged && r.metrics.selfIntersectingCount == 0 && r.farNodes == 0;
}
// The nodes of four faces r's cuts made: two per interior face cut, one per boundary panel (its other end on the
// boundary). A cut boundary panel left out before the clip (dropCutPanels) counts as its node still: the lays are
// weighed as they were before panels were left out (a lay without the cut clips closer to the curve: a steep dome's
// trial lay for 97 % of the faces, uncut, 0.08 edges off where the first lay with its two cut panels left out was 0.72).
int nodesOfFourCut(const PipelineResult& r) {
  return 2 * r.interiorFacesSplit + r.boundaryPanelsSplit + r.boundaryClip.cutDropped;
}

// One lay and solve of `params` (runPipeline lays the global method twice where the first falls short).
PipelineResult runOnce(const PipelineParams& params, const ProgressFn& progress, const CancelFlag* cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  PipelineResult r;
  r.solverUsed = params.solver;
  StageClock clock(r.timings);
  auto report = [&](const char* stage, double fraction, const std::string& msg) {
    checkCancel(cancel);
    if (progress) progress({stage, fraction, msg});
  };

  report("triangulate", 0, "laying the triangulation");
  StageDual stageDual;  // the Dupin dual, where the triangulation stage built it
  TriangulationStage stage = triangulateLocal(params, progress, cancel, &stageDual);
  r.method = stage.method;
  r.field = stage.field;
  r.globalBecause = stage.globalBecause;
  r.surface = std::move(stage.surface);
  r.surfaceReused = stage.surfaceReused;
  r.origin = stage.origin;
  r.triangulation = std::move(stage.triangulation);
  r.check = std::move(stage.check);
  const Surface& surface = *r.surface;
  clock.done("triangulate");

  PlanarizeOptions po = planarizeOptions(params, r.method, surface);
  // The global method's lattice has no seams, but where the solve leaves faces off planar (next to parabolic curves
  // and the lattice's defects, §7) they are cut as on seams, within the same budget: on the shared models the
  // few-faces rule left the solve stalled at 1e-2 with hundreds of faces just off planar.
  const bool seams = r.triangulation.systems > 1 || r.method == TriangulationMethod::Global;
  // The stage's Dupin dual as flipFoldsAway solved it (folds allowed, no fit), where dualOf hands that dual on:
  // solveFrom takes it instead of solving it again where its options are those (the unguarded solve of the global
  // method; the same mesh, one solve fewer: the bench's upload at 10k faces ~35 ms, at 100k ~1 s).
  std::optional<SolvedDual> presolved;
  auto dualOf = [&](Duality duality) {
    report("dualize", 0, std::string(dualityName(duality)) + " duality");
    // The stage's Dupin dual serves once (a second Dupin solve, rare, builds it again rather than keep it).
    std::optional<DualMesh> taken;
    if (duality == Duality::Dupin) taken.swap(stageDual.dual), presolved.reset(), presolved.swap(stageDual.solved);
    DualMesh dual = duality == Duality::Tangent ? tangentDual(r.triangulation, surface)
                    : taken                       ? std::move(*taken)
                                                  : dupinDual(r.triangulation, surface);
    clock.done("dualize");
    return dual;
  };
  auto crossing = [](const PolyMesh& m) {
    const std::vector<char> crosses = selfIntersectingFaces(m);
    return static_cast<int>(std::count(crosses.begin(), crosses.end(), char(1)));
  };
  // The global method's solves fit the planes to the surface once, after their last round of cuts, instead of
  // after every round (whose fitted positions anchored the next round): the same meshes on the shared models at
  // 1500 and 3000 faces, the bumps and the torus, but six_s0 at 1500 faces converged (0.66 % off the surface
  // instead of 2.1 %) and the uploaded bumps at 10k faces planarized in 0.90 s instead of 1.31 s (one fit of
  // ~90 ms instead of five). Method 2's bumps at 1000 faces cut twice the faces so: the paper's methods fit
  // after every round still.
  const bool deferFit = r.method == TriangulationMethod::Global;
  // The largest node move of x's solve from its dual, over the mean edge.
  auto measureDisplacement = [](PipelineResult& x) {
    const double h = x.hex.meanEdgeLength();
    if (h > 0) x.solve.displacementMax = (x.hex.V - x.initial.V).rowwise().norm().maxCoeff() / h;
  };
  // `dual` (of `duality`) into x.dual / x.initial, and the solve from it into x.hex / x.solve. Returns whether
  // interior faces were cut only because a solve stalled (kStalledShare).
  auto solveFrom = [&](PipelineResult& x, Duality duality, DualMesh dual) {
    bool stalledCuts = false;
    x.duality = duality;
    x.dual = std::move(dual);
    x.initial = x.dual.mesh;
    report("planarize", 0, "planarity optimization");
    x.hex = x.initial;
    PlanarizeOptions o = po;
    o.fitSurface = po.fitSurface && !deferFit;
    std::optional<SolvedDual> given;
    given.swap(presolved);  // valid for the dual just taken alone
    if (given && duality == Duality::Dupin && o.method == PlanarizeMethod::LocalGlobal && !o.preventFolds && !o.fitSurface &&
        given->hex.faceCount() == x.hex.faceCount()) {
      x.hex = std::move(given->hex);
      x.solve = std::move(given->report);
    } else {
      x.solve = planarize(x.hex, o, progress, cancel);
    }
    // Boundary panels that stay off planar or cross themselves (and a few interior faces left off planar) are
    // cut in two and the solve goes on from there (twice at most, four times on a surface of several
    // systems); after the last solve, panels it left crossing themselves are cut once more.
    int lastSolve = x.solve.iterations;  // iterations of the latest solve alone
    // Stopped short of the tolerance before its iteration cap.
    auto stalled = [&] { return !x.solve.converged && lastSolve < po.maxIterations; };
    const int last = seams || stalled() ? kSeamRounds : 2;
    for (int round = 0; round <= last && params.splitBoundaryPanels; ++round) {
      const PanelCut cut = splitBoundaryPanels(x, po.tolerance, round == last, seams, stalled(), params.cutShare);
      x.boundaryPanelsSplit += cut.panels;
      x.interiorFacesSplit += cut.interior;
      stalledCuts = stalledCuts || cut.stalledRule;
      if (!cut.resolve || round == last) {
        // The pieces of a face cut for crossing itself may cross themselves still (no diagonal of it left
        // both simple): they are cut again, down to triangles at worst, which cannot.
        for (int again = 0; again < 3 && crossing(x.hex) > 0; ++again) {
          const PanelCut more = splitBoundaryPanels(x, po.tolerance, true, seams, false, params.cutShare);
          x.boundaryPanelsSplit += more.panels;
          x.interiorFacesSplit += more.interior;
          if (more.panels + more.interior == 0) break;
        }
        break;
      }
      // Again from lambda = 1, now anchored at the positions reached (starting at the small lambda the first
      // solve ended with took as long on the uploaded wave roof at 10k faces, 12 iterations against 14).
      const PlanarizeReport first = x.solve;
      x.solve = planarize(x.hex, o, progress, cancel);
      lastSolve = x.solve.iterations;
      x.solve.iterations += first.iterations;
      x.solve.rounds += first.rounds;
      x.solve.initialPlanarityMax = first.initialPlanarityMax;
      x.solve.log.insert(x.solve.log.begin(), first.log.begin(), first.log.end());
      measureDisplacement(x);
    }
    if (po.fitSurface && deferFit && x.solve.converged) {
      fitPlanarMeshToSurface(x.hex, po, x.solve, progress, cancel);
      measureDisplacement(x);
    }
    clock.done("planarize");
    return stalledCuts;
  };
  // Another solve's dual, meshes and counts into `r`.
  auto takeSolve = [&](PipelineResult&& t) {
    r.duality = t.duality;
    r.dual = std::move(t.dual);
    r.initial = std::move(t.initial);
    r.hex = std::move(t.hex);
    r.solve = std::move(t.solve);
    r.boundaryPanelsSplit = t.boundaryPanelsSplit;
    r.interiorFacesSplit = t.interiorFacesSplit;
  };
  // On a surface laid in several systems of rows the local solver starts from the tangent dual, whose faces
  // lie in the tangent planes: across the seams' irregular vertices the Dupin dual's faces leave more to fold
  // (the bumps over 18 sizes from 1000 to 20000 faces, analytic and uploaded: interior faces cut at 6000
  // faces 233 -> 87, hexagons 84.3 % -> 86.2 % and 83.7 % -> 85.3 % on average, better in 30 of 36 runs, none
  // folded, 3-5 % faster). On an uploaded mesh only where the lay is coarse beside it (a vertex for every
  // kTangentSampling of the mesh's or more): its tangent planes come from estimated normals, and on a lay
  // nearly as fine as the mesh they scatter — the uploaded bumps (61k vertices) from the tangent dual at 30k,
  // 50k and 100k faces: 90.6 %, 89.4 % and 80.8 % hexagons (9677 faces cut at 100k), 92.3 %, 93.1 % and
  // 93.9 % from the Dupin dual; at 20k about even.
  const MeshSurface* uploaded = dynamic_cast<const MeshSurface*>(&surface);
  const bool coarse = !uploaded || kTangentSampling * r.triangulation.mesh.V.rows() <= uploaded->vertexCount();
  // Not on the global method's triangulations, which have no seams of rows: from the Dupin dual first, the
  // analytic bumps (`--method global`) at 1000, 2000, 3000 and 5000 faces cut 27, 37, 47 and 77 interior faces
  // against 37, 52, 85 and 117 (0.5-1.6 points more hexagons), the cyclide at 3000 265 against 280 (its farthest
  // node 0.09 % of the diagonal off the surface against 0.47 %), the wave roof at 3000 1 against 15; the
  // helicoid cut more boundary panels (137 against 100 at 3000), none more interior faces.
  const bool tangentFirst = params.duality == Duality::Auto && seams && r.method != TriangulationMethod::Global && coarse &&
                            params.solver == PlanarizeMethod::LocalGlobal;
  const Duality asked = params.duality != Duality::Auto ? params.duality : tangentFirst ? Duality::Tangent : Duality::Dupin;
  // With the fairness (the global method's solves on a surface that is not a noisy upload), the solve with folds
  // allowed comes first: the faces it leaves crossing themselves are cut, and where it converges with none crossing
  // itself, within the seams' budget of cuts and the distance goal, it stands. From the guarded solve first, the
  // uploaded bumps at 10k faces stalled, and the tangent dual's solve and then the unguarded one ran after it:
  // planarize 231 -> 864 ms for the same mesh as the unguarded one alone gives in 118 ms. Over 40 runs of clean
  // surfaces the same figures within a few nodes of four (640 -> 669, hexagons 91.05 -> 91.00 %).
  const double diagonal = surface.bounds().diagonal().norm();
  auto offSurface = [&](const PipelineResult& x) {  // the largest node distance over the diagonal
    if (po.fitSurface && x.solve.converged) return x.solve.surfaceDistanceAfter;  // planarize measured it
    return diagonal > 0 ? largestSurfaceDistance(x.hex, surface) / diagonal : 0.0;
  };
  // A solve with folds allowed from `duality`'s dual (the run's options otherwise).
  auto solveUnguarded = [&](PipelineResult& x, Duality duality) {
    po.preventFolds = false;
    solveFrom(x, duality, dualOf(duality));
    po.preventFolds = true;
  };
  // Nodes farther off than this share of the distance goal are put back on the surface (putBack), at the price of
  // at most this many more interior faces cut. At 0.5 the generated genus 3 at 3000 faces had 23 nodes put back
  // (0.21 -> 0.17 % of the diagonal, but 12 more faces cut: the result past the goal was kept); at 0.75 fewer nodes
  // move and the solve from there cuts one more (0.19 %). Over the sweeps (40 clean runs, 48 perturbed; all
  // converged, none past the goal either way) interior + boundary faces cut 54+47 -> 51+47 and 101+52 -> 98+51,
  // nodes of four 153 -> 147 and 259 -> 256, hexagons the same; the shared models at 1500 and 3000 faces and the
  // bench's upload at 10k faces the same meshes, at 100k 184+46 -> 184+45 cut. (At 1.0: 53+44 and 97+50 cut.)
  constexpr double kPulledBack = 0.75;
  constexpr int kPutBackCuts = 5;
  constexpr double kPutBackLambda = 1e-3;
  // x's nodes farther off than kPulledBack of the distance goal put back on the surface (their closest points), and
  // the mesh solved again from there as from a dual (guarded, cutting what stays off planar, fitted); the cuts,
  // iterations and the dual as laid carried over from x. A repair of a few nodes in a mesh planar elsewhere: its
  // solve starts at kPutBackLambda of the run's lambda (the closeness to where the nodes were put), without the
  // fairness, which pulls every node towards its neighbours and the whole mesh off planar again. With both as in a
  // solve from the dual, the bench's upload at 100k faces (one node put back, 0.22 % of the diagonal off) stalled
  // guarded and cut 716 faces more; now 3 nodes put back, 2 faces more cut, 0.17 % off; the bubble at 2000 faces
  // 0.29 % -> 0.08 % with no face more cut, where the solve from there had stalled.
  auto putBack = [&](const PipelineResult& x) {
    DualMesh from = x.dual;  // its faces as cut
    from.mesh = x.hex;
    for (int v = 0; v < from.mesh.V.rows(); ++v) {
      const Vec3 p = from.mesh.V.row(v).transpose();
      const LocalGeometry g = surface.closestPoint(p);
      if ((g.point - p).norm() > kPulledBack * kSurfaceDistanceGoal * diagonal) from.mesh.V.row(v) = g.point.transpose();
    }
    PipelineResult again;
    const PlanarizeOptions full = po;
    po.lambda *= kPutBackLambda;
    po.fairness = 0;
    solveFrom(again, x.duality, std::move(from));
    po = full;
    again.interiorFacesSplit += x.interiorFacesSplit;
    again.boundaryPanelsSplit += x.boundaryPanelsSplit;
    again.solve.iterations += x.solve.iterations;
    again.initial.V = x.initial.V;  // the dual as laid, not the mesh put back (cuts add no vertex)
    return again;
  };
  // Whether putBack's result `again` cut at most kPutBackCuts (and one in 1000) more interior faces than `x`.
  auto fewMoreCuts = [&](const PipelineResult& again, const PipelineResult& x) {
    return again.interiorFacesSplit <= x.interiorFacesSplit + kPutBackCuts + static_cast<int>(facesBeforeCuts(x) / 1000);
  };
  // Whether x's interior faces cut stay within the run's share of cuts.
  auto withinCutShare = [&](const PipelineResult& x) {
    return static_cast<std::size_t>(x.interiorFacesSplit) <= cutBudget(facesBeforeCuts(x), params.cutShare);
  };
  bool settled = false;
  // The solve with folds allowed from the Dupin dual where it did not stand: the unguarded solve below, from the
  // same dual with the same options, is this one (the bench's upload at 100k faces: planarize 17.1 -> 13.9 s, the
  // same mesh).
  std::optional<PipelineResult> unguardedDupin;
  if (r.method == TriangulationMethod::Global && po.fairness > 0 && params.preventFolds &&
      params.solver == PlanarizeMethod::LocalGlobal && params.duality == Duality::Auto) {
    PipelineResult t;
    solveUnguarded(t, Duality::Dupin);
    auto stands = [&](const PipelineResult& x) {
      return x.solve.converged && crossing(x.hex) == 0 && withinCutShare(x);
    };
    // Where it stands but for a few nodes past the distance goal (three planes through nearly one line), those are
    // put back on the surface and solved again from there, as a converged result is below, and kept where that
    // stands within the goal with at most kPutBackCuts more interior faces cut (and one in 1000): the bench's upload
    // at 100k faces, whose guarded solves from the dual (stalled, then the tangent dual's) took 14 s for the same
    // mesh 0.22 % of the diagonal off.
    if (stands(t) && offSurface(t) > kSurfaceDistanceGoal) {
      PipelineResult again = putBack(t);
      if (stands(again) && offSurface(again) <= kSurfaceDistanceGoal && fewMoreCuts(again, t))
        t = std::move(again);
    }
    if (stands(t) && offSurface(t) <= kSurfaceDistanceGoal) {
      takeSolve(std::move(t));
      r.foldsAllowed = true;
      settled = true;
    } else {
      unguardedDupin = std::move(t);
    }
  }
  const bool firstStalled = settled ? false : solveFrom(r, asked, dualOf(asked));
  // Where the solve from the Dupin dual stalls short of the tolerance or leaves faces crossing themselves,
  // the tangent dual (§4.1) is tried as well: its faces lie in the tangent planes at their vertices, so on
  // a triangulation along a conjugate network it is planar as it stands (the cyclide's lattice at 3000 to
  // 13000 faces, where the solve from the Dupin dual stalls at 2e-8 to 2e-7). The one with fewer faces
  // crossing themselves, then the converged one, then (both converged) the one with fewer interior faces
  // cut, then the lower planarity, is kept; `duality` says which. A Dupin solve that reached the tolerance
  // only by the cuts a stall allows counts as stalled here: the tangent dual may need none (the cyclide's
  // lattice at 3000 faces: 0 iterations and no cut, where the Dupin dual needed 20 faces cut). From the
  // tangent dual first (tangentFirst), the Dupin dual is the one tried as well, alike.
  // A solve that converged clean but left a node past the distance goal (kSurfaceDistanceGoal) is tried from
  // the other dual too, whose panels meet in other nodes: the uploaded bumps at 1000 faces, from the tangent
  // dual 0.212 % of the diagonal off (every surface fit folds faces at the farthest node), from the Dupin dual
  // 0.170 %, with 25 interior faces cut against 30. That one is kept where it converges with no face crossing
  // itself and meets the goal, or comes closer without cutting more. (Duality::Auto only.)
  if (params.duality == Duality::Auto) {
    const int crossed = crossing(r.hex);
    const bool far = r.solve.converged && crossed == 0 && !firstStalled && offSurface(r) > kSurfaceDistanceGoal;
    // The Ceres solvers take seconds to minutes: with them, only a tangent dual planar as it stands is tried.
    auto planarAsItStands = [&](const DualMesh& dual) {
      for (int f = 0; f < dual.mesh.faceCount(); ++f)
        if (!(facePlanarity(dual.mesh, f) <= po.tolerance)) return false;
      return true;
    };
    const Duality other = asked == Duality::Dupin ? Duality::Tangent : Duality::Dupin;
    std::optional<DualMesh> second;
    if (!r.solve.converged || crossed > 0 || firstStalled || far) second = dualOf(other);
    if (second && (params.solver == PlanarizeMethod::LocalGlobal || planarAsItStands(*second))) {
      PipelineResult t;
      solveFrom(t, other, std::move(*second));
      const int otherCrossed = crossing(t.hex);
      // Neither converged: the one that cut fewer interior faces, where the two differ by more than one face in
      // kCutsApart (each cut makes two nodes of four faces, and neither result is planar anyway).
      const int cutsApart = std::abs(t.interiorFacesSplit - r.interiorFacesSplit);
      const bool fewerCuts =
          t.solve.converged ? t.interiorFacesSplit != r.interiorFacesSplit
                            : cutsApart > static_cast<int>(facesBeforeCuts(r) / kCutsApart);
      bool better =
          otherCrossed != crossed                          ? otherCrossed < crossed
          : t.solve.converged != r.solve.converged           ? t.solve.converged
          : fewerCuts                                        ? t.interiorFacesSplit < r.interiorFacesSplit
                                                             : t.solve.planarityMax < r.solve.planarityMax;
      if (far) {
        const double off = offSurface(t);
        better = t.solve.converged && otherCrossed == 0 &&
                 (off <= kSurfaceDistanceGoal || (off < offSurface(r) && t.interiorFacesSplit <= r.interiorFacesSplit));
      }
      if (better) takeSolve(std::move(t));
    }
  }

  // Interior faces cut by a converged guarded solve against its dual's folds that send the global method's
  // triangulation to an unguarded solve as well (below), and how much farther from the surface the unguarded one
  // may then end.
  constexpr double kManyCutsRatio = 1.0, kManyCutsMore = 2, kFewerCutsFarther = 1.6;
  // ... or boundary panels cut, over this share of the boundary faces (a panel cut in two counts as its two pieces):
  // a boundary along asymptotic lines, where no boundary panel is planar without folding. On the uploaded bumps at
  // 10k faces 41 of about 400 are cut, and counting them with the interior faces sent it unguarded for 150 ms and
  // no node of four fewer.
  constexpr double kManyPanelsCut = 0.25;
  // A guarded solve that stalled may reach the tolerance unguarded with no face left crossing itself: the
  // guard refuses every step that would make a simple face cross itself, also where the faces only pass
  // through such a shape on their way to planar ones. Method 1 on a cyclide patch past its parabolic circles
  // (uSpan 180, vSpan 260, 1500 faces: the test) stalls from both duals; unguarded it converges to 3e-13
  // with none crossing itself (73 interior faces cut, 1568 faces in all). Kept only then, and where the faces it cut
  // (every one that folded) stay within PipelineParams::cutShare (`foldsAllowed`); else the guarded result stands,
  // and says that it missed: Method 1 forced onto a cone cut 1865 of 697, and the torus laid across its
  // parabolic circles (Fig. 19's infeasible direction) 143 of 925. Ceres solvers have no guard.
  //
  // So also where the global method's guarded solve converged only by cutting many more interior faces than its
  // dual folds when solved unguarded (the fold rounds measured that: `stageDual.folded`): the guard stalled and
  // every face still off planar was cut, round after round, where the unguarded solve cuts the folded faces alone
  // (the botanic-garden bubble at 5000 faces, alignment 1.001: 121 interior faces cut guarded, 26 unguarded, 87.8 ->
  // 90.9 % hexagons, its farthest node 0.06 -> 0.19 % of the diagonal off). Kept where it cuts fewer and its farthest
  // node stays within the distance goal or the guarded one's distance, or within kFewerCutsFarther of that where it
  // cuts half as many or fewer (each cut face makes two nodes of four faces; the bumps upload at 5000 faces,
  // anisotropy 1.498: 111 -> 44 cut, 0.08 -> 0.27 %). The bubble at 3000 faces (anisotropy 1.499) cut 8 against 77,
  // but two nodes ended 2.2 % of the diagonal off; with the four nodes past half the goal put back on the surface
  // and solved again as from a dual (guarded, cutting what stays off planar) it converges with the same 8 cuts,
  // 0.08 % off (the bumps upload above then 0.09 %; the bubble at 5000 faces, anisotropy 1.503, 135 -> 29 cuts,
  // 87.1 -> 90.5 % hexagons, 0.05 % off, where the solve from the far nodes put back cut 7 more). On seven
  // orderings of the 40-run sweep, interior faces cut in the converged runs 1943 -> 1502 with both, none more.
  const auto boundaryFaces = std::count(r.dual.boundaryFace.begin(), r.dual.boundaryFace.end(), std::uint8_t{1});
  const bool manyCuts = r.solve.converged && r.method == TriangulationMethod::Global && stageDual.folded >= 0 &&
                        (r.interiorFacesSplit > kManyCutsRatio * stageDual.folded + kManyCutsMore ||
                         r.boundaryPanelsSplit > kManyPanelsCut * double(boundaryFaces));
  if (!settled && (!r.solve.converged || manyCuts) && params.preventFolds && params.solver == PlanarizeMethod::LocalGlobal) {
    PipelineResult t;
    if (asked == Duality::Dupin && unguardedDupin) t = std::move(*unguardedDupin);
    else solveUnguarded(t, asked);
    bool keep = t.solve.converged && crossing(t.hex) == 0;
    if (keep && manyCuts) {
      keep = nodesOfFourCut(t) < nodesOfFourCut(r);
      const double goal = std::max(kSurfaceDistanceGoal, offSurface(r));
      double off = keep ? offSurface(t) : 0.0;
      // Where it cuts fewer but ends farther off, its far nodes (three planes through nearly one line, which the
      // surface fit cannot move) are put back on the surface and the mesh solved again from there, guarded.
      if (keep && off > goal) {
        PipelineResult again = putBack(t);
        if (again.solve.converged && crossing(again.hex) == 0) {
          const double nearer = offSurface(again);
          if (nearer < off) t = std::move(again), off = nearer;
        }
      }
      keep = keep && nodesOfFourCut(t) < nodesOfFourCut(r) &&
             off <= goal * (2 * nodesOfFourCut(t) <= nodesOfFourCut(r) ? kFewerCutsFarther : 1.0);
    }
    if (keep && withinCutShare(t)) {
      takeSolve(std::move(t));
      r.foldsAllowed = true;
    } else if (const std::size_t before = facesBeforeCuts(t); keep && !r.solve.converged && before > 0) {
      const std::size_t cuts = static_cast<std::size_t>(t.interiorFacesSplit);
      // Planar, none crossing itself, but over the budget of cuts: the share that would keep it, rounded up to a
      // hundredth, named for the caller.
      const double share = std::ceil(100.0 * static_cast<double>(cuts) / static_cast<double>(before)) / 100.0;
      std::ostringstream n;
      n << "the solve with folds allowed reached the tolerance with no face crossing itself by cutting " << cuts
        << " interior faces in two (" << std::lround(100.0 * cuts / before) << " % of the faces, each cut making two "
        << "nodes of four faces), over the share of cuts allowed (cutShare " << params.cutShare
        << "); with cutShare " << share << " or more the run keeps a planar mesh (this one, or one the guarded solve "
        << "reaches with fewer cuts)";
      r.triangulation.notes.push_back(n.str());
    }
  }

  // A converged result of the global method whose farthest node is past the distance goal, with no face crossing
  // itself: its far nodes are put back on the surface and it is solved again from there, and kept where that
  // converges with none crossing itself, nearer, and at most kPutBackCuts more interior faces cut (and one in
  // 1000). Such nodes sit where three planes pass through nearly one line, which the surface fit cannot move. On
  // seven orderings of the 40-run sweep the converged runs past the goal went 13 -> 0 for 13 more interior faces
  // cut (1502 -> 1515); the bubble at 1000 and 2000 faces 0.42 -> 0.10 % and 0.51 -> 0.07 % of the diagonal (0 and
  // 1 more cut), the bumps upload at 1000 and 5000 0.22 -> 0.15 % and 0.25 -> 0.07 % (1 and 0).
  if (r.solve.converged && r.method == TriangulationMethod::Global) {
    const double off = offSurface(r);
    if (off > kSurfaceDistanceGoal && crossing(r.hex) == 0) {
      PipelineResult again = putBack(r);
      if (again.solve.converged && crossing(again.hex) == 0 && offSurface(again) < off && fewMoreCuts(again, r))
        takeSolve(std::move(again));
    }
  }

  if (params.clipBoundary && !surface.isClosed()) {  // (closed: no boundary curve)
    report("clip", 0, "clipping the boundary panels to the boundary curve");
    const PolyMesh unclipped = r.hex;
    const std::vector<std::uint8_t> boundaryFace = r.dual.boundaryFace;
    const std::vector<int> faceVertex = r.dual.faceVertex;
    const int panelsCut = r.boundaryPanelsSplit;
    std::vector<int> faceOf;
    r.boundaryClip = clipBoundaryPanels(r.hex, surface, &faceOf);
    std::vector<std::uint8_t> clippedBoundary = boundaryFace;  // the faces' marks faceOf indexes
    std::vector<int> clippedVertex = faceVertex;
    // Boundary panels that only a cut made planar left out (dropCutPanels) and the rest clipped, kept where that clip
    // skips no more panels and leaves the edge as drawn and the boundary nodes at most kCutDroppedGap farther from the
    // curve than the first: the vase at 5000 faces, its one cut panel left out, kept a notch 1.13 edges deep (two
    // panels skipped), a steep dome's outline came 0.72 edges off where it was 0.08, and on the helicoid at 2000
    // faces (55 left out) a node of two panels whose edge could not take it to the curve stayed 2.1 edges inside it.
    if (r.boundaryPanelsSplit > 0) {
      PolyMesh thinned = unclipped;
      DualMesh faces;
      faces.faceVertex = faceVertex, faces.boundaryFace = boundaryFace;
      const CutPanelsDropped dropped = dropCutPanels(thinned, faces);
      if (dropped.panels > 0) {
        std::vector<int> thinnedOf;
        const BoundaryClip clip = clipBoundaryPanels(thinned, surface, &thinnedOf);
        if (clip.skipped <= r.boundaryClip.skipped && clip.gapMax <= r.boundaryClip.gapMax + kCutDroppedGap &&
            boundaryOffset(thinned, surface).max <= boundaryOffset(r.hex, surface).max + kCutDroppedGap) {
          r.hex = std::move(thinned);
          faceOf = std::move(thinnedOf);
          clippedBoundary = std::move(faces.boundaryFace);
          clippedVertex = std::move(faces.faceVertex);
          r.boundaryClip = clip;
          r.boundaryClip.cutDropped = dropped.panels;
          r.boundaryPanelsSplit -= dropped.cuts;
        }
      }
    }
    // Panels outside the curve removed; its fillers, appended after the panels, are boundary panels dual to no
    // vertex of the triangulation.
    r.dual.boundaryFace.assign(faceOf.size(), 1);
    r.dual.faceVertex.assign(faceOf.size(), -1);
    for (std::size_t f = 0; f < faceOf.size(); ++f) {
      const auto was = static_cast<std::size_t>(faceOf[f]);
      if (faceOf[f] >= 0 && was < clippedBoundary.size()) r.dual.boundaryFace[f] = clippedBoundary[was];
      if (faceOf[f] >= 0 && was < clippedVertex.size()) r.dual.faceVertex[f] = clippedVertex[was];
    }
    // A node moved along its edge onto the curve carries the planarity the solve left its two panels (up to the
    // tolerance) to the shorter clipped edges: on a rough saddle at 1500 faces one face went from 7.9e-10 to
    // 1.1e-9. Such a mesh is settled by a few sweeps of the solver without the closeness term, else left unclipped.
    if (r.solve.converged && maxPlanarity(r.hex) > params.tolerance) {
      PlanarizeOptions settle = po;
      settle.method = PlanarizeMethod::LocalGlobal;
      settle.lambda = settle.mu = 0;
      settle.maxIterations = 10;
      settle.fitSurface = false;
      planarize(r.hex, settle, {}, cancel);
      if (maxPlanarity(r.hex) > params.tolerance) {
        r.hex = unclipped;
        r.dual.boundaryFace = boundaryFace;
        r.dual.faceVertex = faceVertex;
        r.boundaryPanelsSplit = panelsCut;
        r.boundaryClip = BoundaryClip{};
        r.triangulation.notes.push_back("the boundary panels were not clipped to the boundary curve: clipped, a panel "
                                        "was no longer planar to the tolerance");
      }
    }
    if (r.boundaryClip.cutDropped > 0)
      r.triangulation.notes.push_back(
          std::to_string(r.boundaryClip.cutDropped) + " boundary panel" + (r.boundaryClip.cutDropped > 1 ? "s" : "") +
          " that only a cut in two made planar (each cut makes a node of four faces) left out; the clip took the panels "
          "next to " + (r.boundaryClip.cutDropped > 1 ? "them" : "it") + " to the boundary curve");
    clock.done("clip");
  }

  report("measure", 0, "measuring");
  r.metrics = measure(r.hex, surface);
  {
    const std::vector<Vec3> points = coverageSamples(surface);
    const double edge = r.hex.meanEdgeLength();
    int where = -1;
    r.coverageGap = edge > 0 ? largestGapToMesh(r.hex, points, &where) / edge : 0.0;
    // A part of the surface with no panel over it (a hole where rows did not meet, a strip along the boundary
    // left bare, panels pulled off the surface by an unconverged solve): named, where it is largest.
    if (r.coverageGap > kCoverageGapGoal && where >= 0) {
      const Vec3& at = points[static_cast<std::size_t>(where)];
      std::ostringstream s;
      s.precision(3);
      s << "the surface near (" << at.x() << ", " << at.y() << ", " << at.z() << ") lies " << r.coverageGap
        << " mean panel edges from the nearest panel (the goal is " << kCoverageGapGoal
        << "): a part of the surface is left without panels there";
      if (!r.solve.converged) s << " (the planarity solve did not converge and moved the panels off the surface)";
      r.triangulation.notes.push_back(s.str());
    }
  }
  r.boundaryOffset = boundaryOffset(r.hex, surface);
  int interior = 0, hexagons = 0;
  for (int f = 0; f < r.hex.faceCount(); ++f)
    if (!r.dual.boundaryFace[f]) ++interior, hexagons += r.hex.faceSize(f) == 6;
  r.interiorHexagonFraction = interior ? double(hexagons) / interior : 0.0;
  // A node far off the surface (a rounded box at 8000 faces: one 19 % of the diagonal off, converged and
  // planar, 0 % hexagons lost): its faces' planes meet far away, from a lay's triangle that bridged a gap or
  // three planes through nearly one line. Named, so that the result is not taken for a good one.
  const double farOff = farNodeDistance(r.hex, diagonal);
  int farthest = 0;
  r.farNodes = countFarNodes(r.metrics.surfaceDistance, farOff, &farthest);
  if (r.farNodes > 0) {
    const int far = r.farNodes;
    const Vec3 at = r.hex.vertex(farthest);
    std::ostringstream s;
    s.precision(4);
    s << far << (far == 1 ? " P-Hex node lies" : " P-Hex nodes lie") << " over " << 100 * farOff
      << " % of the diagonal (and a mean edge) off the surface, the farthest " << 100 * r.metrics.surfaceDistanceMax << " % near ("
      << at.x() << ", " << at.y() << ", " << at.z() << ") (the goal is 0.2 %): the planes of its faces meet far "
         "from the surface there (a triangle of the lay across a gap, or three planes through nearly one line); "
         "another face count, start or field may do";
    r.triangulation.notes.push_back(s.str());
  }
  clock.done("measure");
  // Measured in the local frame; the meshes go back to the file's coordinates.
  toFileFrame(r.triangulation, r.origin);
  if (r.origin != Vec3::Zero())
    for (Points* V : {&r.initial.V, &r.hex.V, &r.dual.mesh.V}) V->rowwise() += r.origin.transpose();
  r.totalMilliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

// What a second lay records of the first: that it ran, and how the first ended.
PipelineResult::Relay relayAfter(const PipelineResult& first) {
  PipelineResult::Relay relay;
  relay.tried = true;
  relay.firstReached = reached(first);
  relay.firstNodesOfFour = nodesOfFourCut(first);
  relay.firstCoverageGap = first.coverageGap;
  return relay;
}

// Another lay's stage times added to `timings`, stage by stage (a stage new to them at the end).
void addTimings(std::vector<StageTiming>& timings, const std::vector<StageTiming>& more) {
  for (const StageTiming& t : more) {
    auto same = std::find_if(timings.begin(), timings.end(), [&](const StageTiming& s) { return s.stage == t.stage; });
    if (same != timings.end()) same->milliseconds += t.milliseconds;
    else timings.push_back(t);
  }
}

// The result kept after a second lay: its `relay`, the surface reuse of the first lay (the second reuses the
// surface the first read), and both lays' time, stage by stage (in the order the first ran them).
void keepAfterRelay(PipelineResult& kept, const PipelineResult& first, const PipelineResult& second,
                    const PipelineResult::Relay& relay) {
  kept.relay = relay;
  kept.surfaceReused = first.surfaceReused;
  std::vector<StageTiming> timings = first.timings;
  addTimings(timings, second.timings);
  kept.timings = std::move(timings);
  kept.totalMilliseconds = first.totalMilliseconds + second.totalMilliseconds;
}

// A second lay of `params` after `first`: its result, or none where it cannot be laid at all (a cancellation goes on to
// the caller): `first` then stands, with `relay` and a note saying so (`what` the second lay, `kept` the first).
// (`lay` the second lay: runOnce by default.)
template <class Lay>
std::optional<PipelineResult> layAgainWith(const Lay& lay, PipelineResult& first, const PipelineResult::Relay& relay,
                                           const std::string& what, const std::string& kept) {
  try {
    return lay();
  } catch (const Error& e) {
    if (e.code() == ErrorCode::Cancelled) throw;
    first.relay = relay;
    first.triangulation.notes.push_back(what + ", the surface could not be tiled (" + e.what() + "): " + kept + " kept");
    return std::nullopt;
  }
}
std::optional<PipelineResult> layAgain(const PipelineParams& params, PipelineResult& first, const PipelineResult::Relay& relay,
                                       const std::string& what, const std::string& kept, const ProgressFn& progress,
                                       const CancelFlag* cancel) {
  return layAgainWith([&] { return runOnce(params, progress, cancel); }, first, relay, what, kept);
}

// An upload under auto that Method 2's rows left partly bare (a point of it farther than the coverage goal from
// any panel: rows zipped or ending short of a rim), brought to a P-Hex mesh only by cutting faces (nodes of four
// faces), or did not bring to one, tiled again by the global method; that one is kept where it reaches a P-Hex
// mesh and covers the upload more closely or, both within the goal, its cuts make fewer nodes of four (an
// uploaded vase at 3000 faces: the rows' 71 faces cut, 97 nodes of four; globally 4 and 5). The rows' own check
// (bareGap, on the triangulation) lets edges up to two triangle edges short pass, which keeps Method 2's
// all-hexagon rows on a cylinder or a hyperboloid; the panels' gap is what the goal measures (uploaded analytic
// samples at 1000 faces: a hemisphere 2.9 and a vase 2.3 mean panel edges bare, 21 faces cut on the vase; tiled
// globally 0.07 and 0.09, 96 and 94 % hexagons).
PipelineResult coveredGlobally(PipelineResult first, const PipelineParams& params, const ProgressFn& progress,
                               const CancelFlag* cancel) {
  const bool rows = first.method == TriangulationMethod::Prespecified || first.method == TriangulationMethod::Progressive;
  auto covers = [](const PipelineResult& r) { return r.coverageGap <= kCoverageGapGoal; };
  if (!params.relay || params.method != TriangulationMethod::Auto || !params.mesh || !rows ||
      (reached(first) && covers(first) && nodesOfFourCut(first) == 0))
    return first;
  PipelineParams global = params;
  global.method = TriangulationMethod::Global;
  if (progress) progress({"triangulate", 0, "laying again by the global method"});
  PipelineResult::Relay relay = relayAfter(first);
  relay.globally = true;
  std::optional<PipelineResult> laid =
      layAgain(global, first, relay, "laid again by the global method", "Method 2's rows are", progress, cancel);
  if (!laid) return first;
  PipelineResult& second = *laid;
  // The one that reached a P-Hex mesh; both: the one within the coverage goal; both within it: the one whose cuts
  // made fewer nodes of four faces; neither: the one covering more closely.
  const bool better =
      reached(second) && (!reached(first) || (covers(second) != covers(first)
                                                  ? covers(second)
                                                  : covers(first) ? nodesOfFourCut(second) < nodesOfFourCut(first)
                                                                  : second.coverageGap < first.coverageGap));
  relay.kept = better;
  PipelineResult& kept = better ? second : first;
  std::ostringstream s;
  s.precision(3);
  s << "Method 2's rows " << (relay.firstReached ? "reached a P-Hex mesh" : "did not reach a P-Hex mesh")
    << " leaving the upload up to " << first.coverageGap << " mean panel edges from any panel (the goal is "
    << kCoverageGapGoal << ") and " << relay.firstNodesOfFour << " nodes of four faces from cuts; laid again by the "
    << "global method, which " << (reached(second) ? "reached one" : "did not reach one") << " leaving "
    << second.coverageGap << " and " << nodesOfFourCut(second) << ": the " << (better ? "global method's" : "rows")
    << " kept";
  kept.triangulation.notes.push_back(s.str());
  keepAfterRelay(kept, first, second, relay);
  return std::move(kept);
}

// The global method laid again following the Dupin metric further, where `first` fell short (runPipeline); the
// better of the two, and in `keptParams` the parameters that laid it.
PipelineResult relayed(PipelineResult first, const PipelineParams& params, PipelineParams& keptParams,
                       const ProgressFn& progress, const CancelFlag* cancel) {
  // On a near-developable part the flatter curvature decides which triangles are valid (Props. 4, 5: with an edge
  // off the flatter direction by more than about the curvature ratio, a dual face folds), and the default metric,
  // bounded and regularized, follows little of it there.
  PipelineParams again = params;
  again.anisotropy = std::max(params.anisotropy, kRelayAnisotropy);
  again.curvatureFloor = std::min(params.curvatureFloor, kRelayFloor);
  if (progress) progress({"triangulate", 0, "laying again, following the Dupin metric further"});
  PipelineResult::Relay relay = relayAfter(first);
  relay.anisotropy = again.anisotropy;
  relay.curvatureFloor = again.curvatureFloor;
  std::optional<PipelineResult> laid =
      layAgain(again, first, relay, "laid again following the Dupin metric further", "the first lay is", progress, cancel);
  if (!laid) return first;
  PipelineResult& second = *laid;
  // The one that reached a P-Hex mesh; both did: the one whose cuts made fewer nodes of four faces (then more
  // hexagons); neither: the first.
  const bool better = reached(second) != reached(first)
                          ? reached(second)
                          : reached(second) && (nodesOfFourCut(second) != nodesOfFourCut(first)
                                                    ? nodesOfFourCut(second) < nodesOfFourCut(first)
                                                    : second.interiorHexagonFraction > first.interiorHexagonFraction);
  relay.kept = better;
  PipelineResult& kept = better ? second : first;
  {
    std::ostringstream s;
    s.precision(3);
    s << "the first lay " << (relay.firstReached ? "converged" : "did not reach a P-Hex mesh") << " with "
      << relay.firstNodesOfFour << " nodes of four faces from its cuts; laid again following the Dupin metric to an "
      << "anisotropy of " << again.anisotropy << " (curvature floor " << again.curvatureFloor << "), which "
      << (reached(second) ? "converged" : "did not reach a P-Hex mesh") << " with " << nodesOfFourCut(second)
      << ": the " << (better ? "second" : "first") << " is kept";
    kept.triangulation.notes.push_back(s.str());
  }
  if (better) keptParams = again;
  keepAfterRelay(kept, first, second, relay);
  return std::move(kept);
}

// Where the lay kept (`best`, laid by `laidWith`) still has nodes of four faces from cuts and at most kTrialMostFaces
// faces were asked for (or at most kTrialLargeFaces, where those nodes are over kTrialLargeShare of them: a lay costs
// seconds there, and a few nodes from boundary panels cut do not pay for two), it is laid again for each of
// kTrialShares of the faces (a cell given: the cell scaled as that would), stopping at one without such nodes; kept:
// the one that reached a P-Hex mesh, then covering the surface within the coverage goal, then with fewer nodes of
// four, then more hexagons, among those within kTrialCountMiss of the faces asked. The global method's cuts come from
// a few places where the lattice falls badly against the surface (next to parabolic curves, around a handle a few
// cells across), and its lattice falls otherwise at a face count a few percent off: on the generated genus 0-3 and
// ten clean surfaces at 1000-5000 faces (52 runs), nodes of four 238 -> 72 (METHOD.md). The time is each lay's,
// summed.
constexpr double kTrialCountMiss = 0.1;  // the goal: the face count within 10 % of the count asked
PipelineResult withTrials(PipelineResult best, const PipelineParams& params, const PipelineParams& laidWith,
                          const ProgressFn& progress, const CancelFlag* cancel) {
  const int size = params.cell > 0 ? best.metrics.faceCount : params.faces;  // a cell given: the faces it gave
  const bool many = nodesOfFourCut(best) > kTrialLargeShare * size;
  if (nodesOfFourCut(best) == 0 || size > (many ? kTrialLargeFaces : kTrialMostFaces) || size <= 0) return best;
  auto countOk = [&](const PipelineResult& r) {
    return params.cell > 0 || std::abs(r.metrics.faceCount - params.faces) <= kTrialCountMiss * params.faces;
  };
  auto covers = [](const PipelineResult& r) { return r.coverageGap <= kCoverageGapGoal; };
  auto better = [&](const PipelineResult& a, const PipelineResult& b) {  // a better than b
    if (countOk(a) != countOk(b)) return countOk(a);
    if (reached(a) != reached(b)) return reached(a);
    if (covers(a) != covers(b)) return covers(a);
    if (nodesOfFourCut(a) != nodesOfFourCut(b)) return nodesOfFourCut(a) < nodesOfFourCut(b);
    return a.interiorHexagonFraction > b.interiorHexagonFraction;
  };
  PipelineResult::Relay relay = best.relay;
  relay.trialNodesOfFour = nodesOfFourCut(best);
  double total = best.totalMilliseconds;
  std::vector<StageTiming> timings = best.timings;
  std::vector<std::string> tried;
  std::string keptAs;  // the trial kept, as the note names it
  // The note of a lay laid again (the last of its notes, relayed() or coveredGlobally()) goes with whichever lay is
  // kept: a trial kept in its place was laid with the same parameters, and the report's relay says what ran.
  const std::string relayNote = best.relay.tried && !best.triangulation.notes.empty() ? best.triangulation.notes.back() : "";
  for (double share : kTrialShares) {
    PipelineParams p = laidWith;
    std::ostringstream as;
    as.precision(4);
    if (params.cell > 0) p.cell = params.cell / std::sqrt(share), as << "at a cell of " << p.cell;
    else p.faces = std::max(1, static_cast<int>(std::lround(share * params.faces))), as << "for " << p.faces << " faces";
    if (progress) progress({"triangulate", 0, "laying again " + as.str() + " (a trial: the lay's cuts left nodes of four faces)"});
    ++relay.trials;
    PipelineResult r;
    try {
      r = runOnce(p, progress, cancel);
    } catch (const Error& e) {
      if (e.code() == ErrorCode::Cancelled) throw;
      tried.push_back(as.str() + ": not tiled (" + e.what() + ")");
      continue;
    }
    total += r.totalMilliseconds;
    addTimings(timings, r.timings);
    tried.push_back(as.str() + ": " + std::to_string(r.metrics.faceCount) + " faces, " +
                    (reached(r) ? "converged" : "no P-Hex mesh") + ", " + std::to_string(nodesOfFourCut(r)) + " nodes of four");
    if (better(r, best)) {
      if (!relayNote.empty()) r.triangulation.notes.push_back(relayNote);
      r.surfaceReused = best.surfaceReused;
      best = std::move(r);
      relay.trialShare = share;
      keptAs = as.str();
    }
    if (reached(best) && covers(best) && nodesOfFourCut(best) == 0 && countOk(best)) break;
  }
  std::ostringstream s;
  s << "the lay left " << relay.trialNodesOfFour << " nodes of four faces from its cuts; laid again as trials (";
  for (std::size_t i = 0; i < tried.size(); ++i) s << (i ? "; " : "") << tried[i];
  s << "): " << (keptAs.empty() ? std::string("the lay before them") : "the one " + keptAs) << " is kept";
  best.triangulation.notes.push_back(s.str());
  best.relay = relay;
  best.timings = std::move(timings);
  best.totalMilliseconds = total;
  return best;
}

}  // namespace

namespace {

// Whether `first`, laid by `params` under auto, went to the global method by auto's own choice (not as Method 2's
// rows' replacement, PipelineResult::Relay::globally, whose re-lays choose again).
bool globallyChosen(const PipelineParams& params, const PipelineResult& first) {
  return params.method == TriangulationMethod::Auto && first.method == TriangulationMethod::Global &&
         !first.globalBecause.empty() && !first.relay.globally;
}

// The parameters `first` (laid by `params`) is laid again with: those asked (under auto the choice of method runs
// again, and says so in the notes), or where Method 2's rows gave way to the global method, the global method's; where
// auto chose the global method itself, the global method at once with its reason (PipelineParams::globalBecause).
PipelineParams laidAgainWith(const PipelineParams& params, const PipelineResult& first) {
  PipelineParams again = params;
  if (first.relay.globally) again.method = TriangulationMethod::Global;
  if (globallyChosen(params, first)) again.method = TriangulationMethod::Global, again.globalBecause = first.globalBecause;
  return again;
}

// After `first` (laid by `params`), the global method laid again where it fell short (relayed), then the trial lays
// (withTrials).
PipelineResult relayAndTrials(PipelineResult first, const PipelineParams& params, const ProgressFn& progress,
                              const CancelFlag* cancel) {
  PipelineParams laidWith = laidAgainWith(params, first);
  const PipelineParams relayFrom = globallyChosen(params, first) ? laidWith : params;
  const bool fellShort = !reached(first) || nodesOfFourCut(first) > kRelayNodesOfFour * first.metrics.faceCount;
  PipelineResult kept = fellShort && !first.relay.tried ? relayed(std::move(first), relayFrom, laidWith, progress, cancel)
                                                        : std::move(first);
  return withTrials(std::move(kept), params, laidWith, progress, cancel);
}

// A noisy upload whose first lay (without the repairs, PipelineParams::noisyRepairs) did not reach a P-Hex mesh, or
// reached one only with nodes of four faces from cuts at over kRelayNodesOfFour of its faces (the six_s0 model at
// 1500 faces since the dislocations are cancelled: 149 + 44 faces cut), laid again with them as a smooth upload is
// (relayed and trial lays included); the second kept where it reached one the first did not, or one with fewer
// nodes of four faces from cuts. On the five noisy shared models at 1000, 1500, 3000 and 10000 faces the first lays reached none; the
// second 15 of 20 (cutting 0-277 faces; the genus-3 model at 1500 faces 131 and the car at 3000 faces 277, a tenth
// of its faces), with 2-15 points fewer hexagons where they did (METHOD.md).
PipelineResult withNoisyRepairs(PipelineResult first, const PipelineParams& params, const ProgressFn& progress,
                                const CancelFlag* cancel) {
  PipelineParams again = laidAgainWith(params, first);
  again.noisyRepairs = true;
  if (progress) progress({"triangulate", 0, "laying again with the repairs of a smooth upload (the first lay fell short)"});
  PipelineResult::Relay relay = relayAfter(first);
  relay.globally = first.relay.globally;
  relay.noisyRepairs = true;
  std::optional<PipelineResult> laid = layAgain(again, first, relay, "laid again with the repairs of a smooth upload",
                                                "the first lay is", progress, cancel);
  if (!laid) return first;
  PipelineResult second = relayAndTrials(std::move(*laid), again, progress, cancel);
  // Kept where it reaches a P-Hex mesh the first did not, or one with fewer nodes of four faces from cuts.
  const bool better = reached(second) && (!reached(first) || nodesOfFourCut(second) < nodesOfFourCut(first));
  PipelineResult& kept = better ? second : first;
  PipelineResult::Relay keptRelay = better ? second.relay : relay;
  keptRelay.noisyRepairs = true;
  keptRelay.noisyRepairsKept = better;
  std::ostringstream s;
  s << "the uploaded mesh is noisy, and its first lay, without the solver's fairness, the changes at folded boundary "
       "panels and the dislocation glides (on noisy meshes they trade hexagons for cuts), "
    << (reached(first) ? "reached a P-Hex mesh only by cutting faces (" : "did not reach a P-Hex mesh (") << relay.firstNodesOfFour
    << " nodes of four faces from its cuts); laid again with them, as a smooth upload is, it "
    << (better                ? "reached one with " + std::to_string(nodesOfFourCut(second)) + " nodes of four faces from its cuts: the second is kept"
        : reached(second)     ? "reached one with " + std::to_string(nodesOfFourCut(second)) + " nodes of four faces from its cuts: the first is kept"
        : reached(first)      ? std::string("did not reach one: the first is kept")
                              : std::string("did not reach one either: the first is kept"));
  kept.triangulation.notes.push_back(s.str());
  keepAfterRelay(kept, first, second, keptRelay);
  return std::move(kept);
}

// The first lay and, for the global method, the lays again where it falls short (relayAndTrials, withNoisyRepairs).
PipelineResult layAndRelay(const PipelineParams& params, const ProgressFn& progress, const CancelFlag* cancel) {
  PipelineResult first = coveredGlobally(runOnce(params, progress, cancel), params, progress, cancel);
  const bool noisy = first.surface && !smoothRepairs(params, *first.surface);
  return !params.relay || first.method != TriangulationMethod::Global ? std::move(first)
         : !noisy                                                 ? relayAndTrials(std::move(first), params, progress, cancel)
         : reached(first) && nodesOfFourCut(first) <= kRelayNodesOfFour * first.metrics.faceCount
             ? std::move(first)
             : withNoisyRepairs(std::move(first), params, progress, cancel);
}

}  // namespace

PipelineResult runPipeline(const PipelineParams& params, const ProgressFn& progress, const CancelFlag* cancel) {
  PipelineResult kept = layAndRelay(params, progress, cancel);
  // Where no lay reached a P-Hex mesh (the solve stalled short of the tolerance: the coarse, near-developable shared
  // models fold a tenth to a fifth of their faces), or the lay kept reached one only with nodes of four faces from cuts
  // at over kRelayNodesOfFour of its faces (the car at 1500 faces laid on its refinement, whose relay reached one with
  // 262), all of it once more with the rounds against folds run also where up to kFoldRescueShare of the faces fold;
  // kept where that reaches one, with fewer such nodes where the first reached one too.
  const bool cutMany = reached(kept) && nodesOfFourCut(kept) > kRelayNodesOfFour * kept.metrics.faceCount;
  if (params.relay && params.foldFlips && kept.method == TriangulationMethod::Global && (!reached(kept) || cutMany) &&
      params.foldRoundsShare < kFoldRescueShare) {
    PipelineParams again = laidAgainWith(params, kept);
    again.foldRoundsShare = kFoldRescueShare;
    if (progress)
      progress({"triangulate", 0,
                cutMany ? "laying again with the rounds against folds on more folds (the lay kept cut many faces)"
                        : "laying again with the rounds against folds on more folds (no lay reached a P-Hex mesh)"});
    std::ostringstream s;
    s.precision(2);
    if (cutMany)
      s << "the lay kept reached a P-Hex mesh only with " << nodesOfFourCut(kept)
        << " nodes of four faces from its cuts (over " << std::lround(100 * kRelayNodesOfFour) << " % of its faces)";
    else
      s << "no lay reached a P-Hex mesh (planarity " << kept.metrics.planarityMax << ")";
    s << "; laid again with the edge collapses and flips against folds run also where more than "
      << std::lround(100 * params.foldRoundsShare) << " % of the faces fold (up to " << std::lround(100 * kFoldRescueShare)
      << " %), fewer hexagons for planar faces";
    std::optional<PipelineResult> second =
        layAgainWith([&] { return layAndRelay(again, progress, cancel); }, kept, kept.relay, s.str(), "the first is");
    if (second) {
      const bool better = reached(*second) && (!reached(kept) || nodesOfFourCut(*second) < nodesOfFourCut(kept));
      s << (better            ? ": it reached one (" + std::to_string(second->metrics.faceCount) + " faces, " +
                                    std::to_string(nodesOfFourCut(*second)) + " nodes of four faces from cuts): kept"
            : reached(*second) ? ": it reached one with " + std::to_string(nodesOfFourCut(*second)) +
                                     " nodes of four faces from cuts: the first is kept"
            : cutMany          ? std::string(": it did not reach one: the first is kept")
                               : std::string(": it did not reach one either: the first is kept"));
      PipelineResult& laid = better ? *second : kept;
      laid.triangulation.notes.push_back(s.str());
      const PipelineResult::Relay relay = laid.relay;
      keepAfterRelay(laid, kept, *second, relay);
      if (better) kept = std::move(*second);
    }
  }
  if (progress) progress({"done", 1, "done"});
  return kept;
}

}  // namespace phex
