#pragma once
// The `tri` parameter, declared and parsed in one place for every structure
// that offers both triangle tests.
#include "accel/core/intersect_triangle.h"
#include "base/spec.h"

namespace raylab {

inline ParamInfo triangle_test_param(const char* restriction = "") {
  return ParamInfo{"tri", "watertight",
                   std::string("triangle test: watertight (Woop et al. 2013) or mt (Moller-Trumbore)") + restriction,
                   one_of({"watertight", "mt"})};
}

inline TriangleTest parse_triangle_test(const Params& p) {
  return p.str("tri") == "mt" ? TriangleTest::MollerTrumbore : TriangleTest::Watertight;
}

}  // namespace raylab
