// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Paths to test data. tests/data/ ships with the repository (see its SOURCES.md);
// ../shared/data may be absent (fresh clone): tests that need it call
// GTEST_SKIP() through shared_data_or_skip().
#include <filesystem>
#include <optional>

namespace nurbsfront::test {

//! <repo>/tests/data/<relative>; fails the test if missing.
std::filesystem::path test_data(const std::filesystem::path& relative);
//! <repo>/../shared/data/<relative> (or $NURBSFRONT_SHARED_DATA/<relative>) if it exists.
std::optional<std::filesystem::path> shared_data(const std::filesystem::path& relative);
//! A fresh, empty temporary directory for a test's output files, unique to this process.
std::filesystem::path temp_dir(const std::string& name);

}  // namespace nurbsfront::test
