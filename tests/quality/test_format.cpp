// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include "fixtures/shapes.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront {
namespace {

ReportOptions coarse() {
  ReportOptions options;
  options.distance.sample_spacing_relative = 0.05;
  return options;
}

// Bracket balance outside strings, as a cheap well-formedness check.
bool balanced(const std::string& s) {
  int depth = 0;
  bool in_string = false;
  for (char c : s) {
    if (c == '"') in_string = !in_string;
    if (in_string) continue;
    if (c == '{' || c == '[') ++depth;
    if (c == '}' || c == ']') --depth;
    if (depth < 0) return false;
  }
  return depth == 0 && !in_string;
}

TEST(QualityFormat, JsonHasTheDocumentedKeys) {
  const MeshReport r = mesh_report(test::cube(), test::cube(), coarse());
  const std::string json = to_json(r);
  EXPECT_TRUE(balanced(json));
  for (const char* key : {"\"alpha\": {\"mean\": ", "\"p1\": ", "\"angles\": {\"min\": 45", "\"obtuse_fraction\": 0",
                          "\"closed\": true", "\"genus\": 0", "\"edges\": 18", "\"hausdorff\": ",
                          "\"self_intersecting_pairs\": 0", "\"volume\": 1"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing in " << json;
  }
  EXPECT_EQ(json.find("nan"), std::string::npos);
}

TEST(QualityFormat, NonFiniteBecomesNull) {
  const std::string json = to_json(mesh_report(TriangleSoup{}));
  EXPECT_TRUE(balanced(json));
  EXPECT_NE(json.find("\"mean\": null"), std::string::npos) << json;
  EXPECT_EQ(json.find("nan"), std::string::npos);
}

TEST(QualityFormat, TextNamesEverySection) {
  const std::string text = to_text(mesh_report(test::torus(12, 8), test::torus(12, 8), coarse()));
  for (const char* key : {"topology", "quality", "distance to reference", "genus 1", "self-intersecting pairs"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key;
  }
}

}  // namespace
}  // namespace nurbsfront
