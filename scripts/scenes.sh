#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Remeshes the built-in scenes of docs/pipeline.md "What it meets" (default options, one
# thread) and prints that page's table. Usage: scripts/scenes.sh [BUILD_DIR] [OUT_DIR]
# BUILD_DIR defaults to build-rel (a Release build: scripts/build.sh build-rel), OUT_DIR to
# out/scenes (meshes and JSON reports). Takes about a minute (DRAM 256 included).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${1:-build-rel}
out_dir=${2:-out/scenes}
tool="$build_dir/tools/nurbsfront"
[ -x "$tool" ] || { echo "scenes: $tool not found; build first (scripts/build.sh $build_dir)" >&2; exit 1; }
mkdir -p "$out_dir"
runs=(
  "sphere 128 levelset" "sphere 128 occupancy" "torus 128 levelset" "torus 128 occupancy"
  "trench 128 levelset" "trench 128 occupancy" "dram 128 levelset" "dram 128 occupancy"
  "dram 256 levelset" "dram 256 occupancy"
)
reports=()
for run in "${runs[@]}"; do
  read -r scene res kind <<< "$run"
  name="${scene}_${res}_${kind}"
  flags=()
  [ "$kind" = occupancy ] && flags+=(--occupancy)
  "$tool" remesh --scene "$scene" --res "$res" "${flags[@]}" "$out_dir/$name.ply" -q \
    --threads 1 --report "$out_dir/$name.json" > /dev/null
  reports+=("$out_dir/$name.json")
done
python3 scripts/scenes_table.py "${reports[@]}"
