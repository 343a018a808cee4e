// Benchmark: the structure on a P-Hex mesh (phex/structure.hpp) natively — node axes, the beam layer, the offset
// and the solid model of the torus at about 10k faces (and the cyclide, the hyperboloid), next to the same run's
// pipeline time for that mesh, the yardstick to compare machines by. Measures only; it never fails.
// Usage: phex_bench_structure [faces, default 10000]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "phex/error.hpp"
#include "phex/parallel.hpp"
#include "phex/pipeline.hpp"
#include "phex/structure.hpp"

namespace {

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

template <typename Body>
double median(int runs, Body body) {
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    body();
    ms.push_back(millisecondsSince(start));
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const int faces = argc > 1 ? std::atoi(argv[1]) : 10000;
  std::printf("| surface | faces | pipeline ms | structure ms | axes | beams | solid model | beams/boundary planar | threads |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const char* surface : {"torus", "cyclide", "hyperboloid"}) {
    try {
      phex::PipelineParams p;
      p.surface = surface;
      p.faces = faces;
      phex::runPipeline(p);  // warm-up
      const auto start = std::chrono::steady_clock::now();
      const phex::PipelineResult r = phex::runPipeline(p);
      const double pipeline = millisecondsSince(start);
      phex::StructureOptions o;
      o.offset = 0.05 * r.hex.meanEdgeLength();
      phex::buildStructure(r.hex, o);  // warm-up
      const double total = median(7, [&] { phex::buildStructure(r.hex, o); });
      phex::NodeAxes axes;
      const double axesMs = median(7, [&] { axes = phex::nodeAxes(r.hex); });
      const double beamsMs = median(7, [&] { phex::beamLayer(r.hex, axes, r.hex.meanEdgeLength() / 5); });
      const phex::Structure s = phex::buildStructure(r.hex, o);
      std::printf("| %s | %d | %.0f | %.1f | %.1f | %.1f | %.1f | %d of %d | %d |\n", surface, r.hex.faceCount(), pipeline, total,
                  axesMs, beamsMs, total - axesMs - beamsMs, s.axes.boundaryBeamsPlanar, s.axes.boundaryBeams, phex::threadCount());
    } catch (const phex::Error& e) {
      std::printf("| %s | %d | failed: %s |\n", surface, faces, e.what());
    }
    std::fflush(stdout);
  }
  return 0;
}
