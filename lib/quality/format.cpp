// SPDX-License-Identifier: BSD-3-Clause
// JSON and text renderings of the reports (strings only: the library never prints).
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "nurbsfront/quality/json.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront {
namespace {

using json::number;
using JsonObject = json::Object;

std::string components_json(const TopologyReport& t) {
  std::string s = "[";
  for (std::size_t i = 0; i < t.components.size(); ++i) {
    const auto& c = t.components[i];
    JsonObject o;
    o.count("vertices", c.n_vertices).count("edges", c.n_edges).count("faces", c.n_faces);
    o.add("euler_characteristic", std::to_string(c.euler_characteristic));
    o.add("genus", c.genus ? std::to_string(*c.genus) : "null");
    o.flag("closed", c.is_closed).flag("manifold", c.is_manifold).flag("oriented", c.is_oriented);
    s += (i ? ", " : "") + o.str();
  }
  return s + "]";
}

std::string optional_count(const std::optional<std::size_t>& n) { return n ? std::to_string(*n) : "null"; }

}  // namespace

std::string to_json(const DistanceReport& d) {
  JsonObject o;
  o.num("hausdorff", d.hausdorff).num("mean", d.mean);
  o.num("hausdorff_relative", d.hausdorff_relative).num("mean_relative", d.mean_relative);
  o.num("mesh_to_reference_max", d.mesh_to_reference_max).num("mesh_to_reference_mean", d.mesh_to_reference_mean);
  o.num("reference_to_mesh_max", d.reference_to_mesh_max).num("reference_to_mesh_mean", d.reference_to_mesh_mean);
  o.num("reference_diagonal", d.reference_diagonal);
  o.count("mesh_samples", d.n_mesh_samples).count("reference_samples", d.n_reference_samples);
  o.add("relative_volume_change", d.relative_volume_change ? number(*d.relative_volume_change) : "null");
  return o.str();
}

std::string to_json(const MeshReport& report) {
  const TopologyReport& t = report.topology;
  const QualityReport& q = report.quality;
  JsonObject topo;
  topo.count("vertices", t.n_vertices).count("unreferenced_points", t.n_unreferenced_points);
  topo.count("faces", t.n_faces).count("edges", t.n_edges).count("components", t.n_components);
  topo.count("boundary_edges", t.n_boundary_edges).count("boundary_loops", t.n_boundary_loops);
  topo.count("nonmanifold_edges", t.n_nonmanifold_edges).count("nonmanifold_vertices", t.n_nonmanifold_vertices);
  topo.count("misoriented_edges", t.n_misoriented_edges).count("degenerate_faces", t.n_degenerate_faces);
  topo.count("duplicate_faces", t.n_duplicate_faces);
  topo.add("self_intersecting_pairs", optional_count(t.n_self_intersecting_pairs));
  topo.flag("closed", t.is_closed).flag("manifold", t.is_manifold);
  topo.flag("consistently_oriented", t.is_consistently_oriented);
  topo.add("euler_characteristic", std::to_string(t.euler_characteristic));
  topo.add("volume", t.volume ? number(*t.volume) : "null");
  topo.add("per_component", components_json(t));
  JsonObject alpha;
  alpha.num("mean", q.alpha_mean).num("min", q.alpha_min).num("p1", q.alpha_p1);
  JsonObject angles;
  angles.num("min", q.min_angle_deg).num("max", q.max_angle_deg);
  angles.num("obtuse_fraction", q.obtuse_fraction).num("small_angle_fraction", q.small_angle_fraction);
  JsonObject edges;
  edges.num("mean", q.edge_length_mean).num("min", q.edge_length_min).num("max", q.edge_length_max);
  edges.num("stddev", q.edge_length_stddev);
  JsonObject all;
  all.add("topology", topo.str()).add("alpha", alpha.str()).add("angles", angles.str());
  all.add("edge_length", edges.str());
  all.add("distance", report.distance ? to_json(*report.distance) : "null");
  return all.str();
}

std::string to_text(const MeshReport& report) {
  const TopologyReport& t = report.topology;
  const QualityReport& q = report.quality;
  std::ostringstream out;
  auto row = [&](const char* name, const std::string& value) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "  %-28s ", name);
    out << buffer << value << '\n';
  };
  auto yes_no = [](bool b) { return std::string(b ? "yes" : "no"); };
  out << "topology\n";
  row("vertices", std::to_string(t.n_vertices));
  if (t.n_unreferenced_points) row("unreferenced points", std::to_string(t.n_unreferenced_points));
  row("faces", std::to_string(t.n_faces));
  row("edges", std::to_string(t.n_edges));
  row("components", std::to_string(t.n_components));
  row("closed", yes_no(t.is_closed));
  row("manifold", yes_no(t.is_manifold));
  row("consistently oriented", yes_no(t.is_consistently_oriented));
  row("euler characteristic", std::to_string(t.euler_characteristic));
  for (std::size_t i = 0; i < t.components.size() && i < 10; ++i) {
    const auto& c = t.components[i];
    const std::string name = "  component " + std::to_string(i);
    row(name.c_str(), std::to_string(c.n_faces) + " faces, chi " + std::to_string(c.euler_characteristic) +
                          ", genus " + (c.genus ? std::to_string(*c.genus) : std::string("unknown")));
  }
  if (t.components.size() > 10) row("  ...", std::to_string(t.components.size() - 10) + " more components");
  row("boundary edges", std::to_string(t.n_boundary_edges));
  row("boundary loops", std::to_string(t.n_boundary_loops));
  row("non-manifold edges", std::to_string(t.n_nonmanifold_edges));
  row("non-manifold vertices", std::to_string(t.n_nonmanifold_vertices));
  row("misoriented edges", std::to_string(t.n_misoriented_edges));
  row("degenerate faces", std::to_string(t.n_degenerate_faces));
  row("duplicate faces", std::to_string(t.n_duplicate_faces));
  row("self-intersecting pairs",
      t.n_self_intersecting_pairs ? std::to_string(*t.n_self_intersecting_pairs) : std::string("not checked"));
  if (t.volume) row("volume", number(*t.volume));
  out << "quality\n";
  row("alpha mean / min / p1", number(q.alpha_mean) + " / " + number(q.alpha_min) + " / " + number(q.alpha_p1));
  row("angle min / max (deg)", number(q.min_angle_deg) + " / " + number(q.max_angle_deg));
  row("obtuse fraction", number(q.obtuse_fraction));
  row("min angle < 30 deg fraction", number(q.small_angle_fraction));
  row("edge length mean / stddev", number(q.edge_length_mean) + " / " + number(q.edge_length_stddev));
  row("edge length min / max", number(q.edge_length_min) + " / " + number(q.edge_length_max));
  if (report.distance) {
    const auto& d = *report.distance;
    out << "distance to reference\n";
    row("hausdorff (relative)", number(d.hausdorff) + " (" + number(d.hausdorff_relative) + ")");
    row("mean (relative)", number(d.mean) + " (" + number(d.mean_relative) + ")");
    row("mesh -> reference max / mean", number(d.mesh_to_reference_max) + " / " + number(d.mesh_to_reference_mean));
    row("reference -> mesh max / mean", number(d.reference_to_mesh_max) + " / " + number(d.reference_to_mesh_mean));
    row("samples mesh / reference", std::to_string(d.n_mesh_samples) + " / " + std::to_string(d.n_reference_samples));
    if (d.relative_volume_change) row("relative volume change", number(*d.relative_volume_change));
  }
  return out.str();
}

}  // namespace nurbsfront
