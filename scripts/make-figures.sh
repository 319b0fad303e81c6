#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Makes the before/after pictures of docs/images/: the DRAM cell (built-in scene, 128 cells),
# a CT surface (VTK headsq, skin at iso 500) and the Stanford bunny (../shared/data; skipped
# with a note when absent). For each: the marching-cubes input, nurbsfront's remeshed surface
# and OpenMesh's decimater at the same vertex count, coloured by alpha (nurbsfront render),
# and alpha histograms of nurbsfront against the input and against the decimater
# (nurbsfront histogram). The meshes come from bench_compare --report --write-dir.
# Usage: scripts/make-figures.sh [BUILD_DIR (default build-rel)]; needs a configured build with
# benchmarks (scripts/build.sh build-rel Release). REUSE=1 redraws from the meshes of a previous run.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-rel}
cmake --build "$build" -j2 --target nurbsfront_cli bench_compare
tool="$build/tools/nurbsfront"
work="$build/figures"
img=docs/images
mkdir -p "$work" "$img"
if [[ "${REUSE:-0}" == 1 && -f "$work/figures_table.md" ]]; then
  echo "make-figures: reusing the meshes in $work (REUSE=1)"
else
  "$build/bench/compare/bench_compare" --report --filter '^(dram/128|headsq@500|bunny)$' --threads 2 \
    --write-dir "$work" --md "$work/figures_table.md" > /dev/null
fi

# name, mesh prefix, view direction, up direction, title, what the input is
render_set() {
  local name=$1 prefix=$2 view=$3 up=$4 title=$5 what=$6
  if [[ ! -f "$work/${prefix}_input.ply" ]]; then
    echo "make-figures: $name skipped (no input mesh; ../shared/data absent?)"
    return
  fi
  # shellcheck disable=SC2086
  "$tool" render "$work/${prefix}_input.ply" "$img/${name}_mc.svg" --view $view --up $up \
    --title "$title: $what" --width 800
  # shellcheck disable=SC2086
  "$tool" render "$work/${prefix}_nurbsfront.ply" "$img/${name}_nurbsfront.svg" --view $view --up $up \
    --title "$title: nurbsfront remesh" --width 800
  # shellcheck disable=SC2086
  "$tool" render "$work/${prefix}_decimater.ply" "$img/${name}_decimater.svg" --view $view --up $up \
    --title "$title: OpenMesh decimater (quadric), same vertex count" --width 800
  "$tool" histogram "$work/${prefix}_input.ply" "$work/${prefix}_nurbsfront.ply" -o "$img/${name}_hist_mc.svg" \
    --label "$what" --label "nurbsfront" --title "$title: alpha, $what vs nurbsfront"
  "$tool" histogram "$work/${prefix}_decimater.ply" "$work/${prefix}_nurbsfront.ply" -o "$img/${name}_hist_decimater.svg" \
    --label "decimater (quadric)" --label "nurbsfront" --title "$title: alpha, decimater vs nurbsfront (same vertex count)"
}

render_set dram dram_128 "-1 -0.7 -0.9" "0 0 1" "DRAM cell, 128 cells" "marching cubes"
render_set headsq headsq_500 "0 -1 -0.15" "0 0 -1" "CT head (headsq), skin" "marching cubes"
render_set bunny bunny "0 0 -1" "0 1 0" "Stanford bunny" "input scan"
ls -l "$img"
