#pragma once
// The build figures and spec parameters every tree-shaped structure shares,
// declared, parsed and reported in one place so that a column or a parameter
// means the same for each structure (README "Statistics").
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "accel/registry.h"

namespace raylab {

// The shape of a tree as every structure reports it. Shapes measured by a
// structure's own routine (KdTreeShape, OctreeShape) carry the same fields.
struct TreeShape {
  size_t nodes = 0, inner = 0, leaves = 0, empty_leaves = 0;
  size_t references = 0;  // triangle references in leaves (or all nodes)
  size_t max_leaf_size = 0;
  int max_depth = 0;
  double avg_leaf_depth = 0.0;
  double sah_cost = std::numeric_limits<double>::quiet_NaN();  // accel/core/sah_report.h
};

inline double per_triangle(size_t count, size_t triangles) {
  return triangles ? static_cast<double>(count) / static_cast<double>(triangles) : 0.0;
}

// BuildStats from a tree's shape: nodes, leaves, depths, the reported SAH
// cost, and the reference figures tree_stat_infos() declares. `Shape` is
// TreeShape or a structure's own shape with the same fields.
template <typename Shape>
BuildStats tree_build_stats(const Shape& shape, size_t triangles) {
  BuildStats s;
  s.nodes = shape.nodes;
  s.leaves = shape.leaves;
  s.max_depth = shape.max_depth;
  s.avg_depth = shape.avg_leaf_depth;
  s.sah_cost = shape.sah_cost;
  s.extra["inner_nodes"] = static_cast<double>(shape.inner);
  s.extra["empty_leaves"] = static_cast<double>(shape.empty_leaves);
  s.extra["references"] = static_cast<double>(shape.references);
  s.extra["refs_per_triangle"] = per_triangle(shape.references, triangles);
  s.extra["max_leaf_size"] = static_cast<double>(shape.max_leaf_size);
  return s;
}

// The registry's declarations of what tree_build_stats() reports, then the
// structure's own statistics. Only the meaning of a reference differs.
inline std::vector<StatInfo> tree_stat_infos(const std::string& references, const std::string& refs_per_triangle,
                                             std::initializer_list<StatInfo> own) {
  std::vector<StatInfo> v{{"inner_nodes", "inner nodes"},
                          {"empty_leaves", "leaves without triangles"},
                          {"references", references},
                          {"refs_per_triangle", refs_per_triangle},
                          {"max_leaf_size", "largest leaf, in triangles"}};
  v.insert(v.end(), own);
  return v;
}

// The SAH constants a builder steers by (its K_T and K_I; the reported cost
// uses accel/core/sah_report.h's), declared with their ranges in one place.
// The default K_T is Wald & Havran's 15 (with K_I = 20, for scalar triangle
// tests); trees with 4-wide SIMD leaf blocks declare their own (see kdtree).
inline ParamInfo sah_traversal_cost_param(const char* restriction = "", const char* default_value = "15") {
  return ParamInfo{"ct", default_value, std::string(restriction) + "SAH cost of a traversal step (K_T)", real_in(0, 1e6)};
}
inline ParamInfo sah_intersection_cost_param(const char* restriction = "") {
  return ParamInfo{"ci", "20", std::string(restriction) + "SAH cost of a triangle test (K_I)",
                   real_in(0, 1e6, Ends::OpenLow)};
}

struct SahCosts {
  float traversal, intersection;
};

inline SahCosts parse_sah_costs(const Params& p) {
  return {static_cast<float>(p.real("ct")), static_cast<float>(p.real("ci"))};
}

// `max_depth`: auto (-1: the builder's 8 + 1.3 log2 N) or 0..limit.
inline ParamInfo depth_limit_param(int limit) {
  return ParamInfo{"max_depth", "auto", fmt::format("depth limit: auto = 8 + 1.3 log2 N, or 0..{}", limit),
                   integer_in(0, limit).or_word("auto")};
}

inline int parse_depth_limit(const Params& p) {
  return p.str("max_depth") == "auto" ? -1 : p.integer("max_depth");
}

}  // namespace raylab
