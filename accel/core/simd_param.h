#pragma once
// The `simd` parameter, declared in one place for every structure with SIMD
// kernels: simd=0 keeps the same structure and the same walk but tests with
// scalar kernels, so a study can separate the algorithm from the engineering
// (the registry's scalar_variant names it).
#include <string>
#include <string_view>

#include "base/spec.h"

namespace raylab {

// `simd_what` says what SIMD covers in this structure ("leaves as 4-wide SIMD
// triangle blocks"); `note` is appended inside the closing parenthesis.
inline ParamInfo simd_param(std::string_view simd_what = "triangles as 4-wide SIMD blocks (tri=watertight)",
                            std::string_view note = "") {
  std::string help = "1 = ";
  help += simd_what;
  help += "; 0 = the same structure tested with scalar kernels (same hits";
  help += note;
  help += ")";
  return ParamInfo{"simd", "1", std::move(help), boolean_flag()};
}

inline bool parse_simd(const Params& p) { return p.boolean("simd"); }

}  // namespace raylab
