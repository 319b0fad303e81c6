// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! parallel::Team: the threads of parallel::for_chunks kept for a series of small loops.

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "nurbsfront/core/error.h"

namespace nurbsfront::parallel {

//! Threads kept for several loops: `threads` - 1 workers, started at the first loop that
//! has more than one chunk, waiting between loops (the calling thread is worker 0). A loop
//! costs a wake-up instead of starting and joining threads (segment's fold splits: about a
//! thousand small loops on the liver), and a worker that has not woken when the calling
//! thread took the last chunk is not waited for. Owned by its caller (no global state); its
//! loops run one at a time, from the thread that owns it.
class Team {
 public:
  //! \throw InvalidInput when threads is 0.
  explicit Team(unsigned threads) : threads_(threads) {
    if (threads == 0) throw InvalidInput("parallel::Team: the thread count must be >= 1");
  }
  Team(const Team&) = delete;
  Team& operator=(const Team&) = delete;
  ~Team() {
    {
      const std::lock_guard lock(mutex_);
      quit_ = true;
    }
    wake_.notify_all();
    for (auto& t : pool_) t.join();
  }
  [[nodiscard]] unsigned threads() const { return threads_; }

  //! parallel::for_chunks without a monitor, on this team's threads: task(begin, end,
  //! worker) over [0, n) in chunks of `chunk` indices pulled in order (worker < threads();
  //! on one thread, or one chunk, the whole range in one call on the calling thread). The
  //! same contract: a task writes only the results of its own indices. The first exception
  //! a task throws is rethrown here once no worker runs the loop any more; the chunks not
  //! yet started are skipped. Threads that cannot start (std::system_error) leave their
  //! share to the others.
  template <class Task>
  void for_chunks(std::size_t n, std::size_t chunk, const Task& task) {
    if (n == 0) return;
    chunk = std::max<std::size_t>(chunk, 1);
    const std::size_t n_chunks = (n + chunk - 1) / chunk;
    if (threads_ <= 1 || n_chunks <= 1) {
      task(std::size_t{0}, n, 0U);
      return;
    }
    start();
    const Job job{[](const void* t, std::size_t begin, std::size_t end, unsigned worker) {
                    (*static_cast<const Task*>(t))(begin, end, worker);
                  },
                  &task, n, chunk, n_chunks};
    next_ = 0;
    stop_ = false;
    {
      const std::lock_guard lock(mutex_);
      error_ = nullptr;
      job_ = &job;
      ++generation_;
    }
    wake_.notify_all();
    work(job, 0U);
    std::exception_ptr error;
    {
      std::unique_lock lock(mutex_);
      idle_.wait(lock, [&] { return busy_ == 0; });
      job_ = nullptr;
      error = std::move(error_);
      error_ = nullptr;
    }
    if (error) std::rethrow_exception(error);
  }

 private:
  struct Job {
    void (*run)(const void* task, std::size_t begin, std::size_t end, unsigned worker);
    const void* task;
    std::size_t n, chunk, n_chunks;
  };

  // Starts the workers once (those that cannot start are left out).
  void start() {
    if (started_) return;
    started_ = true;
    pool_.reserve(threads_ - 1);
    for (unsigned w = 1; w < threads_; ++w) {
      try {
        pool_.emplace_back([this, w] { worker_loop(w); });
      } catch (const std::system_error&) {
        break;
      }
    }
  }

  // Takes chunks of the job until none is left or a task failed.
  void work(const Job& job, unsigned worker) {
    try {
      for (;;) {
        if (stop_.load()) return;
        const std::size_t c = next_.fetch_add(1);
        if (c >= job.n_chunks) return;
        const std::size_t begin = c * job.chunk;
        job.run(job.task, begin, std::min(job.n, begin + job.chunk), worker);
      }
    } catch (...) {
      const std::lock_guard lock(mutex_);
      if (!error_) error_ = std::current_exception();
      stop_ = true;
    }
  }

  void worker_loop(unsigned worker) {
    std::uint64_t seen = 0;
    std::unique_lock lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return quit_ || (job_ != nullptr && generation_ != seen); });
      if (quit_) return;
      seen = generation_;
      const Job* job = job_;
      ++busy_;
      lock.unlock();
      work(*job, worker);
      lock.lock();
      if (--busy_ == 0) idle_.notify_one();
    }
  }

  unsigned threads_;
  bool started_ = false;
  std::vector<std::thread> pool_;
  std::mutex mutex_;
  std::condition_variable wake_, idle_;
  // Under mutex_: the current loop (null between loops), its number, the workers inside
  // it, the first exception of its tasks, and the request to end.
  const Job* job_ = nullptr;
  std::uint64_t generation_ = 0;
  unsigned busy_ = 0;
  std::exception_ptr error_;
  bool quit_ = false;
  // The current loop's next chunk and its stop flag (set when a task threw).
  std::atomic<std::size_t> next_{0};
  std::atomic<bool> stop_{false};
};

}  // namespace nurbsfront::parallel
