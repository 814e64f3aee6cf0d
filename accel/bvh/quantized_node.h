#pragma once
// The compressed 8-wide node of `bvh:node=q8`: child boxes as 8-bit plane
// positions on a per-node grid whose cell is a power of two per axis
// (Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on GPUs
// Through Compressed Wide BVHs", HPG 2017; Embree's compressed BVH8 node is
// built on the same idea). 128 bytes, two cache lines, against the float
// node's four: the first line holds everything the box test reads, the
// second the child references, read only when a child is entered.
//
// Decoding is exact. The builder picks each axis's grid so that every plane
// it stores, origin + q * cell, is a float, and so that the decoded box of
// every child contains the child's float box (lower planes rounded down,
// upper planes up). One multiply-add without rounding turns a byte back into
// that float, and the traversal then runs the float node's conservative box
// test on it unchanged: its robustness argument (traverse_wide.h) holds
// because the planes it sees are floats bounding the child, as with float nodes.
//
// Unused slots decode to lo = origin + 255 cells > hi = origin on every axis
// and hold the empty leaf reference, so a ray enters them only if it starts
// hundreds of millions of cells away, and then does no work there.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "accel/bvh/bvh_wide_node.h"

namespace raylab {

struct alignas(64) QuantNode8 {
  // Line 0. Planes in WideNode's order: q[0] = lo.x, [1] = hi.x, [2] = lo.y, ...
  uint8_t q[6][8];
  float origin[3];
  // Cell size per axis as a float's biased exponent: cell = 2^(cell_exp - 127), 1..254.
  uint8_t cell_exp[3];
  uint8_t unused0;
  // Line 1.
  uint32_t child[8];
  uint32_t unused1[8];

  float cell(int axis) const {
    const uint32_t bits = static_cast<uint32_t>(cell_exp[axis]) << 23;
    float c;
    std::memcpy(&c, &bits, sizeof c);
    return c;
  }
  // The decoded plane (exact: origin + q * cell is a float by construction).
  float plane(int p, int i) const { return origin[p / 2] + static_cast<float>(q[p][i]) * cell(p / 2); }
  // The box the traversal tests: contains the child's float box; empty for unused slots.
  Aabb child_box(int i) const {
    if (child[i] == wide_ref::kEmpty) return Aabb();
    return Aabb(Vec3f(plane(0, i), plane(2, i), plane(4, i)), Vec3f(plane(1, i), plane(3, i), plane(5, i)));
  }
};
static_assert(sizeof(QuantNode8) == 128, "two cache lines");
static_assert(offsetof(QuantNode8, child) == 64, "child references on the second line");

// The compressed node holding `node`'s children: same references, each box
// replaced by the smallest grid box containing it. Throws std::domain_error
// on a non-finite child box (meshes are validated before building).
QuantNode8 quantize_node(const WideNode<8>& node);

// How much the grid loosens the boxes: sums over every used child slot of
// the decoded and of the float box's surface area (their ratio is >= 1).
struct QuantLooseness {
  double decoded_area = 0.0, float_area = 0.0;
  double area_ratio() const { return float_area > 0.0 ? decoded_area / float_area : 1.0; }
};

// The compressed tree: the same tree and triangle blocks, nodes compressed
// (parallel over nodes). The float nodes are released.
template <int W>
WideBvh<8, W, QuantNode8> quantize_wide_bvh(WideBvh<8, W>&& bvh, QuantLooseness* looseness = nullptr);

}  // namespace raylab
