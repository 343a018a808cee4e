// Benchmark: read a 1M-triangle binary STL and build its MeshSurface (curvature tensors + AABB tree).
// Measures only; it never fails. Usage: phex_bench_mesh_curvature [triangles-in-thousands, default 1000]
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <vector>

#include "phex/mesh_io.hpp"
#include "phex/mesh_surface.hpp"

namespace {

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// A torus (R = 1, r = 0.4) on an nu x nv grid with slightly jittered vertices: 2 nu nv triangles,
// written as binary STL (each triangle stores its three corners, so reading it has to weld them).
void writeTorusStl(const std::string& path, int nu, int nv) {
  const double pi = 3.141592653589793;
  std::vector<float> xyz(3 * static_cast<std::size_t>(nu) * nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * pi * (i + 0.2 * std::sin(7.1 * i + 3.3 * j)) / nu;
      const double v = 2 * pi * (j + 0.2 * std::cos(5.3 * i + 2.9 * j)) / nv;
      float* p = &xyz[3 * (static_cast<std::size_t>(i) * nv + j)];
      p[0] = static_cast<float>((1 + 0.4 * std::cos(v)) * std::cos(u));
      p[1] = static_cast<float>((1 + 0.4 * std::cos(v)) * std::sin(u));
      p[2] = static_cast<float>(0.4 * std::sin(v));
    }
  const std::uint32_t count = 2u * nu * nv;
  std::vector<char> bytes(84 + 50 * static_cast<std::size_t>(count), 0);
  std::memcpy(bytes.data(), "phex benchmark torus", 20);
  std::memcpy(bytes.data() + 80, &count, 4);
  char* out = bytes.data() + 84;
  auto id = [&](int i, int j) { return static_cast<std::size_t>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const std::size_t t[2][3] = {{id(i, j), id(i + 1, j), id(i + 1, j + 1)}, {id(i, j), id(i + 1, j + 1), id(i, j + 1)}};
      for (const auto& tri : t) {
        for (int k = 0; k < 3; ++k) std::memcpy(out + 12 + 12 * k, &xyz[3 * tri[k]], 12);
        out += 50;
      }
    }
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
  const double thousands = argc > 1 ? std::atof(argv[1]) : 1000;
  const int nv = 500, nu = static_cast<int>(std::lround(thousands * 1000 / (2.0 * nv)));
  const std::string path = "/tmp/phex_bench_mesh_curvature.stl";
  writeTorusStl(path, nu, nv);

  auto start = std::chrono::steady_clock::now();
  phex::MeshReadReport report;
  phex::TriMesh mesh = phex::readMesh(path, &report);
  const double readMs = millisecondsSince(start);
  auto built = std::chrono::steady_clock::now();
  const phex::MeshSurface surface(std::move(mesh), "torus");
  const double surfaceMs = millisecondsSince(built);
  const double totalMs = millisecondsSince(start);

  const int queries = 100000;
  auto queried = std::chrono::steady_clock::now();
  double sum = 0;
  for (int q = 0; q < queries; ++q) {
    const double a = 0.0001 * q, b = 0.00037 * q;
    sum += surface.closestPoint(phex::Vec3(1.2 * std::cos(a), 1.2 * std::sin(a), 0.3 * std::sin(b))).k1;
  }
  const double queryUs = millisecondsSince(queried) * 1000 / queries;

  std::printf("mesh: %d triangles, %d vertices (welded from %d corners)\n", static_cast<int>(surface.mesh().F.rows()),
              surface.vertexCount(), 3 * report.fileTriangles);
  std::printf("readMesh (binary STL):            %8.1f ms\n", readMs);
  std::printf("MeshSurface (curvature + tree):   %8.1f ms\n", surfaceMs);
  std::printf("total load + curvature:           %8.1f ms\n", totalMs);
  std::printf("closestPoint:                     %8.2f us per query (checksum %.6g)\n", queryUs, sum);
  return 0;
}
