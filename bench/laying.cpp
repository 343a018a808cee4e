// Benchmark: laying triangulations (§5.2) — about 100k triangles on the analytic torus with both methods, and
// about 200k triangles on an uploaded mesh (a sampled torus as a MeshSurface). Measures only; it never fails.
// Usage: phex_bench_laying [scale, default 1: multiplies the triangle counts]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "phex/error.hpp"
#include "phex/laying.hpp"
#include "phex/triangulation.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/surfaces.hpp"

namespace {

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void lay(const char* label, const phex::Surface& surface, phex::LayingOptions options) {
  const auto start = std::chrono::steady_clock::now();
  try {
    const phex::Triangulation t = phex::layTriangulation(surface, options);
    std::printf("%-44s cell %.4f: %7d triangles, %6d vertices in %8.1f ms\n", label, options.cell,
                static_cast<int>(t.mesh.F.rows()), static_cast<int>(t.mesh.V.rows()), millisecondsSince(start));
  } catch (const phex::Error& e) {
    std::printf("%-44s cell %.4f: failed after %.1f ms: %s\n", label, options.cell, millisecondsSince(start), e.what());
  }
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  const double scale = argc > 1 ? std::atof(argv[1]) : 1.0;
  const phex::ParametricSurfacePtr torus = phex::makeSurface("torus");  // R = 1, r = 0.4
  // Triangle counts: two triangles per vertex of a regular triangulation.
  auto cellForTriangles = [&](double triangles) { return phex::cellForFaceCount(*torus, static_cast<int>(triangles / 2)); };

  phex::LayingOptions o;
  o.start = phex::Vec3(0.87, 0, 0.38);
  o.cell = cellForTriangles(100000 * scale);
  o.method = phex::LayingMethod::Progressive;
  lay("analytic torus, progressive (Method 1)", *torus, o);
  o.method = phex::LayingMethod::Prespecified;
  lay("analytic torus, prespecified (Method 2)", *torus, o);

  // The uploaded mesh: the torus sampled as a 200k-triangle lattice (100000 scale vertices).
  const phex::TriMesh m = phex::latticeTriangulation(*torus, cellForTriangles(200000 * scale)).mesh;
  auto start = std::chrono::steady_clock::now();
  const phex::MeshSurface mesh(m, "sampled torus");
  std::printf("MeshSurface of %d triangles built (curvature, tree) in %.1f ms\n", static_cast<int>(m.F.rows()),
              millisecondsSince(start));
  o.cell = cellForTriangles(200000 * scale);
  o.method = phex::LayingMethod::Progressive;
  lay("uploaded mesh, progressive (Method 1)", mesh, o);
  o.method = phex::LayingMethod::Prespecified;
  lay("uploaded mesh, prespecified (Method 2)", mesh, o);
  return 0;
}
