// phex — the global triangulation: field, lattice and extraction, with the cell calibrated to the faces asked for.
#include "phex/global_triangulation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "global.hpp"
#include "phex/error.hpp"
#include "phex/mesh_surface.hpp"

namespace phex {

void validate(const GlobalOptions& o) {
  auto bad = [](const std::string& what) { throw Error(ErrorCode::InvalidParameter, what); };
  if (!(o.cell >= 0) || !std::isfinite(o.cell)) bad("cell must be a finite number >= 0");
  if (o.cell == 0 && o.faces <= 0) bad("the global method needs a cell > 0 or a face count > 0");
  if (!(o.anisotropy >= 1 && o.anisotropy <= 8)) bad("anisotropy must be in [1, 8]");
  if (!(o.curvatureFloor >= 0.01 && o.curvatureFloor <= 1)) bad("curvatureFloor must be in [0.01, 1]");
  if (!(o.alignment >= 0 && o.alignment <= 10)) bad("alignment must be in [0, 10]");
  if (!(o.curvatureSizing >= 0 && o.curvatureSizing <= 1)) bad("curvatureSizing must be in [0, 1]");
}

namespace {

using namespace global;

// Field-mesh edges per cell: the position field needs a few vertices per lattice point, and the Voronoi regions
// several, to come out as disks. From about kFewerSamplesFaces faces on (the surface's area over a regular
// triangulation's vertex area at the cell) kFewerSamplesPerCell: measured at 50k and 100k faces (the bench's upload,
// the torus, the bubble, the generated genus 2, the bumps), 2.3 against 2.6 took 13 % less time on average (7 of
// 8 runs less; the bench's upload at 100k 9.8 -> 8.5 s) and 10-20 % less memory (every run; the genus 2 at 100k
// 1.49 -> 1.18 GB), with as many hexagons within the runs' scatter and fewer faces cut on 5 of 8 (the bench's
// upload at 100k 92 -> 78, the torus at 50k 63 -> 32; more on the torus at 100k, 224 -> 278); at 30k faces fewer
// cut on all four (22 -> 8, 18 -> 4, 6 -> 4, 87 -> 8), but at 10k and 20k more on three of four (the torus at 10k
// 0 -> 4, the upload at 20k 3 -> 30).
constexpr double kSamplesPerCell = 2.6, kFewerSamplesPerCell = 2.3, kFewerSamplesFaces = 30000;
// A lay whose vertex count misses the faces asked for by more than this (ratio) is laid again with the cell scaled.
constexpr double kCountMiss = 1.05;
// The field mesh laid this much finer where the first one left non-manifold regions.
constexpr double kDenser = 1.6;
// The dislocations are cancelled (dislocations.cpp) on field meshes of up to this many vertices (about 40k faces).
// Above, they cost more than they give: the bench's upload at 100k faces (675k field-mesh vertices) is 98.43 %
// of valence 6 before the rounds against folds with its dislocations kept, 98.59 % cancelled, for 0.85 s of a 10 s
// run; and laid globally its cancelled field's regions did not all come out as disks, so it was extracted again
// as the sweeps left it (1.5 s for nothing).
constexpr int kCancelMostVertices = 300000;
// Rounds of fitting the vertices to the field (relax.cpp): on the torus at 3000 faces, from 224 interior faces the
// solve could not make planar without folding to 72; more rounds changed nothing.
constexpr int kFitRounds = 3;
// GlobalOptions::principalTrial: the held field's alignment against the first's, and the share of the first's
// singular points it may have at most to be kept.
constexpr double kPrincipalStrength = 10, kPrincipalFewer = 0.75;

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

double globalSamplesPerCell(const Surface& surface, double cell) {
  if (!dynamic_cast<const MeshSurface*>(&surface) && !dynamic_cast<const ParametricSurface*>(&surface))
    return kSamplesPerCell;  // fieldMesh names the surface it cannot sample
  const double faces = surfaceArea(surface) / (std::sqrt(3.0) / 2 * cell * cell);
  return faces >= kFewerSamplesFaces ? kFewerSamplesPerCell : kSamplesPerCell;
}
double globalFieldEdge(const Surface& surface, double cell) { return cell / globalSamplesPerCell(surface, cell); }
int globalFieldSplit(double median, double edge) { return fieldSplit(median, edge); }

Triangulation globalTriangulation(const Surface& surface, const GlobalOptions& options, const ProgressFn& progress,
                                  const CancelFlag* cancel) {
  validate(options);
  auto report = [&](double fraction, const std::string& message) {
    checkCancel(cancel);
    if (progress) progress({"triangulate", fraction, message});
  };
  double cell = options.cell > 0 ? options.cell : cellForFaceCount(surface, options.faces);
  if (!(cell > 0) || !std::isfinite(cell)) throw Error(ErrorCode::CannotTile, "the surface has no area to tile");
  // Where the Voronoi regions of the lattice's points do not come out as disks on the field mesh (a region
  // across a thin part, a handle narrower than a few cells), the field mesh is laid finer once and all again.
  // Where that fails too (regions folded over a crease whose field-mesh normals turn sharply), the lattice laid at
  // a cell a few percent smaller shifts its points off the configuration.
  constexpr double kRetries[3][2] = {{1.0, 1.0}, {kDenser, 1.0}, {kDenser, 0.97}};
  for (int density = 0;; ++density) {
    const double samples = globalSamplesPerCell(surface, cell) * kRetries[density][0];
    cell *= kRetries[density][1];
    try {
      report(0.02, "field mesh");
      FieldMesh m = fieldMesh(surface, cell / samples, options.anisotropy, options.curvatureFloor, cancel);
      std::vector<double> scale = cellScale(m, options.curvatureSizing);
      report(0.1, "direction field");
      std::vector<Level> levels = hierarchy(m, scale, options.freeAlignedBoundary);
      std::vector<std::vector<Vec3>> fields = orientationField(levels, options.alignment, progress, cancel);
      // Per field-mesh triangle (i, j, k), value(i, j, k) over threads (an int: no two threads share a byte).
      auto perTriangle = [&](auto value) {
        std::vector<int> out(m.F.rows());
        parallelRanges(static_cast<int>(m.F.rows()), kSweepGrain, [&](int begin, int end) {
          for (int f = begin; f < end; ++f) out[f] = value(m.F(f, 0), m.F(f, 1), m.F(f, 2));
        });
        return out;
      };
      // Per field-mesh triangle, the index of a field's singular point there (0: none).
      auto singularIndices = [&](const std::vector<Vec3>& q) {
        return perTriangle([&](int i, int j, int k) { return singularityIndex(m, q, i, j, k); });
      };
      std::vector<int> indices = singularIndices(fields[0]);
      auto singularCount = [](const std::vector<int>& i) { return i.size() - std::count(i.begin(), i.end(), 0); };
      // The field held to the principal directions (GlobalOptions::principalTrial), kept where it has clearly
      // fewer singular points.
      bool principal = false;
      const std::size_t firstSingular = singularCount(indices);
      bool trying = options.principalTrial && options.alignment > 0 && firstSingular > 0;
      if (trying) {
        // Around an umbilic the held field turns through at least three singular points of a sixth: not tried
        // where three per field-mesh triangle the principal directions turn about would be more than that share.
        const std::vector<int> turns =
            perTriangle([&](int i, int j, int k) { return static_cast<int>(principalTurns(m, i, j, k)); });
        const auto umbilics = static_cast<std::size_t>(std::count(turns.begin(), turns.end(), 1));
        trying = 3 * umbilics <= kPrincipalFewer * firstSingular;
      }
      if (trying) {
        report(0.3, "direction field held to the principal directions");
        std::vector<double> weights(m.vertexCount());
        for (int v = 0; v < m.vertexCount(); ++v) weights[v] = std::max(m.alignWeight[v], m.principalWeight[v]);
        std::vector<Level> held = hierarchy(m, scale, options.freeAlignedBoundary, &weights);
        std::vector<std::vector<Vec3>> heldFields =
            orientationField(held, kPrincipalStrength * options.alignment, nullptr, cancel);
        std::vector<int> heldIndices = singularIndices(heldFields[0]);
        if (singularCount(heldIndices) <= kPrincipalFewer * firstSingular)
          levels = std::move(held), fields = std::move(heldFields), indices = std::move(heldIndices), principal = true;
      }
      const std::vector<double> integrable = integrableScale(m, fields[0], 1.0);
      for (int v = 0; v < m.vertexCount(); ++v) scale[v] *= integrable[v];
      setScale(levels, scale);
      double laid = options.cell > 0 ? cell : kRetries[density][1] * cellForCount(m, scale, options.faces);

      // The lattice at the cell, and again (at most twice) with the cell scaled where the count misses the faces
      // asked for by more than kCountMiss; the closest is kept.
      Extraction best;
      double bestMiss = std::numeric_limits<double>::infinity(), bestCell = laid;
      int bestCancelled = 0, bestLeft = 0;
      const bool cancelling = options.cancelDislocations && m.vertexCount() <= kCancelMostVertices;
      for (int attempt = 0; attempt < 3; ++attempt) {
        report(0.3 + 0.1 * attempt, "lattice");
        std::vector<Vec3> o = positionField(levels, fields, laid, progress, cancel);
        // The field as the sweeps left it, kept while its dislocations are cancelled: where the cancelled field's
        // regions do not come out as disks (its points strained past the extraction's tolerances around a long
        // path), that one is extracted instead of laying a finer field mesh (the bench's upload laid globally at
        // 100k faces: 23 s and 1.9 GB so, 10 s and 0.8 GB with the kept field).
        std::vector<Vec3> kept;
        int cancelled = 0, left = 0;
        if (cancelling) {
          report(0.5 + 0.1 * attempt, "dislocations");
          kept = o;
          cancelled = cancelDislocations(m, levels[0], fields[0], o, laid, &left, cancel);
        }
        report(0.5 + 0.1 * attempt, "extraction");
        Extraction ex;
        try {
          ex = extractTriangulation(surface, m, o, scale, laid, cancel);
        } catch (const Error& e) {
          if (kept.empty() || e.code() != ErrorCode::CannotTile || std::string(e.what()).find("non-manifold") == std::string::npos)
            throw;
          ex = extractTriangulation(surface, m, kept, scale, laid, cancel);
          cancelled = 0, left = -1;
        }
        const double count = std::max(1.0, static_cast<double>(ex.mesh.V.rows()));
        const double miss = options.faces > 0 ? std::max(count / options.faces, options.faces / count) : 1.0;
        if (miss < bestMiss) bestMiss = miss, best = std::move(ex), bestCell = laid, bestCancelled = cancelled, bestLeft = left;
        if (options.faces <= 0 || bestMiss <= kCountMiss) break;
        laid *= std::sqrt(count / options.faces);
      }
      if (best.mesh.F.rows() == 0)
        throw Error(ErrorCode::CannotTile, "the cell (" + std::to_string(bestCell) +
                                               ") is larger than the surface: no triangle of the lattice could be laid");

      report(0.8, "relaxation");
      Triangulation t;
      t.mesh = std::move(best.mesh);
      const int flips = improveValences(t.mesh, surface, options.glideDislocations, cancel);
      fitToField(t.mesh, best.seeds, surface, m, fields[0], scale, bestCell, kFitRounds, cancel);
      // The field's singular points, from the field mesh; the field's directions at the vertices, for display.
      int plus = 0, minus = 0;
      for (int f = 0; f < m.F.rows(); ++f) {
        const int index = indices[f];
        if (index == 0) continue;
        t.singularities.push_back({(m.point(m.F(f, 0)) + m.point(m.F(f, 1)) + m.point(m.F(f, 2))) / 3, index});
        (index > 0 ? plus : minus) += std::abs(index);
      }
      for (int v = 0; v < t.mesh.V.rows(); ++v) {
        const int s = best.seeds[v];
        if (s < 0) continue;
        const Frame& f = m.frame[s];
        Vec3 d = fields[0][s];
        const Vec3 x = t.mesh.V.row(v).transpose();
        for (int k = 0; k < 3; ++k, d = rotate60(d, f.n)) {
          const Vec3 half = 0.3 * bestCell * scale[s] * f.fromDupin(d);
          t.fieldLines.push_back({x - half, x + half});
        }
      }
      std::ostringstream s;
      s.precision(4);
      s << "global field: cell " << bestCell << ", " << t.singularities.size() << " singular points (" << plus
        << " sixths of a turn positive, " << minus << " negative) laid on " << m.vertexCount() << " field-mesh vertices";
      if (principal)
        s << " (held to the principal directions wherever the curvature is anisotropic: the field smoothest in the "
             "Dupin metric turned through "
          << firstSingular << ")";
      if (m.thinnedFrom > 0)
        s << " (the upload's " << m.thinnedFrom << " vertices, finer or more uneven than the field needs, remeshed to "
          << m.thinnedTo
          << (m.thinnedSplit > 1 ? " at " + std::to_string(m.thinnedSplit) + " times its edge and split " +
                                       std::to_string(m.thinnedSplit) + " x " + std::to_string(m.thinnedSplit) + ")"
                                 : std::string(" at its edge)"));
      if (options.cancelDislocations && !cancelling)
        s << "; the lattice's dislocations kept (the cancellation runs on field meshes of up to "
          << kCancelMostVertices << " vertices)";
      else if (cancelling && bestLeft >= 0)
        s << "; " << bestCancelled << " dislocations of the lattice cancelled before extraction (" << bestLeft << " left)";
      else if (cancelling)
        s << "; the lattice with its dislocations cancelled left regions that are no disks on the field mesh: extracted "
             "as the position field left it, its dislocations kept";
      s << "; " << flips << " edges flipped towards valence 6";
      t.notes.push_back(s.str());
      for (std::string& note : best.notes) t.notes.push_back(std::move(note));
      return t;
    } catch (const Error& e) {
      if (e.code() != ErrorCode::CannotTile || density == 2 || std::string(e.what()).find("non-manifold") == std::string::npos) throw;
    }
  }
}

}  // namespace phex
