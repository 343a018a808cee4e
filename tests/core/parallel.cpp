#include <catch.hpp>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <vector>

#include "phex/error.hpp"
#include "phex/mesh_io.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/parallel.hpp"
#include "phex/pipeline.hpp"
#include "phex/surfaces.hpp"

using namespace phex;

namespace {

// Sets the thread count for a scope, and restores the default after.
struct Threads {
  explicit Threads(int n) { setThreadCount(n); }
  ~Threads() { setThreadCount(0); }
};

MeshInput latticeUpload(const std::string& surface, int faces) {
  const ParametricSurfacePtr s = makeSurface(surface);
  const std::string obj = toObj(latticeTriangulation(*s, cellForFaceCount(*s, faces)).mesh);
  return MeshInput{std::vector<std::uint8_t>(obj.begin(), obj.end()), "obj", surface + ".obj"};
}

// The run's P-Hex mesh and what the report says of it, for comparing runs bit for bit.
struct Outcome {
  Points V;
  std::vector<int> faceSizes, corners;
  std::vector<std::string> notes;
  int iterations;
  double planarity, distance;
};

Outcome outcome(const PipelineResult& r) {
  Outcome o{r.hex.V, {}, {}, r.triangulation.notes, r.solve.iterations, r.metrics.planarityMax,
            r.metrics.surfaceDistanceMax};
  for (int f = 0; f < r.hex.faceCount(); ++f) {
    o.faceSizes.push_back(r.hex.faceSize(f));
    for (int i = 0; i < r.hex.faceSize(f); ++i) o.corners.push_back(r.hex.face(f)[i]);
  }
  return o;
}

void checkSame(const Outcome& a, const Outcome& b) {
  REQUIRE(a.V.rows() == b.V.rows());
  CHECK(a.V == b.V);  // to the bit
  CHECK(a.faceSizes == b.faceSizes);
  CHECK(a.corners == b.corners);
  CHECK(a.notes == b.notes);
  CHECK(a.iterations == b.iterations);
  CHECK(a.planarity == b.planarity);
  CHECK(a.distance == b.distance);
}

}  // namespace

TEST_CASE("parallel: ranges and tasks cover every item once, whatever the thread count") {
  for (int threads : {1, 2, 3, 8}) {
    const Threads scope(threads);
    INFO("threads " << threads);
    for (int n : {0, 1, 7, 100, 5001}) {
      std::vector<std::atomic<int>> seen(n);
      parallelRanges(n, 10, [&](int begin, int end) {
        CHECK(begin <= end);
        for (int i = begin; i < end; ++i) seen[i]++;
      });
      std::vector<std::atomic<int>> done(n);
      parallelTasks(n, [&](int i) { done[i]++; });
      bool once = true;
      for (int i = 0; i < n; ++i) once = once && seen[i] == 1 && done[i] == 1;
      CHECK(once);
    }
    // A part within a part runs, on the thread that asked for it.
    std::vector<std::atomic<int>> inner(4 * 3000);
    parallelTasks(4, [&](int t) {
      parallelRanges(3000, 100, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) inner[t * 3000 + i]++;
      });
    });
    bool once = true;
    for (auto& c : inner) once = once && c == 1;
    CHECK(once);
  }
}

// parallelSort cuts the range into threadCount() parts, sorts them at once and merges them: with a comparator that
// orders every two distinct items it gives std::sort's order, on every thread count and for sizes that do not split
// evenly (and ranges too small to split at all).
TEST_CASE("parallel: parallelSort orders as std::sort does") {
  std::uint64_t state = 12345;
  auto next = [&] { return state = state * 6364136223846793005ULL + 1442695040888963407ULL; };
  for (int n : {0, 1, 4095, 9000, 50001}) {
    std::vector<std::pair<int, int>> items(n);
    for (int i = 0; i < n; ++i) items[i] = {static_cast<int>(next() >> 60), i};  // many equal firsts, unique pairs
    std::vector<std::pair<int, int>> expected = items;
    std::sort(expected.begin(), expected.end(), std::greater<>());
    for (int threads : {1, 2, 3, 8}) {
      Threads scope(threads);
      std::vector<std::pair<int, int>> sorted = items;
      parallelSort(sorted.begin(), sorted.end(), std::greater<>());
      INFO(n << " items on " << threads << " threads");
      CHECK(sorted == expected);
    }
  }
}

TEST_CASE("parallel: the exception of the lowest item that throws reaches the caller, and the next call works") {
  for (int threads : {1, 2, 4}) {
    const Threads scope(threads);
    INFO("threads " << threads);
    CHECK_THROWS_WITH(parallelTasks(6,
                                    [](int i) {
                                      if (i == 2) throw Error(ErrorCode::CannotTile, "item 2");
                                      if (i == 4) throw std::runtime_error("item 4");
                                    }),
                      "item 2");
    CHECK_THROWS_WITH(parallelRanges(10000, 100,
                                     [](int begin, int) {
                                       throw std::runtime_error(begin == 0 ? "the first range" : "a later range");
                                     }),
                      "the first range");
    std::atomic<int> sum{0};
    parallelTasks(5, [&](int i) { sum += i; });
    CHECK(sum == 10);
  }
}

TEST_CASE("parallel: the thread count is checked") {
  CHECK_THROWS_AS(setThreadCount(-1), Error);
  CHECK_THROWS_WITH(setThreadCount(-1), Catch::Contains("threads"));
  setThreadCount(3);
#ifdef __EMSCRIPTEN__
  CHECK(threadCount() == 1);  // built without threads
#else
  CHECK(threadCount() == 3);
#endif
  setThreadCount(1000);
  CHECK(threadCount() <= kMaxThreads);
  setThreadCount(0);
  CHECK(threadCount() >= 1);
}

TEST_CASE("parallel: an uploaded mesh's curvature, and the runs, are the same bits on one thread and on several") {
  // The uploaded bumps: the jet fits of the MeshSurface, trial lays from several starts, Method 2's flow lines
  // and several systems of rows, the surface fit and the measures all run over threads.
  const MeshInput upload = latticeUpload("freeform", 8000);
  std::vector<Outcome> runs;
  std::vector<std::vector<LocalGeometry>> curvature;
  for (int threads : {1, 2, 3}) {
    const Threads scope(threads);
    const MeshSurface surface(readMeshBytes(upload.bytes.data(), upload.bytes.size(), upload.format, upload.name), upload.name);
    curvature.push_back(surface.vertexGeometries());
    clearUploadCache();
    PipelineParams p;
    p.mesh = upload;
    p.faces = 1200;
    runs.push_back(outcome(runPipeline(p)));
    // An analytic surface whose start is chosen among trial lays.
    p = PipelineParams{};
    p.surface = "wave-roof";
    p.faces = 1500;
    runs.push_back(outcome(runPipeline(p)));
  }
  for (std::size_t k = 1; k < curvature.size(); ++k) {
    REQUIRE(curvature[k].size() == curvature[0].size());
    bool same = true;
    for (std::size_t v = 0; v < curvature[0].size(); ++v) {
      const LocalGeometry &a = curvature[0][v], &b = curvature[k][v];
      same = same && a.point == b.point && a.normal == b.normal && a.k1 == b.k1 && a.k2 == b.k2 && a.d1 == b.d1;
    }
    CHECK(same);
  }
  for (std::size_t k = 2; k < runs.size(); ++k) checkSame(runs[k % 2], runs[k]);
}
