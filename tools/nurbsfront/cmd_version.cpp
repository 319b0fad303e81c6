// SPDX-License-Identifier: BSD-3-Clause
#include <iostream>

#include "commands.h"

namespace nurbsfront::cli {

void add_version_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("version", "Print the version");
  cmd->callback([] { std::cout << "nurbsfront 0.1.0\n"; });
}

}  // namespace nurbsfront::cli
