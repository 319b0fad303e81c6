// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront corpus DIR...: runs the remeshing pipeline on every mesh and volume under the
// given directories, each in a child process (posix_spawn of this executable's hidden
// `corpus-one` command) under a time limit, so a crash or a hang is an outcome, not an
// assumption. One JSON line per input: outcome (ok, invalid_input, patch_failed,
// broken_output, error, timeout, crash) and figures. Surfaces are read as `remesh` reads
// them (prepare_mesh: weld, clean, make manifold, no zero-area triangles; the repairs are
// listed); 2D domains (.poly .node .edg) are meshed by the advancing front as `mesh2d` does.
//
// nurbsfront corpus-one FILE [--volume --iso V | --pslg]: the child side, one input, one
// JSON line on stdout.
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/front2d/front.h"
#include "nurbsfront/front2d/pslg.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/volume_io.h"
#include "nurbsfront/pipeline/remesh.h"
#include "nurbsfront/quality/json.h"
#include "nurbsfront/quality/report.h"

extern char** environ;

namespace nurbsfront::cli {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------- child: one input

struct OneArgs {
  std::string input;
  bool volume = false;
  bool pslg = false;  // a 2D domain for mesh_pslg()
  std::optional<double> iso;
  unsigned threads = 1;
  std::string output;  // optional: write the remeshed mesh
  bool self_test_crash = false;  // abort, to test the parent's crash detection
};

const char* kind_of(bool volume, bool pslg) { return volume ? "volume" : pslg ? "pslg" : "mesh"; }

//! The figures of a 2D run: the planar mesh's report and the front's status.
struct PlanarRun {
  std::size_t n_segments = 0;
  std::size_t n_points = 0;
  bool enclosed_convex_hull = false;
  MeshReport report;
};

std::string outcome_json(const OneArgs& a, const std::string& outcome, const std::string& message, double iso,
                         const TriMesh* input, const std::string& repairs, const RemeshReport* report,
                         const PlanarRun* planar, double seconds) {
  json::Object o;
  o.text("input", a.input).text("kind", kind_of(a.volume, a.pslg));
  o.add("iso", a.volume ? json::number(iso) : "null");
  o.text("outcome", outcome).text("message", message).num("seconds", seconds);
  if (input != nullptr) o.count("input_vertices", input->n_vertices()).count("input_faces", input->n_faces());
  if (!repairs.empty()) o.text("input_repairs", repairs);
  if (planar != nullptr) {
    const MeshReport& out = planar->report;
    o.count("input_points", planar->n_points).count("input_segments", planar->n_segments);
    o.flag("enclosed_convex_hull", planar->enclosed_convex_hull);
    o.count("output_vertices", out.topology.n_vertices).count("output_faces", out.topology.n_faces);
    o.num("alpha_mean", out.quality.alpha_mean).num("alpha_min", out.quality.alpha_min);
    o.num("min_angle_deg", out.quality.min_angle_deg).num("max_angle_deg", out.quality.max_angle_deg);
    o.num("obtuse_fraction", out.quality.obtuse_fraction);
  }
  if (report != nullptr) {
    const MeshReport& out = report->output;
    o.count("output_vertices", out.topology.n_vertices).count("output_faces", out.topology.n_faces);
    o.count("patches", report->n_patches).count("failed_patches", report->n_failed_patches);
    o.num("alpha_mean", out.quality.alpha_mean).num("alpha_min", out.quality.alpha_min);
    o.num("min_angle_deg", out.quality.min_angle_deg).num("max_angle_deg", out.quality.max_angle_deg);
    o.num("obtuse_fraction", out.quality.obtuse_fraction);
    // Issue 5's angle bound applies away from creases and corners (StitchReport).
    o.num("min_angle_away_from_features_deg", report->stitch.min_angle_away_from_features_deg);
    o.count("small_angle_away_from_features", report->stitch.n_small_angle_away_from_features);
    o.count("small_angle_at_fin_rims", report->stitch.n_small_angle_at_fin_rims);
    o.add("self_intersecting_pairs", out.topology.n_self_intersecting_pairs
                                         ? std::to_string(*out.topology.n_self_intersecting_pairs)
                                         : "null");
    o.flag("closed", out.topology.is_closed).flag("manifold", out.topology.is_manifold);
    o.integer("euler_characteristic", out.topology.euler_characteristic);
    if (out.distance) {
      o.num("hausdorff", out.distance->hausdorff).num("mean_distance", out.distance->mean);
      o.num("input_mean_edge", report->input_mean_edge);
      // (V_output - V_input) / V_input; null unless both surfaces are closed.
      const auto& volume = out.distance->relative_volume_change;
      o.add("relative_volume_change", volume ? json::number(*volume) : "null");
    }
    o.count("crossing_repairs", report->n_crossing_repairs);
    std::vector<std::string> errors;
    for (std::size_t i = 0; i < std::min<std::size_t>(report->errors.size(), 5); ++i) {
      errors.push_back(json::string(report->errors[i]));
    }
    o.count("n_errors", report->errors.size()).add("errors", json::array(errors));
  }
  return o.str();
}

std::string fixed(double x, int digits) {
  if (!std::isfinite(x)) return "-";
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, x);
  return buffer;
}

// The figures of the Markdown table row: input faces, output faces, alpha mean, min angle,
// min angle away from features, triangles away from features below 25 deg, obtuse %,
// self-intersecting pairs, crossing repairs, Hausdorff / input mean edge, relative
// volume change % (closed inputs).
std::string markdown_cells(const TriMesh* input, const RemeshReport* report, const PlanarRun* planar) {
  if (planar != nullptr) {
    const MeshReport& out = planar->report;
    return std::to_string(planar->n_segments) + " segments | " + std::to_string(out.topology.n_faces) + " | " +
           fixed(out.quality.alpha_mean, 3) + " | " + fixed(out.quality.min_angle_deg, 1) + " | - | - | " +
           fixed(100.0 * out.quality.obtuse_fraction, 2) + " | " +
           (out.topology.n_self_intersecting_pairs ? std::to_string(*out.topology.n_self_intersecting_pairs) : "-") +
           " | - | - | -";
  }
  std::string row = (input != nullptr ? std::to_string(input->n_faces()) : "-") + " | ";
  if (report == nullptr) return row + "- | - | - | - | - | - | - | - | - | -";
  const MeshReport& out = report->output;
  row += std::to_string(out.topology.n_faces) + " | " + fixed(out.quality.alpha_mean, 3) + " | " +
         fixed(out.quality.min_angle_deg, 1) + " | ";
  const StitchReport& stitch = report->stitch;
  row += stitch.n_away_from_features > 0 ? fixed(stitch.min_angle_away_from_features_deg, 1) + " | " +
                                               std::to_string(stitch.n_small_angle_away_from_features)
                                         : std::string("- | -");
  row += " | " + fixed(100.0 * out.quality.obtuse_fraction, 2) + " | ";
  row += (out.topology.n_self_intersecting_pairs ? std::to_string(*out.topology.n_self_intersecting_pairs) : "-") + " | ";
  row += std::to_string(report->n_crossing_repairs) + " | ";
  row += out.distance && report->input_mean_edge > 0.0 ? fixed(out.distance->hausdorff / report->input_mean_edge, 2) : "-";
  row += " | ";
  row += out.distance && out.distance->relative_volume_change ? fixed(100.0 * *out.distance->relative_volume_change, 2) : "-";
  return row;
}

// A 2D domain as `mesh2d` meshes it (default size: bounding-box diagonal / 40). CGAL's
// .edg files are constraint sets whose domain is the convex hull (as CGAL::Mesh_2 meshes
// them), so their hull is enclosed; .poly and .node follow Triangle's -p.
PlanarRun run_planar(const OneArgs& a, std::string& outcome, std::string& message) {
  PlanarRun run;
  const Pslg pslg = read_pslg(a.input);
  run.n_points = pslg.points.size();
  run.n_segments = pslg.segments.size();
  FrontOptions options;
  options.enclose_convex_hull = run.enclosed_convex_hull = lower_extension(a.input) == ".edg";
  Mesh2d mesh;
  try {
    mesh = mesh_pslg(pslg, options);
  } catch (const InvalidInput& e) {
    std::string what = e.what();
    if (what.find("domain is empty") != std::string::npos) {
      what += "; the segments enclose no region: `nurbsfront mesh2d --convex-hull` meshes the convex hull (Triangle -c)";
    }
    throw InvalidInput(what);
  }
  if (mesh.report.status != FrontStatus::Ok) {
    outcome = "patch_failed";
    message = "mesh2d: " + mesh.report.message;
  }
  TriangleSoup soup;
  for (const auto& p : mesh.points) soup.points.emplace_back(p.x(), p.y(), 0.0);
  for (const auto& t : mesh.triangles) {
    soup.triangles.push_back({static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
  }
  ReportOptions report_options;
  report_options.n_threads = a.threads;
  run.report = mesh_report(soup, report_options);
  const auto& n_self = run.report.topology.n_self_intersecting_pairs;
  // Regions of a domain may touch at a point (non-manifold vertices are legitimate in 2D);
  // edges with more than two triangles or overlapping triangles are not.
  const std::size_t n_bad_edges = run.report.topology.n_nonmanifold_edges;
  if (outcome == "ok" && (n_bad_edges > 0 || (n_self && *n_self > 0))) {
    outcome = "broken_output";
    message = "mesh2d: the planar mesh has " + std::to_string(n_bad_edges) + " edges with more than two triangles and " +
              std::to_string(n_self.value_or(0)) + " overlapping triangle pairs";
  }
  return run;
}

void run_one(const OneArgs& a) {
  if (a.self_test_crash) std::abort();
  Stopwatch watch;
  double iso = 0.0;
  std::optional<TriMesh> input;
  std::string repairs;
  std::optional<RemeshResult> result;
  std::optional<PlanarRun> planar;
  std::string outcome = "ok";
  std::string message;
  try {
    try {
      TriangleSoup soup;
      if (a.volume) {
        const ScalarGrid grid = read_volume(a.input);
        MarchingCubesOptions options;
        options.inside_above = true;
        options.pad = true;
        const auto range = grid.value_range();
        iso = a.iso ? *a.iso : 0.5 * (double(range[0]) + double(range[1]));
        options.iso = iso;
        soup = marching_cubes(grid, options);
      } else if (a.pslg) {
        planar = run_planar(a, outcome, message);
      } else {
        soup = read_soup(a.input);
      }
      if (!a.pslg) {
        CleanOptions clean;  // the input's mesh built with the run's threads, as remesh does
        clean.threads = static_cast<int>(a.threads);
        PreparedMesh prepared = prepare_mesh(soup, clean);
        repairs = prepared.report.summary();
        input = std::move(prepared.mesh);
      }
    } catch (const IoError& e) {
      throw InvalidInput(std::string("cannot read the input: ") + e.what());
    } catch (const TopologyError& e) {
      throw InvalidInput(std::string("the input is not an oriented 2-manifold: ") + e.what());
    }
    if (!a.pslg) {
      RemeshOptions options;
      options.set_threads(a.threads);
      result = remesh(*input, options);
      const RemeshReport& r = result->report;
      if (r.n_failed_patches > 0) {
        outcome = "patch_failed";
      } else if (!r.ok()) {
        outcome = "broken_output";
      }
      if (!r.ok()) message = r.errors.front();
      // Self-intersections the input already has are the input's: a named invalid input.
      const auto& n_self = r.output.topology.n_self_intersecting_pairs;
      if (n_self && *n_self > 0) {
        const std::string note = input_self_intersections(*input, a.threads);
        if (!note.empty()) {
          outcome = "invalid_input";
          message = note + " (remeshed anyway: " + (r.errors.empty() ? "" : r.errors.front()) + ")";
        }
      }
      if (!a.output.empty()) write_mesh(result->mesh, a.output);
    }
  } catch (const InvalidInput& e) {
    outcome = "invalid_input";
    message = e.what();
  } catch (const std::exception& e) {
    outcome = "error";
    message = e.what();
  }
  const PlanarRun* planar_run = planar ? &*planar : nullptr;
  std::cout << outcome_json(a, outcome, message, iso, input ? &*input : nullptr, repairs,
                            result ? &result->report : nullptr, planar_run, watch.seconds())
            << '\n'
            << "MD\t" << markdown_cells(input ? &*input : nullptr, result ? &result->report : nullptr, planar_run)
            << std::endl;
}

// ---------------------------------------------------------------- parent: the corpus

struct CorpusArgs {
  std::vector<std::string> directories;
  double timeout = 300.0;
  unsigned threads = 1;
  std::string output;
  std::string markdown;
  std::string out_dir;
  bool quiet = false;
  bool self_test_crash = false;
};

struct CorpusItem {
  fs::path path;
  bool volume = false;
  bool pslg = false;
  std::optional<double> iso;
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A legacy VTK file holds a volume when its DATASET is STRUCTURED_POINTS.
bool is_vtk_volume(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::string line;
  for (int i = 0; i < 6 && std::getline(f, line); ++i) {
    if (line.find("STRUCTURED_POINTS") != std::string::npos) return true;
  }
  return false;
}

// The usual iso-values of the volumes in ../shared/data (SOURCES.md); other volumes get the
// middle of their value range.
std::vector<std::optional<double>> iso_values(const fs::path& path) {
  const std::string name = path.filename().string();
  if (name.rfind("headsq", 0) == 0) return {500.0, 1150.0};  // skin, bone
  if (name.rfind("ironProt", 0) == 0) return {128.0};
  if (name.rfind("liver", 0) == 0) return {127.5};           // the 255 label
  return {std::nullopt};
}

std::vector<CorpusItem> collect(const std::vector<std::string>& directories) {
  std::vector<CorpusItem> items;
  for (const auto& dir : directories) {
    if (!fs::is_directory(dir)) throw InvalidInput("corpus: not a directory: " + dir);
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& p : files) {
      const std::string s = p.string();
      const bool volume_ext = ends_with(s, ".mha") || ends_with(s, ".mhd") || ends_with(s, ".inr") || ends_with(s, ".inr.gz");
      const bool vtk = ends_with(s, ".vtk");
      const bool mesh_ext = ends_with(s, ".off") || ends_with(s, ".obj") || ends_with(s, ".ply") || ends_with(s, ".stl");
      const bool pslg_ext = ends_with(s, ".poly") || ends_with(s, ".node") || ends_with(s, ".edg");
      if (volume_ext || (vtk && is_vtk_volume(p))) {
        for (const auto& iso : iso_values(p)) items.push_back({p, true, false, iso});
      } else if (mesh_ext || vtk) {
        items.push_back({p, false, false, std::nullopt});
      } else if (pslg_ext) {
        items.push_back({p, false, true, std::nullopt});
      }
    }
  }
  return items;
}

// The value of a text field of a JSON line written by json::Object, unescaped enough for
// a table cell ('|' and newlines replaced), cut to `max_size` characters; "" when absent.
std::string table_text(const std::string& line, const std::string& key, std::size_t max_size) {
  std::string text;
  const std::string pattern = "\"" + key + "\": \"";
  const auto at = line.find(pattern);
  if (at == std::string::npos) return text;
  for (std::size_t k = at + pattern.size(); k < line.size() && line[k] != '"'; ++k) {
    if (line[k] == '\\' && k + 1 < line.size()) ++k;
    text += line[k];
  }
  std::replace(text.begin(), text.end(), '|', '/');
  std::replace(text.begin(), text.end(), '\n', ' ');
  if (text.size() > max_size) text = text.substr(0, max_size - 3) + "...";
  return text;
}

std::string read_text(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string tail(const std::string& text, std::size_t n) {
  return text.size() <= n ? text : "..." + text.substr(text.size() - n);
}

struct ChildResult {
  std::string line;  // the child's JSON (empty when none)
  std::string cells;  // the child's Markdown cells (empty when none)
  std::string outcome_override;  // timeout / crash
  std::string message;
  double wall_seconds = 0.0;
  long max_rss_kb = 0;
};

ChildResult run_child(const std::vector<std::string>& argv_strings, const fs::path& out_file, const fs::path& err_file,
                      double timeout) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv;
  for (const auto& s : argv_strings) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const auto start = std::chrono::steady_clock::now();
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw IoError(std::string("corpus: cannot start ") + argv[0] + ": " + std::strerror(rc));
  ChildResult result;
  int status = 0;
  rusage usage{};
  bool timed_out = false;
  for (;;) {
    const pid_t done = wait4(pid, &status, WNOHANG, &usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) throw IoError(std::string("corpus: wait failed: ") + std::strerror(errno));
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!timed_out && elapsed > timeout) {
      kill(pid, SIGKILL);
      timed_out = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.max_rss_kb = usage.ru_maxrss;
  const std::string out = read_text(out_file);
  const std::string err = read_text(err_file);
  if (timed_out) {
    result.outcome_override = "timeout";
    result.message = "killed after " + std::to_string(timeout) + " s";
  } else if (WIFSIGNALED(status)) {
    result.outcome_override = "crash";
    result.message = std::string("signal ") + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) +
                     "): " + tail(err, 300);
  } else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || out.find('{') == std::string::npos) {
    result.outcome_override = "crash";
    result.message = "exit status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                     " without a result: " + tail(err, 300);
  } else {
    std::istringstream lines(out);
    std::string l;
    while (std::getline(lines, l)) {
      if (l.rfind("{", 0) == 0) result.line = l;
      if (l.rfind("MD\t", 0) == 0) result.cells = l.substr(3);
    }
    while (!result.line.empty() && result.line.back() != '}') result.line.pop_back();
    if (result.line.empty()) {
      result.outcome_override = "crash";
      result.message = "no JSON result line: " + tail(out + err, 300);
    }
  }
  return result;
}

std::string self_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw IoError("corpus: cannot find this executable (/proc/self/exe): " + ec.message());
  return p.string();
}

void run_corpus(const CorpusArgs& a) {
  if (a.timeout <= 0.0) throw InvalidInput("corpus: --timeout must be positive");
  if (a.threads == 0) throw InvalidInput("corpus: --threads must be at least 1");
  const std::vector<CorpusItem> items = collect(a.directories);
  if (items.empty()) throw InvalidInput("corpus: no mesh, volume or 2D domain files under the given directories");
  const std::string exe = self_executable();
  const fs::path scratch = fs::temp_directory_path() / ("nurbsfront-corpus-" + std::to_string(getpid()));
  fs::create_directories(scratch);
  if (!a.out_dir.empty()) fs::create_directories(a.out_dir);
  std::ofstream output;
  if (!a.output.empty()) {
    output.open(a.output);
    if (!output) throw IoError("corpus: cannot write " + a.output);
  }
  std::map<std::string, int> counts;
  std::ostringstream md;
  md << "| input | outcome | input faces | output faces | alpha mean | min angle | min angle away from features | "
        "away below 25 deg | obtuse % | self-int. | crossing repairs | Hausdorff / input mean edge | volume change % | "
        "wall s | peak RSS MB | input repairs | first error |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < items.size(); ++i) {
    const CorpusItem& item = items[i];
    std::vector<std::string> argv{exe, "corpus-one", item.path.string(), "--threads", std::to_string(a.threads)};
    std::string label = item.path.filename().string();
    if (item.pslg) argv.push_back("--pslg");
    if (item.volume) {
      argv.push_back("--volume");
      if (item.iso) {
        argv.push_back("--iso");
        argv.push_back(json::number(*item.iso));
        label += "@" + json::number(*item.iso);
      }
    }
    if (a.self_test_crash) argv.push_back("--self-test-crash");
    if (!a.out_dir.empty() && !item.pslg) {
      argv.push_back("-o");
      argv.push_back((fs::path(a.out_dir) / (label + ".ply")).string());
    }
    if (!a.quiet) std::cerr << "[" << (i + 1) << "/" << items.size() << "] " << label << " ..." << std::flush;
    const ChildResult child = run_child(argv, scratch / "out.txt", scratch / "err.txt", a.timeout);
    std::string line;
    std::string outcome;
    if (!child.outcome_override.empty()) {
      outcome = child.outcome_override;
      json::Object o;
      o.text("input", item.path.string()).text("kind", kind_of(item.volume, item.pslg));
      o.add("iso", item.iso ? json::number(*item.iso) : "null");
      o.text("outcome", outcome).text("message", child.message);
      line = o.str();
    } else {
      line = child.line;
      const auto key = line.find("\"outcome\":");
      const auto q1 = line.find('"', key + 10);
      const auto q2 = line.find('"', q1 + 1);
      outcome = line.substr(q1 + 1, q2 - q1 - 1);
    }
    // Append the parent's measurements to the object.
    line.pop_back();
    line += ", \"wall_seconds\": " + json::number(child.wall_seconds) + ", \"max_rss_mb\": " +
            json::number(double(child.max_rss_kb) / 1024.0) + "}";
    ++counts[outcome];
    {
      const std::string first_error = table_text(line, "message", 120);
      const std::string repairs = table_text(line, "input_repairs", 80);
      md << "| " << label << " | " << outcome << " | " << (child.cells.empty() ? "- | - | - | - | - | - | - | - | - | - | -" : child.cells)
         << " | " << fixed(child.wall_seconds, 1) << " | " << fixed(double(child.max_rss_kb) / 1024.0, 0) << " | "
         << (repairs == "nothing to repair" ? "" : repairs) << " | " << first_error << " |\n";
    }
    std::cout << line << std::endl;
    if (output.is_open()) output << line << '\n' << std::flush;
    if (!a.quiet) std::cerr << " " << outcome << " (" << json::number(child.wall_seconds) << " s)\n";
  }
  fs::remove_all(scratch);
  if (!a.markdown.empty()) {
    std::ofstream file(a.markdown);
    file << md.str();
    if (!file) throw IoError("corpus: cannot write " + a.markdown);
  }
  std::string summary = "corpus: " + std::to_string(items.size()) + " inputs:";
  for (const auto& [k, n] : counts) summary += " " + k + " " + std::to_string(n) + ",";
  summary.pop_back();
  std::cerr << summary << '\n';
  const int bad = static_cast<int>(items.size()) - counts["ok"] - counts["invalid_input"];
  if (bad > 0) throw std::runtime_error("corpus: " + std::to_string(bad) + " inputs neither ok nor a named invalid input");
}

}  // namespace

void add_corpus_command(CLI::App& app) {
  auto args = std::make_shared<CorpusArgs>();
  auto* cmd = app.add_subcommand(
      "corpus",
      "Remesh every mesh and volume (and mesh every 2D domain) under DIR... in child processes under a time limit; "
      "one JSON line each");
  cmd->add_option("directories", args->directories,
                  "Directories searched recursively: meshes (.off .obj .ply .stl .vtk POLYDATA) and volumes "
                  "(.mha .mhd .inr .inr.gz .vtk STRUCTURED_POINTS), 2D domains (.poly .node .edg)")
      ->required();
  cmd->add_option("--timeout", args->timeout, "Seconds per input before the child is killed")->capture_default_str();
  cmd->add_option("--threads", args->threads, "Threads of each run")->capture_default_str();
  cmd->add_option("-o,--output", args->output, "Also write the JSON lines to this file");
  cmd->add_option("--md", args->markdown, "Also write a Markdown table, one row per input");
  cmd->add_option("--out-dir", args->out_dir, "Write each remeshed surface there (<name>.ply)");
  cmd->add_flag("-q,--quiet", args->quiet, "No per-input progress on stderr");
  cmd->add_flag("--self-test-crash", args->self_test_crash, "Make every child abort (tests the crash detection)")
      ->group("");
  cmd->callback([args] { run_corpus(*args); });

  auto one = std::make_shared<OneArgs>();
  auto* child = app.add_subcommand("corpus-one", "One input of `corpus` (run in a child process): one JSON line");
  child->group("");  // hidden from --help: an implementation detail of `corpus`
  child->add_option("input", one->input, "Mesh or volume file")->required();
  child->add_flag("--volume", one->volume, "The input is a volume: marching cubes first (inside above iso, padded)");
  child->add_flag("--pslg", one->pslg, "The input is a 2D domain: advancing front in the plane");
  child->add_option("--iso", one->iso, "Iso-value of the volume (default: middle of the value range)");
  child->add_option("--threads", one->threads, "Threads")->capture_default_str();
  child->add_option("-o,--output", one->output, "Write the remeshed surface");
  child->add_flag("--self-test-crash", one->self_test_crash, "Abort at once")->group("");
  child->callback([one] { run_one(*one); });
}

}  // namespace nurbsfront::cli
