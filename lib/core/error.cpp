// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/core/error.h"

namespace nurbsfront::detail {

void assertion_failed(const char* condition, const char* file, int line) {
  throw InternalError(std::string("nurbsfront internal error: assertion '") + condition +
                      "' failed at " + file + ":" + std::to_string(line));
}

}  // namespace nurbsfront::detail
