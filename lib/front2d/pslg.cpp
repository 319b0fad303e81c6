// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/front2d/pslg.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "nurbsfront/core/error.h"

namespace nurbsfront {
namespace {

// Reads the lines of a Triangle-style file without comments and blank lines, split into tokens.
class TokenLines {
 public:
  explicit TokenLines(const std::filesystem::path& path) : path_(path) {
    std::ifstream in(path);
    if (!in) throw IoError("cannot open '" + path.string() + "'");
    std::string line;
    while (std::getline(in, line)) {
      if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
      std::istringstream ss(line);
      std::vector<std::string> tokens;
      std::string t;
      while (ss >> t) tokens.push_back(t);
      if (!tokens.empty()) lines_.push_back(std::move(tokens));
    }
  }
  [[nodiscard]] bool done() const { return next_ >= lines_.size(); }
  const std::vector<std::string>& next(std::size_t min_tokens, const char* what) {
    if (done()) fail(std::string("unexpected end of file, expected ") + what);
    const auto& l = lines_[next_++];
    if (l.size() < min_tokens) fail(std::string("too few values in ") + what);
    return l;
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw IoError("'" + path_.string() + "' line group " + std::to_string(next_) + ": " + why);
  }
  double number(const std::string& token) const {
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') fail("not a number: '" + token + "'");
    return v;
  }
  long integer(const std::string& token) const {
    char* end = nullptr;
    const long v = std::strtol(token.c_str(), &end, 10);
    if (end == token.c_str() || *end != '\0') fail("not an integer: '" + token + "'");
    return v;
  }

 private:
  std::filesystem::path path_;
  std::vector<std::vector<std::string>> lines_;
  std::size_t next_ = 0;
};

// Reads the vertex section; returns the index base (0 or 1).
long read_vertices(TokenLines& in, Pslg& pslg) {
  const auto& header = in.next(1, "vertex header");
  const long n = in.integer(header[0]);
  const long dim = header.size() > 1 ? in.integer(header[1]) : 2;
  const long n_attr = header.size() > 2 ? in.integer(header[2]) : 0;
  if (n < 0 || dim != 2 || n_attr < 0) in.fail("bad vertex header (need N 2 attributes markers)");
  long base = 0;
  std::vector<std::pair<long, Eigen::Vector2d>> read;
  std::vector<double> sizes;
  for (long i = 0; i < n; ++i) {
    const auto& l = in.next(3, "a vertex line");
    read.emplace_back(in.integer(l[0]), Eigen::Vector2d(in.number(l[1]), in.number(l[2])));
    if (n_attr > 0 && l.size() > 3) sizes.push_back(in.number(l[3]));
  }
  if (!read.empty()) base = read.front().first;
  if (base != 0 && base != 1) in.fail("vertex numbering must start at 0 or 1");
  for (long i = 0; i < n; ++i) {
    if (read[static_cast<std::size_t>(i)].first != base + i) in.fail("vertices must be numbered consecutively");
    pslg.points.push_back(read[static_cast<std::size_t>(i)].second);
  }
  if (n_attr > 0 && static_cast<long>(sizes.size()) == n) pslg.point_sizes = std::move(sizes);
  return base;
}

}  // namespace

Pslg read_node(const std::filesystem::path& path) {
  TokenLines in(path);
  Pslg pslg;
  read_vertices(in, pslg);
  return pslg;
}

Pslg read_poly(const std::filesystem::path& path) {
  TokenLines in(path);
  Pslg pslg;
  long base = read_vertices(in, pslg);
  if (pslg.points.empty()) {
    auto node = path;
    node.replace_extension(".node");
    if (std::filesystem::exists(node)) {
      TokenLines nin(node);
      base = read_vertices(nin, pslg);
    }
  }
  const auto& sh = in.next(1, "segment header");
  const long m = in.integer(sh[0]);
  if (m < 0) in.fail("negative segment count");
  for (long i = 0; i < m; ++i) {
    const auto& l = in.next(3, "a segment line");
    pslg.segments.push_back({static_cast<int>(in.integer(l[1]) - base), static_cast<int>(in.integer(l[2]) - base)});
  }
  if (in.done()) return pslg;
  const long nh = in.integer(in.next(1, "hole header")[0]);
  for (long i = 0; i < nh; ++i) {
    const auto& l = in.next(3, "a hole line");
    pslg.holes.emplace_back(in.number(l[1]), in.number(l[2]));
  }
  if (in.done()) return pslg;
  const long nr = in.integer(in.next(1, "region header")[0]);
  for (long i = 0; i < nr; ++i) {
    const auto& l = in.next(4, "a region line");
    pslg.regions.push_back({Eigen::Vector2d(in.number(l[1]), in.number(l[2])), static_cast<int>(in.number(l[3]))});
  }
  return pslg;
}

Pslg read_edg(const std::filesystem::path& path) {
  TokenLines in(path);
  const long n = in.integer(in.next(1, "segment count")[0]);
  if (n < 0) in.fail("negative segment count");
  Pslg pslg;
  std::map<std::pair<double, double>, int> index;
  auto point_id = [&](double x, double y) {
    auto [it, inserted] = index.try_emplace({x, y}, static_cast<int>(pslg.points.size()));
    if (inserted) pslg.points.emplace_back(x, y);
    return it->second;
  };
  for (long i = 0; i < n; ++i) {
    const auto& l = in.next(4, "a segment line");
    const int a = point_id(in.number(l[0]), in.number(l[1]));
    const int b = point_id(in.number(l[2]), in.number(l[3]));
    if (a != b) pslg.segments.push_back({a, b});  // zero-length segments carry no information
  }
  return pslg;
}

Pslg read_pslg(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".poly") return read_poly(path);
  if (ext == ".node") return read_node(path);
  if (ext == ".edg") return read_edg(path);
  throw IoError("unknown PSLG format '" + ext + "' of '" + path.string() + "' (expected .poly, .node or .edg)");
}

}  // namespace nurbsfront
