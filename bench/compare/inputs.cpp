// SPDX-License-Identifier: BSD-3-Clause
#include "inputs.h"

#include <array>
#include <cstdlib>

#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/isosurface/volume_io.h"

#ifndef NURBSFRONT_SOURCE_DIR
#error "NURBSFRONT_SOURCE_DIR must be defined by the build"
#endif

namespace nurbsfront::bench {

namespace {

TriMesh scene_surface(const std::string& scene, int resolution) {
  const ScalarGrid grid = sample_scene(scene_by_name(scene), resolution, SampleMode::LevelSet);
  return to_trimesh(clean(marching_cubes(grid, scene_marching_cubes_options(SampleMode::LevelSet))).soup);
}

// CT convention (inside above iso), padded so the surface is closed at the grid border.
TriMesh volume_surface(const std::filesystem::path& path, double iso) {
  MarchingCubesOptions options;
  options.iso = iso;
  options.inside_above = true;
  options.pad = true;
  return to_trimesh(clean(marching_cubes(read_volume(path), options)).soup);
}

}  // namespace

std::filesystem::path shared_data_dir() {
  if (const char* env = std::getenv("NURBSFRONT_SHARED_DATA")) return env;
  // <repo>/../shared/data for a clone beside shared/; worktrees sit deeper (wt/<name>), so
  // the nearest ancestor holding shared/data wins.
  const std::filesystem::path source = std::filesystem::path(NURBSFRONT_SOURCE_DIR);
  for (std::filesystem::path dir = source.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (std::filesystem::is_directory(dir / "shared" / "data")) return dir / "shared" / "data";
    if (dir == dir.parent_path()) break;
  }
  return source.parent_path() / "shared" / "data";
}

std::vector<CompareInput> comparison_inputs(std::vector<std::string>& skipped) {
  std::vector<CompareInput> inputs;
  for (const int res : {128, 256}) {
    for (const std::string scene : {"sphere", "torus", "trench", "dram"}) {
      const bool quick = res == 128 && (scene == "sphere" || scene == "dram");
      inputs.push_back({scene + "/" + std::to_string(res),
                        "marching cubes of the built-in " + scene + " scene (signed distance), " +
                            std::to_string(res) + " cells along the longest side",
                        quick, [scene, res] { return scene_surface(scene, res); }});
    }
  }
  const std::filesystem::path repo_data = std::filesystem::path(NURBSFRONT_SOURCE_DIR) / "tests" / "data";
  // The volumes ship in tests/data too (copies of ../shared/data/volumes).
  struct Volume {
    std::string name, file;
    double iso;
    bool quick;
    std::string what;
  };
  for (const Volume& v : std::vector<Volume>{
           {"headsq@500", "volumes/headsq.mha", 500.0, true, "VTK headsq CT (64x64x93), skin, iso 500, padded"},
           {"ironProt@128", "volumes/ironProt.vtk", 128.0, false, "VTK ironProt density (68^3), iso 128, padded"},
           {"liver@127.5", "volumes/liver.inr.gz", 127.5, false,
            "CGAL liver label image (438x353x165), label 255, iso 127.5, padded (staircase)"}}) {
    const std::filesystem::path path = repo_data / v.file;
    inputs.push_back({v.name, v.what, v.quick, [path, iso = v.iso] { return volume_surface(path, iso); }});
  }
  {
    const std::filesystem::path path = repo_data / "io" / "brainImageSmooth.vtk";
    inputs.push_back({"brain", "VTK brainImageSmooth marching-cubes surface (9522 triangles, welded)", true,
                      [path] { return read_mesh(path); }});
  }
  const std::filesystem::path shared = shared_data_dir();
  for (const auto& [name, file, what] : std::vector<std::array<std::string, 3>>{
           {"bunny", "meshes/cgal/bunny00.off", "Stanford bunny (CGAL data, 75408 triangles)"},
           {"fandisk", "meshes/cgal/fandisk.off", "fandisk CAD mesh with creases (CGAL data, 12946 triangles)"}}) {
    const std::filesystem::path path = shared / file;
    if (!std::filesystem::exists(path)) {
      skipped.push_back(name + ": " + path.string() + " is absent (../shared/data not available)");
      continue;
    }
    inputs.push_back({name, what, false, [path] { return read_mesh(path); }});
  }
  return inputs;
}

}  // namespace nurbsfront::bench
