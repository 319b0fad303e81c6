// SPDX-License-Identifier: BSD-3-Clause
#include "cli_util.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <iostream>
#include <memory>

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

void print_error(std::string_view message) {
  std::cerr << "nurbsfront: error: " << message << '\n';
}

}  // namespace nurbsfront::cli
