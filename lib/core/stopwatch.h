// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Wall-clock timing for stage reports.

#include <chrono>

namespace nurbsfront {

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  void restart() { start_ = std::chrono::steady_clock::now(); }
  //! Seconds since construction or the last restart().
  [[nodiscard]] double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace nurbsfront
