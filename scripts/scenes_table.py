#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Prints docs/pipeline.md's "What it meets" table from remesh JSON reports named
SCENE_RES_KIND.json (as scripts/scenes.sh writes them)."""
import json
import os
import sys

DRAM_HEIGHT_UM = 3.45  # the DRAM scene's height along z; a voxel is DRAM_HEIGHT_UM / res


def row(path):
    scene, res, kind = os.path.basename(path)[:-len(".json")].split("_")
    r = json.load(open(path))
    out, st = r["output"], r["stitch"]
    topo, dist = out["topology"], out["distance"]
    valid = (r["ok"] and not r["errors"] and topo["closed"] and topo["manifold"]
             and topo["consistently_oriented"] and topo["self_intersecting_pairs"] == 0)
    name = {"sphere": "sphere", "torus": "torus", "trench": "trench", "dram": "DRAM"}[scene]
    kind_text = "level set" if kind == "levelset" else "occupancy"
    h = dist["hausdorff"] / r["input_mean_edge"]
    h_text = f"{h:.2f}"
    if scene == "dram":
        h_text += f" ({dist['hausdorff'] / (DRAM_HEIGHT_UM / int(res)):.2f} voxel)"
    faces = f"{topo['faces']:,}".replace(",", " ")
    cells = [
        f"{name}, {kind_text}, {res}", faces,
        f"{out['alpha']['mean']:.3f} / {out['alpha']['min']:.3f}",
        f"{out['angles']['min']:.1f} / {out['angles']['max']:.1f}",
        f"{st['min_angle_away_from_features_deg']:.1f} ({st['small_angle_away_from_features']})",
        f"{100 * out['angles']['obtuse_fraction']:.2f}%", h_text,
        f"{100 * dist['relative_volume_change']:+.2f}%",
    ]
    line = "| " + " | ".join(cells) + " |"
    if not valid:
        line += f" INVALID (euler {topo['euler_characteristic']}, errors {len(r['errors'])})"
    return line


def main(paths):
    print("| input | output faces | alpha mean / min | angle min / max (deg) | away from features: "
          "min angle (< 25 deg) | obtuse | Hausdorff (mean edges) | volume change |")
    print("|---|---|---|---|---|---|---|---|")
    for p in paths:
        print(row(p))


if __name__ == "__main__":
    main(sys.argv[1:])
