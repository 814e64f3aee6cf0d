// The 4-wide layout's kernels (vector and scalar tests), compiled apart
// from the other widths' (bvh_kernel.h).
#include "accel/bvh/wide_kernel.h"

namespace raylab {

template std::unique_ptr<BvhKernel> make_wide_kernel<4>(const WideTree&, const TriangleMesh&, const BvhConfig&, size_t&);

}  // namespace raylab
