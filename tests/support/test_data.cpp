// SPDX-License-Identifier: BSD-3-Clause
#include "support/test_data.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace nurbsfront::test {

std::filesystem::path test_data(const std::filesystem::path& relative) {
  auto path = std::filesystem::path(NURBSFRONT_SOURCE_DIR) / "tests" / "data" / relative;
  EXPECT_TRUE(std::filesystem::exists(path)) << "missing test data file " << path;
  return path;
}

std::optional<std::filesystem::path> shared_data(const std::filesystem::path& relative) {
  // NURBSFRONT_SHARED_DATA overrides the location (a worktree is not next to ../shared).
  const char* root = std::getenv("NURBSFRONT_SHARED_DATA");
  auto path = (root != nullptr && *root != '\0' ? std::filesystem::path(root)
                                                 : std::filesystem::path(NURBSFRONT_SOURCE_DIR).parent_path() / "shared" / "data") /
              relative;
  if (std::filesystem::exists(path)) return path;
  return std::nullopt;
}

std::filesystem::path temp_dir(const std::string& name) {
  // Unique per process: ctest runs tests of one runner in parallel processes.
  auto path = std::filesystem::temp_directory_path() /
              ("nurbsfront_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(path);
  std::filesystem::create_directories(path);
  return path;
}

}  // namespace nurbsfront::test
