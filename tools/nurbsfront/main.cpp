// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront: command-line front end. Parses arguments into option structs and calls
// the library; no meshing logic lives here.
#include <exception>
#include <iostream>

#include "cli_util.h"
#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"nurbsfront: marching-cubes surfaces to simulation-grade triangle meshes"};
  app.require_subcommand(1);
  nurbsfront::cli::add_all_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    nurbsfront::cli::print_error(e.what());
    return 1;
  }
  return 0;
}
