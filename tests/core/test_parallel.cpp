// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/team.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "nurbsfront/core/error.h"

namespace nurbsfront {
namespace {

// A result per index that takes a little work (so chunks overlap in time).
double value_of(std::size_t i) {
  double x = static_cast<double>(i);
  for (int k = 0; k < 50; ++k) x = std::sin(x) + 0.5 * x;
  return x;
}

std::vector<double> run(unsigned threads, std::size_t n, std::size_t chunk, std::vector<int>& calls_per_index,
                        unsigned& max_worker) {
  std::vector<double> out(n, 0.0);
  calls_per_index.assign(n, 0);
  std::atomic<unsigned> highest{0};
  const bool finished = parallel::for_chunks(n, threads, chunk, [&](std::size_t begin, std::size_t end, unsigned worker) {
    unsigned seen = highest.load();
    while (worker > seen && !highest.compare_exchange_weak(seen, worker)) {
    }
    for (std::size_t i = begin; i < end; ++i) {
      out[i] = value_of(i);
      ++calls_per_index[i];
    }
  });
  EXPECT_TRUE(finished);
  max_worker = highest.load();
  return out;
}

TEST(Parallel, EveryIndexOnceAndTheSameResultsForAnyThreadCount) {
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
    std::vector<int> calls;
    unsigned max_worker = 0;
    const auto reference = run(1, 2001, chunk, calls, max_worker);
    EXPECT_EQ(max_worker, 0U);
    for (const unsigned threads : {2U, 3U, 8U}) {
      const auto out = run(threads, 2001, chunk, calls, max_worker);
      EXPECT_EQ(out, reference) << "threads " << threads << " chunk " << chunk;
      for (const int c : calls) ASSERT_EQ(c, 1);
      EXPECT_LT(max_worker, threads);
    }
  }
  // Nothing to do: no call.
  int n_calls = 0;
  EXPECT_TRUE(parallel::for_chunks(0, 4, 1, [&](std::size_t, std::size_t, unsigned) { ++n_calls; }));
  EXPECT_EQ(n_calls, 0);
}

// Two chunks on two threads: each call waits (up to a timeout, so a pool that runs one
// worker fails instead of hanging) until both calls have arrived. Both can arrive only when
// two threads run the task at the same time; their thread ids and worker numbers differ.
TEST(Parallel, TwoWorkersRunAtTheSameTime) {
  for (const bool with_monitor : {false, true}) {
    std::mutex mutex;
    std::condition_variable arrived_changed;
    int arrived = 0;
    int met = 0;  // calls that saw both arrivals before the timeout
    std::vector<std::thread::id> ids;
    std::vector<unsigned> workers;
    auto task = [&](std::size_t, std::size_t, unsigned worker) {
      std::unique_lock lock(mutex);
      ++arrived;
      ids.push_back(std::this_thread::get_id());
      workers.push_back(worker);
      arrived_changed.notify_all();
      if (arrived_changed.wait_for(lock, std::chrono::seconds(20), [&] { return arrived >= 2; })) ++met;
    };
    const parallel::Monitor monitor = with_monitor ? parallel::Monitor([](std::size_t) { return true; }) : nullptr;
    EXPECT_TRUE(parallel::for_chunks(2, 2, 1, task, monitor));
    EXPECT_EQ(met, 2) << "with monitor " << with_monitor;
    ASSERT_EQ(ids.size(), 2U);
    EXPECT_NE(ids[0], ids[1]);
    EXPECT_NE(workers[0], workers[1]);
    if (with_monitor) {  // every chunk on a started thread
      EXPECT_NE(ids[0], std::this_thread::get_id());
      EXPECT_NE(ids[1], std::this_thread::get_id());
    }
  }
}

TEST(Parallel, WorkerExceptionReachesTheCaller) {
  // With a monitor every chunk runs on a started thread, never on the calling one.
  const auto caller = std::this_thread::get_id();
  std::atomic<bool> thrown_off_caller{false};
  auto task = [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      if (i == 37) {
        thrown_off_caller = std::this_thread::get_id() != caller;
        throw std::runtime_error("index 37");
      }
    }
  };
  EXPECT_THROW(parallel::for_chunks(100, 2, 1, task, [](std::size_t) { return true; }), std::runtime_error);
  EXPECT_TRUE(thrown_off_caller.load());
  // Without a monitor (the calling thread works too) and on one thread.
  for (const unsigned threads : {1U, 2U, 4U}) {
    EXPECT_THROW(parallel::for_chunks(100, threads, 3, task), std::runtime_error) << threads;
  }
}

TEST(Parallel, MonitorSeesProgressAndMayStop) {
  for (const unsigned threads : {1U, 2U}) {
    std::vector<std::size_t> seen;
    std::atomic<std::size_t> n_run{0};
    const bool finished = parallel::for_chunks(
        50, threads, 2, [&](std::size_t begin, std::size_t end, unsigned) { n_run += end - begin; },
        [&](std::size_t done) {
          seen.push_back(done);  // always on the calling thread
          return true;
        });
    EXPECT_TRUE(finished);
    EXPECT_EQ(n_run.load(), 50U);
    ASSERT_FALSE(seen.empty());
    EXPECT_EQ(seen.back(), 50U);
    for (std::size_t k = 1; k < seen.size(); ++k) EXPECT_LT(seen[k - 1], seen[k]);
    // Stopping after the first report: false returned, not every index run.
    n_run = 0;
    const bool stopped = !parallel::for_chunks(
        1000, threads, 1,
        [&](std::size_t begin, std::size_t end, unsigned) {
          n_run += end - begin;
          std::this_thread::sleep_for(std::chrono::microseconds(200));
        },
        [](std::size_t) { return false; });
    EXPECT_TRUE(stopped);
    EXPECT_LT(n_run.load(), 1000U);
  }
}

// The workers do not wake the monitoring thread per chunk: 20 000 chunks of about a
// microsecond give at most one monitor call per kMonitorPeriod (and a last one with n).
// Woken per chunk (main 5f97e4a), it was called hundreds of times in such a loop.
TEST(Parallel, MonitorLooksEveryPeriodNotEveryChunk) {
  constexpr std::size_t n = 20000;
  std::vector<double> out(n, 0.0);
  std::size_t n_calls = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const bool finished = parallel::for_chunks(
      n, 2, 1, [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) out[i] = value_of(i);
      },
      [&](std::size_t) {
        ++n_calls;
        return true;
      });
  const auto elapsed = std::chrono::steady_clock::now() - t0;
  EXPECT_TRUE(finished);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(out[i], value_of(i));
  EXPECT_GE(n_calls, 1U);
  EXPECT_LE(n_calls, 2 + static_cast<std::size_t>(elapsed / parallel::kMonitorPeriod)) << n_calls;
}

TEST(Parallel, FailedThreadStartLeavesTheWorkToTheRunningThreads) {
  for (const int n_starts : {0, 1}) {  // threads that start before the failure
    for (const bool with_monitor : {false, true}) {
      int started = 0;
      auto start = [&](auto&& f) {
        if (started >= n_starts) throw std::system_error(std::make_error_code(std::errc::resource_unavailable_try_again));
        ++started;
        return std::thread(std::forward<decltype(f)>(f));
      };
      std::vector<int> calls(500, 0);
      std::mutex mutex;
      auto task = [&](std::size_t begin, std::size_t end, unsigned worker) {
        EXPECT_LT(worker, 4U);
        const std::lock_guard lock(mutex);
        for (std::size_t i = begin; i < end; ++i) ++calls[i];
      };
      const parallel::Monitor monitor = with_monitor ? parallel::Monitor([](std::size_t) { return true; }) : nullptr;
      EXPECT_TRUE(parallel::for_chunks_started_by(start, calls.size(), 4, 5, task, monitor));
      EXPECT_EQ(started, n_starts);
      for (const int c : calls) ASSERT_EQ(c, 1) << n_starts << " " << with_monitor;
    }
  }
}

// One team, many loops of varying size and chunk (most of them small, as segment's fold
// splits): every index once, the one-thread results, worker numbers below the thread count.
TEST(ParallelTeam, ManyLoopsGiveTheResultsOfOneThread) {
  for (const unsigned threads : {1U, 2U, 3U, 8U}) {
    parallel::Team team(threads);
    EXPECT_EQ(team.threads(), threads);
    for (int loop = 0; loop < 300; ++loop) {
      const auto n = static_cast<std::size_t>((loop * 7) % 41);
      const std::size_t chunk = 1 + static_cast<std::size_t>(loop % 3);
      std::vector<double> out(n, 0.0);
      std::vector<int> calls(n, 0);
      std::atomic<unsigned> highest{0};
      team.for_chunks(n, chunk, [&](std::size_t begin, std::size_t end, unsigned worker) {
        unsigned seen = highest.load();
        while (worker > seen && !highest.compare_exchange_weak(seen, worker)) {
        }
        for (std::size_t i = begin; i < end; ++i) {
          out[i] = value_of(i);
          ++calls[i];
        }
      });
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_EQ(calls[i], 1) << threads << " " << loop << " " << i;
        ASSERT_EQ(out[i], value_of(i));
      }
      EXPECT_LT(highest.load(), threads);
    }
  }
  EXPECT_THROW(parallel::Team(0), InvalidInput);
}

// The team's workers run: two chunks that wait for each other (with a timeout, so one
// thread fails instead of hanging) meet on two threads, in each of several loops.
TEST(ParallelTeam, TwoWorkersRunAtTheSameTimeInEveryLoop) {
  parallel::Team team(2);
  for (int loop = 0; loop < 5; ++loop) {
    std::mutex mutex;
    std::condition_variable arrived_changed;
    int arrived = 0, met = 0;
    std::vector<std::thread::id> ids;
    team.for_chunks(2, 1, [&](std::size_t, std::size_t, unsigned) {
      std::unique_lock lock(mutex);
      ++arrived;
      ids.push_back(std::this_thread::get_id());
      arrived_changed.notify_all();
      if (arrived_changed.wait_for(lock, std::chrono::seconds(20), [&] { return arrived >= 2; })) ++met;
    });
    ASSERT_EQ(met, 2) << "loop " << loop << ": a worker did not run beside the caller within 20 s";
    ASSERT_EQ(ids.size(), 2U);
    EXPECT_NE(ids[0], ids[1]);
  }
}

// A task's exception reaches the caller (from either thread), and the team's next loops run
// every index again.
TEST(ParallelTeam, ExceptionReachesTheCallerAndLaterLoopsRun) {
  for (const unsigned threads : {1U, 2U, 4U}) {
    parallel::Team team(threads);
    for (const std::size_t thrower : {std::size_t{0}, std::size_t{37}, std::size_t{99}}) {
      EXPECT_THROW(team.for_chunks(100, 3,
                                   [&](std::size_t begin, std::size_t end, unsigned) {
                                     for (std::size_t i = begin; i < end; ++i)
                                       if (i == thrower) throw std::runtime_error("index");
                                   }),
                   std::runtime_error)
          << threads << " " << thrower;
      std::vector<int> calls(100, 0);
      team.for_chunks(100, 3, [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) ++calls[i];
      });
      for (const int c : calls) ASSERT_EQ(c, 1) << threads << " " << thrower;
    }
  }
}

}  // namespace
}  // namespace nurbsfront
