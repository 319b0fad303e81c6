// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/nurbs/surface_io.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>

#include "nurbsfront/core/error.h"

namespace nurbsfront {
namespace {

std::string shortest(double x) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), x);
  return std::string(buf, res.ptr);
}

// IGES real: shortest round-trip mantissa, always with a decimal point, E exponent.
std::string iges_real(double x) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), x, std::chars_format::scientific);
  std::string s(buf, res.ptr);
  const std::size_t e = s.find('e');
  std::string mantissa = s.substr(0, e);
  if (mantissa.find('.') == std::string::npos) mantissa += ".0";
  return mantissa + "E" + s.substr(e + 1);
}

std::string hollerith(const std::string& s) { return std::to_string(s.size()) + "H" + s; }

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open '" + path.string() + "' for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError("error reading '" + path.string() + "'");
  return ss.str();
}

void write_file(const std::filesystem::path& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw IoError("cannot open '" + path.string() + "' for writing");
  out << content;
  out.flush();
  if (!out) throw IoError("error writing '" + path.string() + "'");
}

// Whitespace tokenizer that skips '#' comment lines and remembers line numbers.
class Tokens {
 public:
  explicit Tokens(std::string_view text) : text_(text) {}
  std::string_view next(const char* expected) {
    for (;;) {
      while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\r' || text_[pos_] == '\n')) {
        if (text_[pos_] == '\n') ++line_;
        ++pos_;
      }
      if (pos_ < text_.size() && text_[pos_] == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
        continue;
      }
      break;
    }
    if (pos_ >= text_.size()) fail(std::string("unexpected end of text, expected ") + expected);
    const std::size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != ' ' && text_[pos_] != '\t' && text_[pos_] != '\r' && text_[pos_] != '\n') ++pos_;
    return text_.substr(start, pos_ - start);
  }
  void keyword(std::string_view word) {
    const std::string_view t = next(std::string(word).c_str());
    if (t != word) fail("expected '" + std::string(word) + "', found '" + std::string(t) + "'");
  }
  double number(const char* what) {
    const std::string_view t = next(what);
    double x = 0.0;
    const auto res = std::from_chars(t.data(), t.data() + t.size(), x);
    if (res.ec != std::errc() || res.ptr != t.data() + t.size()) fail(std::string("bad number '") + std::string(t) + "' for " + what);
    return x;
  }
  std::size_t count(const char* what) {
    const std::string_view t = next(what);
    std::size_t x = 0;
    const auto res = std::from_chars(t.data(), t.data() + t.size(), x);
    if (res.ec != std::errc() || res.ptr != t.data() + t.size()) fail(std::string("bad count '") + std::string(t) + "' for " + what);
    return x;
  }
  [[noreturn]] void fail(const std::string& message) const {
    throw IoError("NURBS surface text, line " + std::to_string(line_) + ": " + message);
  }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

// Limit on declared sizes so a corrupt count cannot allocate gigabytes.
constexpr std::size_t kMaxTextCount = std::size_t{1} << 28;

}  // namespace

std::string surface_to_text(const NurbsSurface& surface) {
  surface.validate();
  std::string s = "# nurbsfront NURBS surface (docs/nurbs.md): u index fastest, x y z w per point\n";
  s += "nurbsfront_surface 1\n";
  s += "degrees " + std::to_string(surface.u.degree) + " " + std::to_string(surface.v.degree) + "\n";
  s += "counts " + std::to_string(surface.n_u) + " " + std::to_string(surface.n_v) + "\n";
  s += "knots_u";
  for (double k : surface.u.knots) {
    s += ' ';
    s += shortest(k);
  }
  s += "\nknots_v";
  for (double k : surface.v.knots) {
    s += ' ';
    s += shortest(k);
  }
  s += "\npoints\n";
  for (std::size_t j = 0; j < surface.n_v; ++j) {
    for (std::size_t i = 0; i < surface.n_u; ++i) {
      const Eigen::Vector3d& p = surface.control_point(i, j);
      s += shortest(p.x()) + " " + shortest(p.y()) + " " + shortest(p.z()) + " " + shortest(surface.weight(i, j)) + "\n";
    }
  }
  s += "end\n";
  return s;
}

NurbsSurface surface_from_text(std::string_view text) {
  Tokens tok(text);
  tok.keyword("nurbsfront_surface");
  if (tok.count("format version") != 1) tok.fail("unsupported format version");
  NurbsSurface s;
  tok.keyword("degrees");
  const std::size_t p = tok.count("degree p");
  const std::size_t q = tok.count("degree q");
  if (p < 1 || q < 1 || p > static_cast<std::size_t>(kMaxDegree) || q > static_cast<std::size_t>(kMaxDegree)) {
    tok.fail("degree outside [1, " + std::to_string(kMaxDegree) + "]");
  }
  s.u.degree = static_cast<int>(p);
  s.v.degree = static_cast<int>(q);
  tok.keyword("counts");
  s.n_u = tok.count("n_u");
  s.n_v = tok.count("n_v");
  if (s.n_u == 0 || s.n_v == 0 || s.n_u > kMaxTextCount || s.n_v > kMaxTextCount || s.n_u * s.n_v > kMaxTextCount) {
    tok.fail("control net size out of range");
  }
  tok.keyword("knots_u");
  for (std::size_t k = 0; k < s.n_u + p + 1; ++k) s.u.knots.push_back(tok.number("knot u"));
  tok.keyword("knots_v");
  for (std::size_t k = 0; k < s.n_v + q + 1; ++k) s.v.knots.push_back(tok.number("knot v"));
  tok.keyword("points");
  s.control_points.resize(s.n_u * s.n_v);
  s.weights.resize(s.n_u * s.n_v);
  for (std::size_t k = 0; k < s.control_points.size(); ++k) {
    const double x = tok.number("x");
    const double y = tok.number("y");
    const double z = tok.number("z");
    s.control_points[k] = {x, y, z};
    s.weights[k] = tok.number("weight");
  }
  tok.keyword("end");
  s.validate();
  return s;
}

void write_surface(const std::filesystem::path& path, const NurbsSurface& surface) {
  write_file(path, surface_to_text(surface));
}

NurbsSurface read_surface(const std::filesystem::path& path) { return surface_from_text(read_file(path)); }

std::string surfaces_to_iges(const std::vector<NurbsSurface>& surfaces) {
  if (surfaces.empty()) throw InvalidInput("IGES: no surfaces to write");
  double max_coordinate = 0.0;
  for (const auto& s : surfaces) {
    s.validate();
    for (const auto& p : s.control_points) max_coordinate = std::max(max_coordinate, p.cwiseAbs().maxCoeff());
  }

  const auto card = [](const std::string& data, char section, int seq) {
    char tail[16];
    std::snprintf(tail, sizeof(tail), "%c%7d", section, seq);
    std::string line = data;
    line.resize(72, ' ');
    return line + tail + "\n";
  };
  // Packs tokens (each followed by its delimiter) into lines of `width` columns, never
  // splitting a token.
  const auto pack = [](const std::vector<std::string>& tokens, std::size_t width) {
    std::vector<std::string> lines(1);
    for (const auto& t : tokens) {
      if (!lines.back().empty() && lines.back().size() + t.size() > width) lines.emplace_back();
      lines.back() += t;
    }
    return lines;
  };

  std::string out;
  // Start section.
  out += card("nurbsfront: rational B-spline surfaces (IGES entity 128)", 'S', 1);
  // Global section.
  char date[32] = "20000101.000000";
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  if (gmtime_r(&now, &utc) != nullptr) std::strftime(date, sizeof(date), "%Y%m%d.%H%M%S", &utc);
  const std::vector<std::string> global = {
      "1H,,", "1H;,", hollerith("nurbsfront") + ",", hollerith("nurbsfront.igs") + ",",
      hollerith("nurbsfront 0.1.0") + ",", hollerith("nurbsfront nurbs 1") + ",", "32,", "38,", "6,", "308,", "15,",
      hollerith("nurbsfront") + ",", "1.0,", "2,", "2HMM,", "1,", "1.0,", hollerith(date) + ",", "1.0E-9,",
      iges_real(std::max(max_coordinate, 1.0)) + ",", hollerith("nurbsfront") + ",", hollerith("nurbsfront") + ",",
      "11,", "0,", hollerith(date) + ";"};
  const std::vector<std::string> g_lines = pack(global, 72);
  for (std::size_t k = 0; k < g_lines.size(); ++k) out += card(g_lines[k], 'G', static_cast<int>(k + 1));

  // Parameter data for every entity first (the directory needs their line counts).
  std::vector<std::vector<std::string>> p_lines;
  for (std::size_t e = 0; e < surfaces.size(); ++e) {
    const NurbsSurface& s = surfaces[e];
    std::vector<std::string> t;
    const bool polynomial = !s.is_rational();
    for (const long long x : {128LL, static_cast<long long>(s.n_u) - 1, static_cast<long long>(s.n_v) - 1,
                              static_cast<long long>(s.u.degree), static_cast<long long>(s.v.degree), 0LL, 0LL,
                              polynomial ? 1LL : 0LL, 0LL, 0LL}) {
      t.push_back(std::to_string(x) + ",");
    }
    for (double k : s.u.knots) t.push_back(iges_real(k) + ",");
    for (double k : s.v.knots) t.push_back(iges_real(k) + ",");
    for (std::size_t j = 0; j < s.n_v; ++j)
      for (std::size_t i = 0; i < s.n_u; ++i) t.push_back(iges_real(s.weight(i, j)) + ",");
    for (std::size_t j = 0; j < s.n_v; ++j) {
      for (std::size_t i = 0; i < s.n_u; ++i) {
        const Eigen::Vector3d& p = s.control_point(i, j);
        for (int c = 0; c < 3; ++c) t.push_back(iges_real(p[c]) + ",");
      }
    }
    t.push_back(iges_real(s.u.domain_min()) + ",");
    t.push_back(iges_real(s.u.domain_max()) + ",");
    t.push_back(iges_real(s.v.domain_min()) + ",");
    t.push_back(iges_real(s.v.domain_max()) + ";");
    p_lines.push_back(pack(t, 64));
  }

  // Directory entry section: two lines per entity.
  int p_start = 1;
  for (std::size_t e = 0; e < surfaces.size(); ++e) {
    const int de = static_cast<int>(2 * e + 1);
    char l1[80];
    char l2[80];
    std::snprintf(l1, sizeof(l1), "%8d%8d%8d%8d%8d%8d%8d%8d%8s", 128, p_start, 0, 0, 0, 0, 0, 0, "00000000");
    std::snprintf(l2, sizeof(l2), "%8d%8d%8d%8d%8d%8s%8s%8s%8d", 128, 0, 0, static_cast<int>(p_lines[e].size()), 0, "", "",
                  "", 0);
    out += card(l1, 'D', de);
    out += card(l2, 'D', de + 1);
    p_start += static_cast<int>(p_lines[e].size());
  }
  // Parameter data section: 64 columns of data, then the entity's directory pointer.
  int p_seq = 1;
  for (std::size_t e = 0; e < surfaces.size(); ++e) {
    for (const auto& line : p_lines[e]) {
      char pointer[16];
      std::snprintf(pointer, sizeof(pointer), "%8d", static_cast<int>(2 * e + 1));
      std::string data = line;
      data.resize(64, ' ');
      out += card(data + pointer, 'P', p_seq++);
    }
  }
  char term[80];
  std::snprintf(term, sizeof(term), "S%7dG%7dD%7dP%7d", 1, static_cast<int>(g_lines.size()), static_cast<int>(2 * surfaces.size()),
                p_seq - 1);
  out += card(term, 'T', 1);
  return out;
}

void write_iges(const std::filesystem::path& path, const std::vector<NurbsSurface>& surfaces) {
  write_file(path, surfaces_to_iges(surfaces));
}

std::vector<Eigen::Vector3d> read_xyz(const std::filesystem::path& path) {
  const std::string text = read_file(path);
  std::vector<Eigen::Vector3d> points;
  std::size_t line_no = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    std::size_t k = 0;
    const auto is_sep = [](char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r' || c == ';'; };
    while (k < line.size() && is_sep(line[k])) ++k;
    if (k == line.size() || line[k] == '#') continue;
    Eigen::Vector3d p;
    for (int c = 0; c < 3; ++c) {
      while (k < line.size() && is_sep(line[k])) ++k;
      const char* first = line.data() + k;
      const char* last = line.data() + line.size();
      if (k < line.size() && line[k] == '+') ++first;  // from_chars does not take a leading '+'
      const auto res = std::from_chars(first, last, p[c]);
      if (res.ec != std::errc() || (res.ptr != last && !is_sep(*res.ptr))) {
        throw IoError("'" + path.string() + "', line " + std::to_string(line_no) + ": expected three numbers x y z");
      }
      k = static_cast<std::size_t>(res.ptr - line.data());
    }
    points.push_back(p);
  }
  return points;
}

void write_xyz(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& points) {
  std::string s;
  for (const auto& p : points) s += shortest(p.x()) + " " + shortest(p.y()) + " " + shortest(p.z()) + "\n";
  write_file(path, s);
}

}  // namespace nurbsfront
