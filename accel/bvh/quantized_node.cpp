#include "accel/bvh/quantized_node.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace raylab {

namespace {

constexpr int kMinCellExp = -126;  // cells stay normal floats: q * cell is exact
constexpr int kMaxCellExp = 127;

bool is_float(double x) { return static_cast<double>(static_cast<float>(x)) == x; }

// One axis of a node: the grid (origin, 2^e) and every used child's byte
// pair. Works in double, where origin + q * cell is exact for the grids
// tried (cell >= the float ulp of the node's coordinates, so origin / cell
// and q stay far below 2^53): every candidate plane is computed exactly and
// compared exactly with the float it must bound.
struct AxisGrid {
  double origin = 0.0;
  int exp = 0;
  uint8_t lo[8] = {}, hi[8] = {};
};

// The grid of the smallest cell exponent that holds every used child's
// interval on this axis with representable planes, starting from the least
// that can: one ulp of the node's largest coordinate, 255 cells across the
// node. `used` marks the slots to encode.
AxisGrid quantize_axis(const float* lo, const float* hi, uint32_t used, float node_lo, float node_hi) {
  const float m = std::max(std::fabs(node_lo), std::fabs(node_hi));
  int e = m >= FLT_MIN ? std::ilogb(m) - 23 : kMinCellExp;
  const double extent = static_cast<double>(node_hi) - static_cast<double>(node_lo);
  while (std::ldexp(255.0, e) < extent) ++e;
  e = std::max(e, kMinCellExp);
  for (; e <= kMaxCellExp; ++e) {
    const double cell = std::ldexp(1.0, e);
    AxisGrid g;
    g.exp = e;
    g.origin = std::floor(static_cast<double>(node_lo) / cell) * cell;
    if (!is_float(g.origin)) continue;
    const auto plane = [&](int q) { return g.origin + q * cell; };
    bool ok = true;
    for (int c = 0; c < 8 && ok; ++c) {
      if (!(used >> c & 1)) {
        g.lo[c] = 255, g.hi[c] = 0;  // decodes to an inverted interval
        continue;
      }
      // The quotients give the tightest containing planes unless lo - origin
      // (hi - origin) rounded onto a grid point from the inside of the box:
      // lo a hair below a grid point (hi above one), the hair far below
      // origin's ulp. Rounding is monotonic and grid points are doubles, so
      // the quotient is then exactly one cell inside; step one plane out.
      long ql = static_cast<long>(std::floor((static_cast<double>(lo[c]) - g.origin) / cell));
      long qh = static_cast<long>(std::ceil((static_cast<double>(hi[c]) - g.origin) / cell));
      ql = std::clamp(ql, 0L, 256L), qh = std::clamp(qh, -1L, 256L);
      while (ql > 0 && plane(static_cast<int>(ql)) > lo[c]) --ql;
      while (qh < 256 && plane(static_cast<int>(qh)) < hi[c]) ++qh;
      ok = ql >= 0 && qh <= 255 && ql <= qh && plane(static_cast<int>(ql)) <= lo[c] &&
           plane(static_cast<int>(qh)) >= hi[c] && is_float(plane(static_cast<int>(ql))) &&
           is_float(plane(static_cast<int>(qh)));
      g.lo[c] = static_cast<uint8_t>(std::clamp(ql, 0L, 255L));
      g.hi[c] = static_cast<uint8_t>(std::clamp(qh, 0L, 255L));
    }
    if (ok) return g;
  }
  throw std::domain_error("bvh node=q8: no 8-bit grid holds a child box (non-finite bounds?)");
}

}  // namespace

QuantNode8 quantize_node(const WideNode<8>& node) {
  QuantNode8 out{};
  uint32_t used = 0;
  Aabb box;
  for (int c = 0; c < 8; ++c) {
    out.child[c] = node.child[c];
    const Aabb b = node.child_box(c);
    if (node.child[c] == wide_ref::kEmpty || b.is_empty()) continue;
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(b.lo[a]) || !std::isfinite(b.hi[a]))
        throw std::domain_error("bvh node=q8: non-finite child box");
    used |= 1u << c;
    box.extend(b);
  }
  for (int a = 0; a < 3; ++a) {
    if (used == 0) {
      out.origin[a] = 0.0f;
      out.cell_exp[a] = 127;
      std::fill(out.q[2 * a], out.q[2 * a] + 8, uint8_t{255});
      std::fill(out.q[2 * a + 1], out.q[2 * a + 1] + 8, uint8_t{0});
      continue;
    }
    const AxisGrid g = quantize_axis(node.bounds[2 * a], node.bounds[2 * a + 1], used, box.lo[a], box.hi[a]);
    out.origin[a] = static_cast<float>(g.origin);
    out.cell_exp[a] = static_cast<uint8_t>(g.exp + 127);
    std::copy(g.lo, g.lo + 8, out.q[2 * a]);
    std::copy(g.hi, g.hi + 8, out.q[2 * a + 1]);
  }
  return out;
}

template <int W>
WideBvh<8, W, QuantNode8> quantize_wide_bvh(WideBvh<8, W>&& bvh, QuantLooseness* looseness) {
  WideBvh<8, W, QuantNode8> out;
  out.nodes.resize(bvh.nodes.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, bvh.nodes.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) out.nodes[i] = quantize_node(bvh.nodes[i]);
  });
  if (looseness) {
    *looseness = QuantLooseness{};
    for (size_t i = 0; i < out.nodes.size(); ++i)
      for (int c = 0; c < 8; ++c) {
        if (out.nodes[i].child[c] == wide_ref::kEmpty) continue;
        looseness->decoded_area += out.nodes[i].child_box(c).surface_area();
        looseness->float_area += bvh.nodes[i].child_box(c).surface_area();
      }
  }
  out.blocks = std::move(bvh.blocks);
  out.root_ref = bvh.root_ref;
  out.root_box = bvh.root_box;
  HugePageVector<WideNode<8>>().swap(bvh.nodes);
  return out;
}

template WideBvh<8, 4, QuantNode8> quantize_wide_bvh<4>(WideBvh<8, 4>&&, QuantLooseness*);
template WideBvh<8, 8, QuantNode8> quantize_wide_bvh<8>(WideBvh<8, 8>&&, QuantLooseness*);
template WideBvh<8, 16, QuantNode8> quantize_wide_bvh<16>(WideBvh<8, 16>&&, QuantLooseness*);

}  // namespace raylab
