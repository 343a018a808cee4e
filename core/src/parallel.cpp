#include "phex/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <exception>
#include <string>
#include <system_error>
#include <vector>

#include "phex/error.hpp"

#if !defined(__EMSCRIPTEN__) || defined(__EMSCRIPTEN_PTHREADS__)
#define PHEX_HAS_THREADS 1
#include <condition_variable>
#include <mutex>
#include <thread>
#endif

namespace phex {

namespace {

std::atomic<int> chosen{0};  // setThreadCount's value; 0: the default

int defaultThreads() {
#ifdef PHEX_HAS_THREADS
  // Set but not a count ("abc", "-1", "2x") is an error, as --threads' is: ignoring it would run on another
  // count than the one asked for without a word.
  if (const char* env = std::getenv("PHEX_THREADS"); env && *env) {
    char* end = nullptr;
    errno = 0;
    const long n = std::strtol(env, &end, 10);
    if (end == env || *end != '\0' || errno == ERANGE || n < 0)
      throw Error(ErrorCode::InvalidParameter, "the PHEX_THREADS environment variable is '" + std::string(env) +
                                                   "': it must be a whole number, 0 (the default) or at least 1");
    if (n >= 1) return static_cast<int>(std::min<long>(n, kMaxThreads));
  }
  const unsigned hardware = std::thread::hardware_concurrency();
  return std::clamp(static_cast<int>(hardware), 1, kMaxThreads);
#else
  return 1;
#endif
}

#ifdef PHEX_HAS_THREADS
// Whether this thread runs inside a parallel part: parts within it (the closest points of a trial lay laid
// beside others) run on it in turn rather than start threads of their own.
thread_local bool inParallel = false;

// Marks the calling thread as inside a parallel part while it lives.
struct InParallel {
  bool was = inParallel;
  InParallel() { inParallel = true; }
  ~InParallel() { inParallel = was; }
};
#endif

#ifdef PHEX_HAS_THREADS
// Threads started once and kept (a lay asks for a parallel part per layer, hundreds per lay: starting threads
// for each cost about as much as they saved). run(workers, work) hands work(1 .. workers - 1) to them and runs
// work(0) on the calling thread. One caller at a time; another (phex called from two threads of its own)
// runs its part on its own thread, item after item.
class Pool {
 public:
  ~Pool() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }

  void run(int workers, const std::function<void(int)>& work) {
    std::unique_lock<std::mutex> busy(busy_, std::try_to_lock);
    if (!busy.owns_lock()) {
      for (int k = 0; k < workers; ++k) work(k);
      return;
    }
    int started;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      // A thread that cannot be started (the system's limit) leaves its share to the calling thread.
      while (static_cast<int>(threads_.size()) < workers - 1) {
        try {
          threads_.emplace_back([this, id = static_cast<int>(threads_.size()) + 1] { loop(id); });
        } catch (const std::system_error&) {
          break;
        }
      }
      started = std::min(workers - 1, static_cast<int>(threads_.size()));
      job_ = &work;
      participants_ = started;
      pending_ = started;
      ++generation_;
    }
    wake_.notify_all();
    {
      const InParallel mark;
      work(0);
      for (int k = started + 1; k < workers; ++k) work(k);
    }
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return pending_ == 0; });
    job_ = nullptr;
  }

 private:
  void loop(int id) {
    inParallel = true;
    long seen = 0;
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return quit_ || generation_ != seen; });
      if (quit_) return;
      seen = generation_;
      if (id > participants_) continue;
      const std::function<void(int)>* job = job_;
      lock.unlock();
      (*job)(id);
      lock.lock();
      if (--pending_ == 0) done_.notify_all();
    }
  }

  std::mutex busy_, mutex_;
  std::condition_variable wake_, done_;
  std::vector<std::thread> threads_;
  const std::function<void(int)>* job_ = nullptr;
  int participants_ = 0, pending_ = 0;
  long generation_ = 0;
  bool quit_ = false;
};
#endif

// Runs work(k) for k in [0, workers), work(0) on the calling thread, and waits.
void runWorkers(int workers, const std::function<void(int)>& work) {
#ifdef PHEX_HAS_THREADS
  if (workers == 1) return work(0);
  static Pool pool;
  pool.run(workers, work);
#else
  for (int k = 0; k < workers; ++k) work(k);
#endif
}

}  // namespace

int threadCount() {
#ifdef PHEX_HAS_THREADS
  if (inParallel) return 1;
  const int n = chosen.load(std::memory_order_relaxed);
  if (n > 0) return n;
  static const int fallback = defaultThreads();
  return fallback;
#else
  return 1;
#endif
}

void setThreadCount(int n) {
  if (n < 0) throw Error(ErrorCode::InvalidParameter, "threads must be 0 (the default) or at least 1 (got " + std::to_string(n) + ")");
  chosen.store(std::min(n, kMaxThreads), std::memory_order_relaxed);
}

void parallelRanges(int n, int grain, const std::function<void(int, int)>& body) {
  if (n <= 0) return;
  const int ranges = std::clamp(n / std::max(grain, 1), 1, threadCount());
  if (ranges == 1) return body(0, n);
  std::vector<std::exception_ptr> failed(ranges);
  runWorkers(ranges, [&](int k) {
    try {
      body(static_cast<int>(static_cast<long long>(n) * k / ranges), static_cast<int>(static_cast<long long>(n) * (k + 1) / ranges));
    } catch (...) {
      failed[k] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
}

void parallelTasks(int n, const std::function<void(int)>& task) {
  if (n <= 0) return;
  const int workers = std::min(n, threadCount());
  std::vector<std::exception_ptr> failed(n);
  // Items are taken in order, so once one has thrown, those not yet started (all above it) are skipped: the
  // lowest item that throws has always run, whatever the count.
  std::atomic<bool> stop{false};
  std::atomic<int> next{0};
  runWorkers(workers, [&](int) {
    for (int i; !stop.load() && (i = next.fetch_add(1)) < n;) {
      try {
        task(i);
      } catch (...) {
        failed[i] = std::current_exception();
        stop.store(true);
      }
    }
  });
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
}

}  // namespace phex
