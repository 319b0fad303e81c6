// SPDX-License-Identifier: BSD-3-Clause
// JSON and text renderings of the remesh report (strings only: the library never prints).
#include <algorithm>
#include <cstdio>
#include <string>

#include "nurbsfront/pipeline/remesh.h"
#include "nurbsfront/quality/json.h"

namespace nurbsfront {

namespace {

std::string patch_json(std::size_t index, const PatchMeshReport& p) {
  json::Object o;
  o.count("patch", index).text("status", to_string(p.status)).text("message", p.message);
  o.count("input_faces", p.n_input_faces).count("border_nodes", p.n_border_nodes);
  o.count("inner_nodes", p.n_inner_nodes).count("triangles", p.n_triangles).count("clamped_nodes", p.n_clamped_nodes);
  o.num("fit_max_residual", p.fit_max_residual).integer("fit_levels", p.fit_levels).flag("detail_fit", p.detail_fit).num("seconds", p.seconds);
  return o.str();
}

std::string components_json(const std::vector<ComponentSignature>& components) {
  std::vector<std::string> items;
  for (const auto& c : components) {
    json::Object o;
    o.count("vertices", c.n_vertices).count("edges", c.n_edges).count("faces", c.n_faces);
    o.integer("euler_characteristic", c.euler_characteristic).flag("closed", c.is_closed);
    items.push_back(o.str());
  }
  return json::array(items);
}

std::string fixed(double x, int digits) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, x);
  return buffer;
}

}  // namespace

std::string to_json(const RemeshReport& r) {
  json::Object counts;
  counts.count("input_vertices", r.n_input_vertices).count("input_faces", r.n_input_faces);
  counts.count("patches", r.n_patches).count("patches_split", r.n_patches_split);
  counts.count("curves", r.n_curves).count("corners", r.n_corners).count("crease_edges", r.n_crease_edges);
  counts.count("nodes", r.n_nodes).count("triangles", r.n_triangles).count("failed_patches", r.n_failed_patches);
  counts.count("crossing_repairs", r.n_crossing_repairs);
  counts.count("narrow_patches_merged", r.n_narrow_merged);
  counts.count("tiny_patches_merged", r.n_tiny_merged);
  counts.count("hairline_patches_merged", r.n_hairline_merged);
  counts.count("narrow_patches_widened", r.n_narrow_widened);
  counts.count("fin_rim_curves", r.n_fin_rim_curves);
  counts.num("crease_angle_deg", r.crease_angle_deg);
  json::Object seconds;
  seconds.num("segment", r.seconds_segment).num("surfmesh", r.seconds_surfmesh).num("stitch", r.seconds_stitch);
  seconds.num("distance", r.seconds_distance).num("total", r.seconds_total);
  std::vector<std::string> failed;
  double fit_residual_max = 0.0;
  std::size_t n_detail_fit = 0;
  for (std::size_t p = 0; p < r.patches.size(); ++p) {
    fit_residual_max = std::max(fit_residual_max, r.patches[p].fit_max_residual);
    n_detail_fit += r.patches[p].detail_fit ? 1 : 0;
    if (r.patches[p].status != PatchStatus::Ok) failed.push_back(patch_json(p, r.patches[p]));
  }
  json::Object patches;
  patches.count("count", r.patches.size()).count("ok", r.patches.size() - r.n_failed_patches);
  patches.num("fit_max_residual", fit_residual_max).count("detail_fit", n_detail_fit).add("failed", json::array(failed));
  const StitchReport& s = r.stitch;
  json::Object stitch;
  stitch.count("input_nodes", s.n_input_nodes).count("unused_nodes", s.n_unused_nodes);
  stitch.count("input_triangles", s.n_input_triangles).count("rejected_triangles", s.n_rejected_triangles);
  stitch.count("collapses", s.n_collapses).count("collapses_undone", s.n_collapses_undone);
  stitch.count("flips", s.n_flips).count("smoothing_moves", s.n_smoothing_moves);
  stitch.count("smoothing_rejected", s.n_smoothing_rejected).count("feature_slides", s.n_feature_slides).count("chord_compensation_moves", s.n_chord_compensation_moves).count("volume_compensation_moves", s.n_volume_compensation_moves).count("obtuse_splits", s.n_obtuse_splits).count("obtuse_splits_undone", s.n_obtuse_splits_undone).count("reverted_moves", s.n_reverted_moves);
  stitch.flag("volume_compensation_skipped", s.volume_compensation_skipped);
  stitch.count("reverted_flips", s.n_reverted_flips);
  stitch.flag("optimisation_undone", s.optimisation_undone);
  stitch.count("settled_nodes", s.n_settled_nodes).count("settled_flips", s.n_settled_flips);
  stitch.count("settled_collapses", s.n_settled_collapses);
  stitch.count("angle_flips", s.n_angle_flips).count("angle_collapses", s.n_angle_collapses).count("angle_moves", s.n_angle_moves);
  stitch.count("angle_two_steps", s.n_angle_two_steps).count("angle_searches", s.n_angle_searches);
  stitch.count("angle_repairs_undone", s.n_angle_repairs_undone).count("obtuse_collapses", s.n_obtuse_collapses);
  stitch.count("fidelity_moves", s.n_fidelity_moves).count("fidelity_moves_undone", s.n_fidelity_moves_undone).count("fidelity_splits", s.n_fidelity_splits);
  stitch.count("triangles_away_from_features", s.n_away_from_features);
  stitch.num("min_angle_away_from_features_deg", s.min_angle_away_from_features_deg);
  stitch.count("small_angle_away_from_features", s.n_small_angle_away_from_features);
  stitch.count("triangles_at_fin_rims", s.n_at_fin_rims);
  stitch.num("min_angle_at_fin_rims_deg", s.min_angle_at_fin_rims_deg);
  stitch.count("small_angle_at_fin_rims", s.n_small_angle_at_fin_rims);
  stitch.num("alpha_mean_before", s.alpha_mean_before).num("alpha_min_before", s.alpha_min_before);
  stitch.add("input_components", components_json(s.input_components));
  stitch.add("output_components", components_json(s.output_components));
  std::vector<std::string> errors;
  for (const auto& e : r.errors) errors.push_back(json::string(e));
  json::Object all;
  all.flag("ok", r.ok()).num("target_size", r.target_size).num("input_mean_edge", r.input_mean_edge);
  all.flag("feature_sizing_applied", r.feature_sizing_applied).flag("detail_fit_skipped", r.detail_fit_skipped);
  all.add("counts", counts.str()).add("seconds", seconds.str()).add("patches", patches.str());
  all.add("stitch", stitch.str()).add("output", to_json(r.output)).add("errors", json::array(errors));
  return all.str();
}

std::string to_summary(const RemeshReport& r) {
  const QualityReport& q = r.output.quality;
  const TopologyReport& t = r.output.topology;
  std::string s;
  s += "patches " + std::to_string(r.n_patches) + " (" + std::to_string(r.n_failed_patches) + " failed), curves " +
       std::to_string(r.n_curves) + ", corners " + std::to_string(r.n_corners);
  if (r.n_crossing_repairs > 0) s += ", crossings re-segmented " + std::to_string(r.n_crossing_repairs) + "x";
  s += "\n";
  s += "faces " + std::to_string(r.n_input_faces) + " -> " + std::to_string(r.n_triangles) + ", target edge " +
       json::number(r.target_size) + " (input mean edge " + json::number(r.input_mean_edge) + ")\n";
  s += "topology: " + std::string(t.is_closed ? "closed" : "open") + ", " + (t.is_manifold ? "manifold" : "NOT manifold") +
       ", " + (t.is_consistently_oriented ? "oriented" : "NOT oriented") + ", components " +
       std::to_string(t.n_components) + ", euler " + std::to_string(t.euler_characteristic) + "\n";
  s += "alpha mean " + fixed(q.alpha_mean, 4) + ", min " + fixed(q.alpha_min, 4) + "; angles min " +
       fixed(q.min_angle_deg, 2) + " max " + fixed(q.max_angle_deg, 2) + " deg; obtuse " +
       fixed(100.0 * q.obtuse_fraction, 3) + "%\n";
  if (r.stitch.n_away_from_features == 0) {
    s += "away from features: no triangle (every triangle touches a crease, boundary or corner node)\n";
  } else {
    s += "away from features (" + std::to_string(r.stitch.n_away_from_features) + " triangles): angle min " +
         fixed(r.stitch.min_angle_away_from_features_deg, 2) + " deg, " +
         std::to_string(r.stitch.n_small_angle_away_from_features) + " below " +
         fixed(kAwayFromFeaturesAngleBoundDeg, 0) + " deg\n";
  }
  if (r.stitch.n_at_fin_rims > 0) {
    s += "at fin rims only (" + std::to_string(r.stitch.n_at_fin_rims) + " triangles): angle min " +
         fixed(r.stitch.min_angle_at_fin_rims_deg, 2) + " deg, " + std::to_string(r.stitch.n_small_angle_at_fin_rims) +
         " below " + fixed(kAwayFromFeaturesAngleBoundDeg, 0) + " deg\n";
  }
  if (r.output.distance) {
    const DistanceReport& d = *r.output.distance;
    s += "distance to input: hausdorff " + json::number(d.hausdorff) + " (" + json::number(d.hausdorff_relative) +
         " of the diagonal), mean " + json::number(d.mean);
    if (d.relative_volume_change) s += ", volume change " + fixed(100.0 * *d.relative_volume_change, 4) + "%";
    s += "\n";
  }
  s += "seconds: segment " + fixed(r.seconds_segment, 3) + ", surfmesh " + fixed(r.seconds_surfmesh, 3) + ", stitch " +
       fixed(r.seconds_stitch, 3) + ", distance " + fixed(r.seconds_distance, 3) + ", total " +
       fixed(r.seconds_total, 3) + "\n";
  s += "errors: " + std::to_string(r.errors.size()) + "\n";
  for (const auto& e : r.errors) s += "  " + e + "\n";
  return s;
}

}  // namespace nurbsfront
