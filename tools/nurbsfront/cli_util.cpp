// SPDX-License-Identifier: BSD-3-Clause
#include "cli_util.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numeric>
#include <vector>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront::cli {

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

ProgressCallback terminal_progress(bool quiet) {
  if (quiet) return {};
  const bool is_tty = isatty(fileno(stderr)) != 0;
  auto last_stage = std::make_shared<std::string>();
  auto last_percent = std::make_shared<int>(-1);
  return [is_tty, last_stage, last_percent](std::string_view stage, double fraction) {
    const int percent = static_cast<int>(fraction * 100.0 + 0.5);
    const bool new_stage = stage != *last_stage;
    if (is_tty) {
      if (new_stage || percent != *last_percent) {
        std::fprintf(stderr, "\r%-24.*s %3d%%", static_cast<int>(stage.size()), stage.data(), percent);
        if (percent >= 100) std::fputc('\n', stderr);
        std::fflush(stderr);
      }
    } else if (new_stage) {
      std::fprintf(stderr, "%.*s ...\n", static_cast<int>(stage.size()), stage.data());
    }
    *last_stage = std::string(stage);
    *last_percent = percent;
    return true;
  };
}

std::string input_self_intersections(const TriMesh& input, unsigned threads) {
  const TriangleSoup soup = to_soup(input);
  const auto pairs = self_intersecting_pairs(soup, threads);
  if (pairs.empty()) return "";
  // Components through shared vertices (union-find, lowest index as representative).
  std::vector<std::uint32_t> parent(soup.points.size());
  std::iota(parent.begin(), parent.end(), std::uint32_t{0});
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& t : soup.triangles) {
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find(t[0]), b = find(t[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::size_t n_between = 0;
  for (const auto& [f, g] : pairs) n_between += find(soup.triangles[f][0]) != find(soup.triangles[g][0]) ? 1 : 0;
  return "the input surface itself has " + std::to_string(pairs.size()) + " self-intersecting triangle pairs (" +
         std::to_string(n_between) +
         " between different components), so the remeshed surface cannot be free of them; separate or repair "
         "the overlapping parts first (`nurbsfront stats --clean` lists the input's components)";
}

void print_error(std::string_view message) {
  // Many library messages start with "nurbsfront: " already: the prefix once.
  constexpr std::string_view kPrefix = "nurbsfront: ";
  if (message.starts_with(kPrefix)) message.remove_prefix(kPrefix.size());
  std::cerr << "nurbsfront: error: " << message << '\n';
}

}  // namespace nurbsfront::cli
