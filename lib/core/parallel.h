// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! The one thread pool of the library: a parallel loop over index chunks.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace nurbsfront::parallel {

//! The thread count of an options field where 0 means every hardware thread.
[[nodiscard]] inline unsigned thread_count(int threads) {
  return threads > 0 ? static_cast<unsigned>(threads) : std::max(1U, std::thread::hardware_concurrency());
}

//! Called on the calling thread with the number of indices done so far (after chunks were
//! finished; the last call reports n); returning false stops the loop.
using Monitor = std::function<bool(std::size_t done)>;

//! How often the calling thread of a monitored for_chunks looks at the progress of its
//! workers (it is woken early only when they end or a task throws).
inline constexpr std::chrono::milliseconds kMonitorPeriod{10};

//! Runs task(begin, end, worker) over [0, n) in chunks of `chunk` indices (the last one may
//! be shorter) on up to `threads` threads, which pull chunks in order from a shared counter.
//! Each index is in exactly one call, but which worker runs it (worker < threads) and how
//! the calls are cut vary: a task writes only the results of its own indices, and
//! per-worker state must not change them, so the results never depend on the thread count.
//!
//! Without a monitor the calling thread is worker 0 and threads - 1 others are started (on
//! one thread the task gets the whole range in one call). With a monitor, `threads`
//! workers are started and the calling thread calls monitor(done) when chunks were
//! finished, looking every kMonitorPeriod (a worker never wakes it per chunk: on loops of
//! thousands of small chunks that hand-off cost more than the chunks); when it returns
//! false the remaining chunks are skipped and false is returned.
//!
//! A thread that cannot start (std::system_error) leaves its share to the threads already
//! running, the calling thread at least (it then works even with a monitor, calling it
//! after each of its chunks). The first exception a task throws is rethrown here once every
//! thread has stopped; the chunks not yet started are skipped.
//! Returns false when the monitor said stop (even at its last call, when every index ran),
//! true otherwise.
//! for_chunks_started_by takes the function that starts a thread (start(f) returns a
//! std::thread running f(); tests make it fail), for_chunks uses std::thread's constructor.
template <class Start, class Task>
bool for_chunks_started_by(const Start& start, std::size_t n, unsigned threads, std::size_t chunk, const Task& task,
                           const Monitor& monitor = {}) {
  if (n == 0) return !monitor || monitor(0);
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t n_chunks = (n + chunk - 1) / chunk;
  const auto n_threads = static_cast<unsigned>(std::min<std::size_t>(std::max(threads, 1U), n_chunks));
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::mutex mutex;
  std::condition_variable changed;
  std::atomic<std::size_t> done{0};  // indices finished
  unsigned running = 0;              // started workers not yet finished (under mutex)
  std::exception_ptr error;
  auto fail = [&](std::exception_ptr e) {
    {
      const std::lock_guard lock(mutex);
      if (!error) error = std::move(e);
      stop = true;
    }
    changed.notify_all();
  };
  // Takes chunks until none is left or the loop stops; `report` is called on the calling
  // thread after each of its chunks (false stops).
  auto work = [&](unsigned worker, const auto& report) {
    try {
      for (;;) {
        if (stop.load()) return;
        const std::size_t c = next.fetch_add(1);
        if (c >= n_chunks) return;
        const std::size_t begin = c * chunk, end = std::min(n, begin + chunk);
        task(begin, end, worker);
        const std::size_t now = done.fetch_add(end - begin) + (end - begin);
        if (!report(now)) {
          stop = true;
          return;
        }
      }
    } catch (...) {
      fail(std::current_exception());
    }
  };
  auto no_report = [](std::size_t) { return true; };
  auto on_thread = [&](unsigned worker) {
    work(worker, no_report);
    {
      const std::lock_guard lock(mutex);
      --running;
    }
    changed.notify_all();
  };
  // Without a monitor, one thread: the whole range in one call.
  if (!monitor && n_threads <= 1) {
    task(std::size_t{0}, n, 0U);
    return true;
  }
  std::vector<std::thread> pool;
  pool.reserve(n_threads);
  for (unsigned w = monitor ? 0U : 1U; w < n_threads && n_threads > 1; ++w) {
    {
      const std::lock_guard lock(mutex);
      ++running;
    }
    try {
      pool.push_back(start([&on_thread, w] { on_thread(w); }));
    } catch (const std::system_error&) {
      const std::lock_guard lock(mutex);
      --running;
      break;  // no more threads: the ones running (and the calling thread) do the rest
    } catch (...) {
      // Anything else (e.g. std::bad_alloc): stop, join the running threads below and
      // rethrow it there; never leave with threads that reference this frame.
      {
        const std::lock_guard lock(mutex);
        --running;
      }
      fail(std::current_exception());
      break;
    }
  }
  bool stopped_by_monitor = false;
  if (!monitor) {
    work(0U, no_report);
  } else if (pool.empty()) {
    // No worker started: the calling thread works and reports after each chunk.
    work(0U, [&](std::size_t now) {
      if (monitor(now)) return true;
      stopped_by_monitor = true;
      return false;
    });
  } else {
    std::unique_lock lock(mutex);
    std::size_t reported = 0;
    for (;;) {
      changed.wait_for(lock, kMonitorPeriod, [&] { return running == 0 || stop.load(); });
      if (stop.load()) break;  // a task failed
      const std::size_t now = done.load();
      if (now == reported) {
        if (running == 0) break;  // the workers ended
        continue;
      }
      reported = now;
      lock.unlock();
      bool go_on = false;
      try {
        go_on = monitor(reported);
      } catch (...) {
        fail(std::current_exception());
      }
      lock.lock();
      if (error) break;
      if (!go_on) {
        stopped_by_monitor = true;
        stop = true;
        break;
      }
      if (reported == n) break;
    }
  }
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  return !stopped_by_monitor;
}

template <class Task>
bool for_chunks(std::size_t n, unsigned threads, std::size_t chunk, const Task& task, const Monitor& monitor = {}) {
  const auto start = [](auto&& f) { return std::thread(std::forward<decltype(f)>(f)); };
  return for_chunks_started_by(start, n, threads, chunk, task, monitor);
}

//! for_chunks with body(i) called for every index i of [0, n): for loops whose index writes
//! only its own results.
template <class Body>
void for_each_index(std::size_t n, unsigned threads, std::size_t chunk, const Body& body) {
  for_chunks(n, threads, chunk, [&body](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) body(i);
  });
}

}  // namespace nurbsfront::parallel
