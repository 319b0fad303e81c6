// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Progress reporting and cancellation for long runs (as OpenMesh's Decimater Observer).

#include <functional>
#include <stdexcept>
#include <string_view>

namespace nurbsfront {

//! Called with the stage's name and its completed fraction in [0, 1]. Return false to
//! cancel: the running operation then throws Cancelled at its next check.
using ProgressCallback = std::function<bool(std::string_view stage, double fraction)>;

//! Thrown when a ProgressCallback asked to stop.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("nurbsfront: cancelled by the progress callback") {}
};

//! Reports progress if a callback is set; throws Cancelled if it returns false.
inline void report_progress(const ProgressCallback& callback, std::string_view stage, double fraction) {
  if (callback && !callback(stage, fraction)) throw Cancelled();
}

}  // namespace nurbsfront
