// phex — threads for work that splits into independent parts (native builds; WebAssembly runs them in turn).
#pragma once
#include <algorithm>
#include <functional>
#include <vector>

namespace phex {

// How many threads phex uses: setThreadCount(n) for n >= 1, else the PHEX_THREADS environment variable,
// else the hardware's threads (at most kMaxThreads); a PHEX_THREADS that is not a whole number >= 0 makes
// threadCount (and so any run) throw InvalidParameter naming it. Always 1 in WebAssembly, which phex builds without
// threads. Every parallel part computes exactly what one thread computes (each item on its own, written to
// its own place, combined in order afterwards), so the meshes do not depend on the count.
constexpr int kMaxThreads = 8;
// The grain of loops over points or faces of about a microsecond each (closest points, jet fits, measures):
// a thread takes at least this many, so that small meshes stay on one.
constexpr int kPointsPerThread = 2000;
int threadCount();
// n >= 1 sets the count (capped at kMaxThreads), 0 restores the default; other values throw InvalidParameter.
void setThreadCount(int n);

// body(begin, end) over [0, n) split into at most threadCount() contiguous ranges of at least `grain` items
// each, run at once (the caller's thread takes the first). For loops of many small items that want scratch
// space of their own per range. Waits for all; then rethrows the exception of the first range that threw.
void parallelRanges(int n, int grain, const std::function<void(int begin, int end)>& body);

// task(i) for i in [0, n), each item taken by the next free thread: for a few large items of unequal cost
// (trial lays). Waits for all; then rethrows the exception of the lowest item that threw.
void parallelTasks(int n, const std::function<void(int i)>& task);

// std::sort(begin, end, less) over threads: the range cut into threadCount() parts sorted at once (parallelTasks),
// then merged pairwise. Where `less` orders every two distinct items (no ties), the result is std::sort's.
template <typename It, typename Less>
void parallelSort(It begin, It end, Less less) {
  const long n = static_cast<long>(end - begin);
  int parts = threadCount();
  while (parts > 1 && n < 4096L * parts) --parts;  // small ranges stay on one thread
  if (parts <= 1) {
    std::sort(begin, end, less);
    return;
  }
  std::vector<It> cut(parts + 1);
  for (int k = 0; k <= parts; ++k) cut[k] = begin + n * k / parts;
  parallelTasks(parts, [&](int k) { std::sort(cut[k], cut[k + 1], less); });
  for (int width = 1; width < parts; width *= 2)
    for (int k = 0; k + width < parts; k += 2 * width)
      std::inplace_merge(cut[k], cut[k + width], cut[std::min(k + 2 * width, parts)], less);
}

}  // namespace phex
