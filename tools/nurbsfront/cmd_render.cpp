// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront render MESH OUT.svg: an orthographic picture of a mesh as SVG, triangles
// coloured by quality (alpha or min angle) with a colour bar, Lambert-shaded, drawn back to
// front (painter's algorithm), back faces and fully hidden triangles left out so files stay
// small.
// nurbsfront histogram MESH [MESH2] -o OUT.svg: quality histogram (alpha or min angle) of
// one or two meshes overlaid, as an SVG bar chart.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront::cli {

namespace {

using Eigen::Vector3d;

// ---------------------------------------------------------------- colours

struct Rgb {
  double r, g, b;
};

// Quality colour map, bad (0) to good (1): dark red, red, amber, light green, teal (so the
// right isosceles triangles of marching cubes, alpha 0.87, differ from equilateral ones).
Rgb quality_colour(double t) {
  static constexpr std::array<std::array<double, 4>, 5> stops{{{0.0, 0.50, 0.00, 0.00},
                                                               {0.35, 0.84, 0.19, 0.12},
                                                               {0.65, 0.99, 0.73, 0.28},
                                                               {0.85, 0.75, 0.88, 0.45},
                                                               {1.0, 0.07, 0.52, 0.55}}};
  t = std::clamp(t, 0.0, 1.0);
  for (std::size_t i = 1; i < stops.size(); ++i) {
    if (t <= stops[i][0]) {
      const double s = (t - stops[i - 1][0]) / (stops[i][0] - stops[i - 1][0]);
      return {stops[i - 1][1] + s * (stops[i][1] - stops[i - 1][1]), stops[i - 1][2] + s * (stops[i][2] - stops[i - 1][2]),
              stops[i - 1][3] + s * (stops[i][3] - stops[i - 1][3])};
    }
  }
  return {stops.back()[1], stops.back()[2], stops.back()[3]};
}

// "#rgb" (12 bit: small files, enough for shaded colours).
std::string hex12(const Rgb& c) {
  auto q = [](double x) { return static_cast<int>(std::lround(std::clamp(x, 0.0, 1.0) * 15.0)); };
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "#%x%x%x", q(c.r), q(c.g), q(c.b));
  return buffer;
}

std::string hex24(const Rgb& c) {
  auto q = [](double x) { return static_cast<int>(std::lround(std::clamp(x, 0.0, 1.0) * 255.0)); };
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "#%02x%02x%02x", q(c.r), q(c.g), q(c.b));
  return buffer;
}

std::string num(double x, int digits = 1) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, x);
  std::string s = buffer;
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  return s == "-0" ? "0" : s;
}

Vector3d parse_vector(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) throw InvalidInput(std::string("render: ") + what + " needs three numbers x y z");
  const Vector3d d(v[0], v[1], v[2]);
  if (!d.allFinite() || d.norm() == 0.0) throw InvalidInput(std::string("render: ") + what + " must be a non-zero vector");
  return d.normalized();
}

// Per-face value of the chosen measure; the colour maps [0, range_max] to [0, 1].
struct Measure {
  std::string label;
  double range_max = 1.0;
  std::vector<double> values;
};

Measure face_measure(const TriangleSoup& soup, const std::string& name) {
  if (name == "alpha") return {"alpha", 1.0, face_alpha(soup)};
  if (name == "min-angle") return {"min angle (deg)", 60.0, face_min_angle_deg(soup)};
  if (name == "none") return {"", 1.0, std::vector<double>(soup.triangles.size(), 1.0)};
  throw InvalidInput("render: --color must be alpha, min-angle or none, not '" + name + "'");
}

// ---------------------------------------------------------------- render

struct RenderArgs {
  std::string input;
  std::string output;
  std::string color = "alpha";
  std::vector<double> view{-1.0, -1.0, -1.0};
  std::vector<double> up{0.0, 0.0, 1.0};
  int width = 900;
  std::string title;
  bool both_sides = false;
  bool all_triangles = false;
  bool no_edges = false;
  std::size_t max_triangles = 250000;
};

struct Projected {
  std::array<Eigen::Vector2d, 3> p;
  double depth = 0.0;  // larger = nearer the viewer
  double shade = 1.0;
  double value = 0.0;
  std::size_t face = 0;
};

// Triangles that own at least one sample of a z-buffer (2x the picture's resolution).
std::vector<bool> visible_in_zbuffer(const std::vector<Projected>& tris, int width, int height) {
  const int w = 2 * width, h = 2 * height;
  std::vector<double> depth(std::size_t(w) * std::size_t(h), -std::numeric_limits<double>::infinity());
  std::vector<std::int64_t> owner(depth.size(), -1);
  // Per-triangle plane depth z = a x + b y + c from its three projected corners.
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const auto& q = tris[t];
    const Eigen::Vector2d a = 2.0 * q.p[0], b = 2.0 * q.p[1], c = 2.0 * q.p[2];
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (area == 0.0) continue;
    const int x0 = std::max(0, int(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(w - 1, int(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(h - 1, int(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d s(x + 0.5, y + 0.5);
        const double l0 = ((b - s).x() * (c - s).y() - (b - s).y() * (c - s).x()) / area;
        const double l1 = ((c - s).x() * (a - s).y() - (c - s).y() * (a - s).x()) / area;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < 0.0 || l1 < 0.0 || l2 < 0.0) continue;
        const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
        if (q.depth > depth[i]) {  // triangles come back to front: equal depth keeps the earlier one
          depth[i] = q.depth;
          owner[i] = std::int64_t(t);
        }
      }
    }
  }
  std::vector<bool> visible(tris.size(), false);
  for (const auto o : owner) {
    if (o >= 0) visible[std::size_t(o)] = true;
  }
  return visible;
}

void colour_bar(std::ostringstream& svg, double x, double y, double h, const Measure& m) {
  const int steps = 32;
  svg << "<g>";
  for (int i = 0; i < steps; ++i) {
    const double t0 = double(i) / steps;
    svg << "<rect x=\"" << num(x) << "\" y=\"" << num(y + h * (1.0 - t0 - 1.0 / steps)) << "\" width=\"16\" height=\""
        << num(h / steps + 0.5) << "\" fill=\"" << hex24(quality_colour(t0 + 0.5 / steps)) << "\"/>";
  }
  svg << "<rect x=\"" << num(x) << "\" y=\"" << num(y) << "\" width=\"16\" height=\"" << num(h)
      << "\" fill=\"none\" stroke=\"#000\" stroke-width=\"0.8\"/>";
  for (int i = 0; i <= 4; ++i) {
    const double t = i / 4.0;
    const double ty = y + h * (1.0 - t);
    svg << "<line x1=\"" << num(x + 16) << "\" y1=\"" << num(ty) << "\" x2=\"" << num(x + 20) << "\" y2=\"" << num(ty)
        << "\" stroke=\"#000\"/><text x=\"" << num(x + 23) << "\" y=\"" << num(ty + 4) << "\">"
        << num(t * m.range_max, 2) << "</text>";
  }
  svg << "<text x=\"" << num(x) << "\" y=\"" << num(y - 8) << "\">" << m.label << "</text></g>\n";
}

void run_render(const RenderArgs& a) {
  if (a.width < 100 || a.width > 8000) throw InvalidInput("render: --width must be within 100..8000 pixels");
  const TriangleSoup soup = clean(read_soup(a.input)).soup;
  if (soup.triangles.empty()) throw InvalidInput("render: the mesh has no triangles: " + a.input);
  const Measure measure = face_measure(soup, a.color);
  const Vector3d view = parse_vector(a.view, "--view");
  const Vector3d up_hint = parse_vector(a.up, "--up");
  const Vector3d w = -view;  // towards the viewer
  Vector3d u = up_hint.cross(w);
  if (u.norm() < 1e-9) throw InvalidInput("render: --up must not be parallel to --view");
  u.normalize();
  const Vector3d v = w.cross(u);
  const Vector3d light = (w + 0.5 * v + 0.3 * u).normalized();  // from the viewer, a little above

  // Project, cull back faces, shade.
  std::vector<Projected> tris;
  Eigen::Vector2d lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto& p : soup.points) {
    const Eigen::Vector2d q(p.dot(u), p.dot(v));
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double margin = 20.0, bar = measure.label.empty() ? 0.0 : 90.0, title_h = 40.0;
  const double scale = (a.width - 2 * margin - bar) / std::max(hi.x() - lo.x(), 1e-300);
  const int height = static_cast<int>(std::ceil((hi.y() - lo.y()) * scale + 2 * margin + title_h));
  for (std::size_t f = 0; f < soup.triangles.size(); ++f) {
    const auto& t = soup.triangles[f];
    const Vector3d& a0 = soup.points[t[0]];
    const Vector3d& a1 = soup.points[t[1]];
    const Vector3d& a2 = soup.points[t[2]];
    Vector3d n = (a1 - a0).cross(a2 - a0);
    if (n.norm() == 0.0) continue;
    n.normalize();
    const double facing = n.dot(w);
    if (facing <= 0.0 && !a.both_sides) continue;
    Projected q;
    const std::array<const Vector3d*, 3> corners{&a0, &a1, &a2};
    for (int k = 0; k < 3; ++k) {
      const Vector3d& p = *corners[std::size_t(k)];
      q.p[std::size_t(k)] = {margin + (p.dot(u) - lo.x()) * scale, title_h + margin + (hi.y() - p.dot(v)) * scale};
    }
    q.depth = (a0 + a1 + a2).dot(w) / 3.0;
    q.shade = 0.3 + 0.7 * std::abs(n.dot(light));
    q.value = measure.values[f];
    q.face = f;
    tris.push_back(q);
  }
  std::stable_sort(tris.begin(), tris.end(), [](const Projected& x, const Projected& y) { return x.depth < y.depth; });
  std::vector<bool> keep(tris.size(), true);
  if (!a.all_triangles) keep = visible_in_zbuffer(tris, a.width, height);
  const std::size_t n_drawn = static_cast<std::size_t>(std::count(keep.begin(), keep.end(), true));
  if (n_drawn > a.max_triangles) {
    throw InvalidInput("render: " + std::to_string(n_drawn) + " triangles to draw, more than --max-triangles " +
                       std::to_string(a.max_triangles) + " (the SVG would be too large; coarsen the mesh or raise the limit)");
  }

  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << a.width << "\" height=\"" << height
      << "\" viewBox=\"0 0 " << a.width << ' ' << height << "\" font-family=\"sans-serif\" font-size=\"13\">\n";
  svg << "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n";
  const std::vector<double>& values = measure.values;
  const double mean = std::accumulate(values.begin(), values.end(), 0.0) / double(values.size());
  std::string title = a.title.empty() ? a.input : a.title;
  svg << "<text x=\"" << num(margin) << "\" y=\"22\" font-size=\"15\">" << title << "</text>";
  svg << "<text x=\"" << num(margin) << "\" y=\"38\" fill=\"#444\">" << soup.triangles.size() << " triangles";
  if (!measure.label.empty()) svg << ", mean " << measure.label << " " << num(mean, 3);
  svg << "</text>\n";
  if (a.no_edges) {
    svg << "<g stroke-width=\"0.3\" stroke-linejoin=\"round\">\n";
  } else {
    svg << "<g stroke=\"#000\" stroke-opacity=\"0.35\" stroke-width=\"0.25\" stroke-linejoin=\"round\">\n";
  }
  for (std::size_t i = 0; i < tris.size(); ++i) {
    if (!keep[i]) continue;
    const Projected& q = tris[i];
    const Rgb base = measure.label.empty() ? Rgb{0.8, 0.8, 0.8} : quality_colour(q.value / measure.range_max);
    const std::string fill = hex12({base.r * q.shade, base.g * q.shade, base.b * q.shade});
    svg << "<path d=\"M" << num(q.p[0].x()) << ' ' << num(q.p[0].y()) << 'L' << num(q.p[1].x()) << ' ' << num(q.p[1].y())
        << 'L' << num(q.p[2].x()) << ' ' << num(q.p[2].y()) << "Z\" fill=\"" << fill << '"';
    if (a.no_edges) svg << " stroke=\"" << fill << '"';
    svg << "/>\n";
  }
  svg << "</g>\n";
  if (!measure.label.empty()) colour_bar(svg, a.width - bar + 15.0, title_h + margin + 20.0, std::min(300.0, height - title_h - 2 * margin - 20.0), measure);
  svg << "</svg>\n";
  std::ofstream file(a.output, std::ios::binary);
  file << svg.str();
  if (!file) throw IoError("render: cannot write " + a.output);
  std::cout << "wrote " << a.output << ": " << n_drawn << " of " << soup.triangles.size() << " triangles drawn, "
            << a.width << " x " << height << " px, " << svg.str().size() / 1024 << " KiB\n";
}

// ---------------------------------------------------------------- histogram

struct HistogramArgs {
  std::vector<std::string> inputs;
  std::vector<std::string> labels;
  std::string output;
  std::string measure = "alpha";
  int bins = 40;
  std::string title;
};

void run_histogram(const HistogramArgs& a) {
  if (a.inputs.empty() || a.inputs.size() > 2) throw InvalidInput("histogram: give one or two meshes");
  if (a.bins < 2 || a.bins > 500) throw InvalidInput("histogram: --bins must be within 2..500");
  if (!a.labels.empty() && a.labels.size() != a.inputs.size()) {
    throw InvalidInput("histogram: give one --label per mesh");
  }
  const std::array<Rgb, 2> colours{Rgb{0.84, 0.19, 0.12}, Rgb{0.10, 0.45, 0.70}};
  std::vector<std::vector<double>> shares;
  std::vector<std::string> legends;
  std::string axis;
  double range_max = 1.0;
  for (std::size_t k = 0; k < a.inputs.size(); ++k) {
    const TriangleSoup soup = clean(read_soup(a.inputs[k])).soup;
    if (soup.triangles.empty()) throw InvalidInput("histogram: the mesh has no triangles: " + a.inputs[k]);
    const Measure m = face_measure(soup, a.measure);
    if (m.label.empty()) throw InvalidInput("histogram: --measure must be alpha or min-angle");
    axis = m.label;
    range_max = m.range_max;
    std::vector<double> h(std::size_t(a.bins), 0.0);
    double mean = 0.0;
    for (const double x : m.values) {
      const int b = std::clamp(static_cast<int>(x / range_max * a.bins), 0, a.bins - 1);
      h[std::size_t(b)] += 100.0 / double(m.values.size());
      mean += x / double(m.values.size());
    }
    shares.push_back(h);
    legends.push_back((a.labels.empty() ? a.inputs[k] : a.labels[k]) + " (" + std::to_string(m.values.size()) +
                      " triangles, mean " + num(mean, 3) + ")");
  }
  double top = 0.0;
  for (const auto& h : shares) top = std::max(top, *std::max_element(h.begin(), h.end()));
  double step = 1.0;  // a round tick step giving at most 8 ticks
  for (const double candidate : {1.0, 2.0, 5.0, 10.0, 20.0, 25.0}) {
    step = candidate;
    if (top / candidate <= 8.0) break;
  }
  const int n_ticks = std::max(1, static_cast<int>(std::ceil(top / step)));
  top = n_ticks * step;
  const double W = 720, H = 400, left = 60, right = 20, top_margin = 60, bottom = 50;
  const double pw = W - left - right, ph = H - top_margin - bottom;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H << "\" viewBox=\"0 0 " << W
      << ' ' << H << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n";
  svg << "<text x=\"" << left << "\" y=\"20\" font-size=\"15\">"
      << (a.title.empty() ? "histogram of " + axis : a.title) << "</text>\n";
  for (std::size_t k = 0; k < shares.size(); ++k) {
    const double bw = pw / a.bins;
    svg << "<g fill=\"" << hex24(colours[k]) << "\" fill-opacity=\"0.55\">";
    for (int b = 0; b < a.bins; ++b) {
      const double hgt = shares[k][std::size_t(b)] / top * ph;
      if (hgt <= 0.0) continue;
      svg << "<rect x=\"" << num(left + b * bw, 2) << "\" y=\"" << num(top_margin + ph - hgt, 2) << "\" width=\""
          << num(bw, 2) << "\" height=\"" << num(hgt, 2) << "\"/>";
    }
    svg << "</g>\n<rect x=\"" << left + 10 << "\" y=\"" << 30 + 15 * k << "\" width=\"10\" height=\"10\" fill=\""
        << hex24(colours[k]) << "\" fill-opacity=\"0.55\"/><text x=\"" << left + 25 << "\" y=\"" << 39 + 15 * k << "\">"
        << legends[k] << "</text>\n";
  }
  // Axes, ticks, labels.
  svg << "<g stroke=\"#000\" fill=\"none\"><path d=\"M" << left << ' ' << top_margin << "V" << top_margin + ph << "H"
      << left + pw << "\"/></g>\n";
  for (int i = 0; i <= 5; ++i) {
    const double x = left + pw * i / 5.0;
    svg << "<text x=\"" << num(x) << "\" y=\"" << num(top_margin + ph + 16) << "\" text-anchor=\"middle\">"
        << num(range_max * i / 5.0, 2) << "</text>";
  }
  for (int i = 0; i <= n_ticks; ++i) {
    const double y = top_margin + ph - ph * i / n_ticks;
    svg << "<text x=\"" << num(left - 6) << "\" y=\"" << num(y + 4) << "\" text-anchor=\"end\">" << num(step * i, 1)
        << "</text>";
  }
  svg << "\n<text x=\"" << num(left + pw / 2) << "\" y=\"" << num(H - 12) << "\" text-anchor=\"middle\">" << axis
      << "</text><text x=\"14\" y=\"" << num(top_margin + ph / 2) << "\" transform=\"rotate(-90 14 "
      << num(top_margin + ph / 2) << ")\" text-anchor=\"middle\">% of triangles</text>\n</svg>\n";
  std::ofstream file(a.output, std::ios::binary);
  file << svg.str();
  if (!file) throw IoError("histogram: cannot write " + a.output);
  std::cout << "wrote " << a.output << '\n';
}

}  // namespace

// Registers `render` and `histogram` (the two picture commands).
void add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand("render", "Draw a mesh as SVG: orthographic, shaded, triangles coloured by quality");
  cmd->add_option("mesh", args->input, "Mesh file (.obj .ply .stl .off .vtk)")->required();
  cmd->add_option("output", args->output, "Output .svg")->required();
  cmd->add_option("--color", args->color, "Face colour: alpha, min-angle or none")->capture_default_str();
  cmd->add_option("--view", args->view, "Viewing direction x y z (from the eye into the scene)")->expected(3)->capture_default_str();
  cmd->add_option("--up", args->up, "Up direction x y z")->expected(3)->capture_default_str();
  cmd->add_option("--width", args->width, "Picture width in pixels")->capture_default_str();
  cmd->add_option("--title", args->title, "Title line (default: the file name)");
  cmd->add_flag("--both-sides", args->both_sides, "Draw back faces too (open surfaces)");
  cmd->add_flag("--all-triangles", args->all_triangles, "Keep hidden triangles (no z-buffer visibility filter)");
  cmd->add_flag("--no-edges", args->no_edges, "Do not outline the triangles");
  cmd->add_option("--max-triangles", args->max_triangles, "Refuse to write more triangles than this")->capture_default_str();
  cmd->callback([args] { run_render(*args); });

  auto hist = std::make_shared<HistogramArgs>();
  auto* h = app.add_subcommand("histogram", "SVG histogram of alpha or min angle of one or two meshes, overlaid");
  h->add_option("meshes", hist->inputs, "One or two mesh files")->required()->expected(1, 2);
  h->add_option("-o,--output", hist->output, "Output .svg")->required();
  h->add_option("--measure", hist->measure, "alpha or min-angle")->capture_default_str();
  h->add_option("--bins", hist->bins, "Number of bars")->capture_default_str();
  h->add_option("--label", hist->labels, "Legend label per mesh (repeat)");
  h->add_option("--title", hist->title, "Title line");
  h->callback([hist] { run_histogram(*hist); });
}

}  // namespace nurbsfront::cli
