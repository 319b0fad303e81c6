#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs, builds (Release) and runs the main job on the built-in example: the DRAM cell
# scene (four cup capacitors over bit and word lines), its marching-cubes surface and
# the quality report. Output files go to ${OUT:-out}/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh build Release -DNURBSFRONT_BUILD_BENCH=OFF
out=${OUT:-out}
mkdir -p "$out"
build/tools/nurbsfront mc --scene dram --res 128 -o "$out/dram_mc.ply"
build/tools/nurbsfront stats "$out/dram_mc.ply" --vtk "$out/dram_mc.vtk"
echo "example: files written to $out/"
