// phex — the global triangulation: field, lattice and extraction, with the cell calibrated to the faces asked for.
#include "phex/global_triangulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "global.hpp"
#include "phex/error.hpp"

namespace phex {

void validate(const GlobalOptions& o) {
  auto bad = [](const std::string& what) { throw Error(ErrorCode::InvalidParameter, what); };
  if (!(o.cell >= 0) || !std::isfinite(o.cell)) bad("cell must be a finite number >= 0");
  if (o.cell == 0 && o.faces <= 0) bad("the global method needs a cell > 0 or a face count > 0");
  if (!(o.anisotropy >= 1 && o.anisotropy <= 8)) bad("anisotropy must be in [1, 8]");
  if (!(o.alignment >= 0 && o.alignment <= 10)) bad("alignment must be in [0, 10]");
  if (!(o.curvatureSizing >= 0 && o.curvatureSizing <= 1)) bad("curvatureSizing must be in [0, 1]");
}

namespace {

using namespace global;

// Field-mesh edges per cell: the position field needs a few vertices per lattice point, and the Voronoi regions
// several, to come out as disks.
constexpr double kSamplesPerCell = 2.6;
// A lay whose vertex count misses the faces asked for by more than this (ratio) is laid again with the cell scaled.
constexpr double kCountMiss = 1.04;

// Per fine vertex, the factor of the cell there: 1 for uniform panels; with curvature sizing s, the largest
// |curvature| over the surface's median to the power -s/2, within [1/3, 3], smoothed over the mesh, and normalized
// so that the mean cell area stays that of the uniform cell.
std::vector<double> cellScale(const FieldMesh& m, double sizing) {
  const int nv = m.vertexCount();
  std::vector<double> scale(nv, 1.0);
  if (sizing <= 0) return scale;
  std::vector<double> sorted = m.curvature;
  std::nth_element(sorted.begin(), sorted.begin() + nv / 2, sorted.end());
  const double typical = sorted[nv / 2];
  if (!(typical > 0)) return scale;
  for (int v = 0; v < nv; ++v) {
    const double ratio = std::max(m.curvature[v], 1e-3 * typical) / typical;
    // ratio^(-s/2) as exp(-s/2 log ratio) would use libm; a few square roots give the same on every platform for
    // the steps 0, 1/4, 1/2, 3/4, 1 of s, and a linear blend between them.
    const double r1 = 1 / std::sqrt(ratio), r2 = std::sqrt(r1);
    const double steps[5] = {1.0, std::sqrt(r2), r2, r2 * std::sqrt(r2), r1};
    const double at = 4 * sizing;
    const int i = std::min(3, static_cast<int>(at));
    const double w = at - i;
    scale[v] = std::clamp((1 - w) * steps[i] + w * steps[i + 1], 1.0 / 3, 3.0);
  }
  for (int pass = 0; pass < 8; ++pass) {
    std::vector<double> next(nv);
    for (int v = 0; v < nv; ++v) {
      double sum = scale[v];
      for (int i = m.start[v]; i < m.start[v + 1]; ++i) sum += scale[m.adjacent[i]];
      next[v] = sum / (1 + m.start[v + 1] - m.start[v]);
    }
    scale.swap(next);
  }
  double area = 0, weighted = 0;
  for (int v = 0; v < nv; ++v) area += m.area[v], weighted += m.area[v] / (scale[v] * scale[v]);
  const double norm = weighted > 0 ? std::sqrt(weighted / area) : 1.0;
  for (double& s : scale) s *= norm;
  return scale;
}

// The cell that gives about `faces` vertices: interior vertices one per sqrt(3)/2 cell^2 of (scaled) area, and
// the boundary's half a row more: faces = A / (c h^2) + P / (2 h).
double cellForCount(const FieldMesh& m, const std::vector<double>& scale, int faces) {
  double area = 0, perimeter = 0;
  for (int v = 0; v < m.vertexCount(); ++v) area += m.area[v] / (scale[v] * scale[v]);
  for (const std::vector<int>& loop : m.loops)
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      const Vec3 d = m.point(b) - m.point(a);
      perimeter += 0.5 * (norm(m.frame[a].toDupin(d)) / scale[a] + norm(m.frame[b].toDupin(d)) / scale[b]);
    }
  const double c = std::sqrt(3.0) / 2, N = faces;
  return (perimeter / 2 + std::sqrt(perimeter * perimeter / 4 + 4 * N * area / c)) / (2 * N);
}

}  // namespace

Triangulation globalTriangulation(const Surface& surface, const GlobalOptions& options, const ProgressFn& progress,
                                  const CancelFlag* cancel) {
  validate(options);
  auto report = [&](double fraction, const std::string& message) {
    checkCancel(cancel);
    if (progress) progress({"triangulate", fraction, message});
  };
  const auto t0 = std::chrono::steady_clock::now();
  std::ostringstream times;
  auto lap = [&](const char* what) {
    times << what << " " << std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() << " ms; ";
  };
  double cell = options.cell > 0 ? options.cell : cellForFaceCount(surface, options.faces);
  report(0.02, "field mesh");
  FieldMesh m = fieldMesh(surface, cell / kSamplesPerCell, options.anisotropy, cancel);
  lap("field mesh");
  std::vector<double> scale = cellScale(m, options.curvatureSizing);
  report(0.1, "direction field");
  std::vector<Level> levels = hierarchy(m, scale);
  std::vector<std::vector<Vec3>> fields = orientationField(levels, options.alignment, progress, cancel);
  lap("directions");
  {
    static const double strength = getenv("PHEX_IS") ? atof(getenv("PHEX_IS")) : 1.0;
    const std::vector<double> integrable = integrableScale(m, fields[0], strength);
    for (int v = 0; v < m.vertexCount(); ++v) scale[v] *= integrable[v];
    setScale(levels, scale);
  }
  lap("scale");
  if (options.cell == 0) cell = cellForCount(m, scale, options.faces);

  Extraction best;
  double bestMiss = std::numeric_limits<double>::infinity(), bestCell = cell;
  for (int attempt = 0; attempt < 3; ++attempt) {
    report(0.3, "lattice");
    const std::vector<Vec3> o = positionField(levels, fields, cell, progress, cancel);
    lap("positions");
    report(0.5, "extraction");
    Extraction ex = extractTriangulation(surface, m, fields[0], o, scale, cell, cancel);
    lap("extraction");
    const double count = static_cast<double>(ex.mesh.V.rows());
    const double ratio = std::max(count, 1.0) / options.faces;
    const double miss = options.faces > 0 ? std::max(ratio, 1 / ratio) : 1.0;
    if (miss < bestMiss) bestMiss = miss, best = std::move(ex), bestCell = cell;
    if (options.faces <= 0 || bestMiss <= kCountMiss) break;
    cell *= std::sqrt(std::max(count, 1.0) / options.faces);
  }

  Triangulation t;
  t.mesh = std::move(best.mesh);
  if (t.mesh.F.rows() == 0)
    throw Error(ErrorCode::CannotTile, "the cell (" + std::to_string(bestCell) + ") is larger than the surface: no triangle could be laid");
  // The field's singular points, from the fine mesh.
  int plus = 0, minus = 0;
  for (int f = 0; f < m.F.rows(); ++f) {
    const int index = singularityIndex(m, fields[0], m.F(f, 0), m.F(f, 1), m.F(f, 2));
    if (index == 0) continue;
    const Vec3 at = (m.point(m.F(f, 0)) + m.point(m.F(f, 1)) + m.point(m.F(f, 2))) / 3;
    t.singularities.push_back({at, index});
    (index > 0 ? plus : minus) += std::abs(index);
  }
  std::ostringstream s;
  s.precision(4);
  s << "global field: cell " << bestCell << ", " << t.singularities.size() << " singular points (" << plus
    << " sixths of a turn positive, " << minus << " negative), laid on " << m.vertexCount() << " field-mesh vertices in "
    << levels.size() << " levels";
  t.notes.push_back(s.str());
  if (getenv("PHEX_DBG")) t.notes.push_back(times.str());
  for (std::string& note : best.notes) t.notes.push_back(std::move(note));
  return t;
}

}  // namespace phex
