#pragma once
// The irregular grid of Perard-Gayot, Kalojanov & Slusallek, "GPU Ray
// Tracing using Irregular Grids", Eurographics 2017, on the CPU.
//
// Every cell is an axis-aligned box of the *virtual grid*: the top grid
// refined 2^depth times on each axis (the deepest octree level allowed).
// Cell boxes are integer ranges of virtual voxels, so merging, expanding
// and the walk's steps are exact integer operations; only the exit
// distances are computed in floating point (double).
//
// The voxel map (which cell owns a voxel) is the top grid plus one octree
// per top cell, flattened k <= 3 levels at a time: an entry is either a cell
// id or, with kIrgridInnerNode set, k and the offset of a block of (2^k)^3
// entries (child = the next k bits of x, y, z, most significant first). Merging rewrites the entries of the
// merged cells; expansion only grows a cell's own box (`lo`/`hi`), so boxes
// may overlap their neighbours while the map still names each voxel's owner.
//
// A cell's triangles are either ids into `refs` (scalar test, either
// triangle test) or, with leaf blocks (simd=1, tri=watertight), the BVH's
// SIMD triangle blocks (8 wide here), stored with the cell: `slabs` holds
// per cell its record (32 bytes, padded to a chunk) followed by its blocks,
// and the voxel map's leaf entries name the record's position there. The
// walk then goes voxel map -> cell record and blocks in consecutive cache
// lines (one stream the walk can prefetch as soon as it knows the next
// cell), instead of map -> cell -> id -> triangle; the block test gives the scalar test's hits bit
// for bit (triangle_block.h).
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

#include "accel/core/huge_page_allocator.h"
#include "accel/core/simd/triangle_block.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/grid/dda_grid.h"

namespace raylab {

// Everything one step of the walk reads, in one 32-byte record.
struct IrgridCell {
  int32_t lo[3], hi[3];  // virtual voxels [lo, hi), the expanded box
  // count triangles: refs[begin, begin + count), or with leaf blocks the
  // irgrid_blocks(count) blocks after the record.
  uint32_t begin = 0, count = 0;
};
static_assert(sizeof(IrgridCell) == 32);

// The cells' SIMD triangle blocks: 8 triangles per block (cells hold 25-36
// triangles on average with the default densities, so 8 lanes are mostly
// full; measured in docs/structures/irgrid.md).
inline constexpr int kIrgridBlockWidth = 8;
using IrgridTriangleBlock = TriangleBlock<kIrgridBlockWidth>;
inline uint32_t irgrid_blocks(uint32_t count) { return triangle_blocks<kIrgridBlockWidth>(count); }

// The unit of `slabs`, as large as a block's alignment: a cell record (padded)
// or a part of a block.
struct alignas(IrgridTriangleBlock) IrgridChunk {
  std::byte bytes[alignof(IrgridTriangleBlock)];
};
inline constexpr uint32_t kIrgridChunksPerBlock = sizeof(IrgridTriangleBlock) / sizeof(IrgridChunk);
static_assert(sizeof(IrgridTriangleBlock) % sizeof(IrgridChunk) == 0);
static_assert(sizeof(IrgridCell) <= sizeof(IrgridChunk));

inline constexpr uint32_t kIrgridInnerNode = 0x80000000u;
inline constexpr int kIrgridLevelsShift = 29;  // bits 29-30 of an inner entry: k
inline constexpr uint32_t kIrgridBlockMask = (1u << kIrgridLevelsShift) - 1;
inline constexpr int kIrgridMaxLevelsPerBlock = 3;

struct Irgrid {
  DdaGrid top;      // the top grid
  DdaGrid virt;     // the virtual grid: top refined 2^depth per axis (same box)
  int depth = 0;    // log2 of the refinement: the deepest octree level allowed
  // The arrays the walk reads on huge pages (huge_page_allocator.h: the
  // walk touches tens of megabytes, and with 4 KiB pages nearly every
  // lookup would also miss the TLB).
  HugePageVector<uint32_t> top_nodes;  // per top cell: its root entry
  HugePageVector<uint32_t> nodes;      // blocks of (2^k)^3 child entries
  std::vector<IrgridCell> cells;    // empty with leaf blocks
  std::vector<uint32_t> refs;       // empty with leaf blocks
  std::vector<LeafTriangle> tris;   // empty with leaf blocks
  // With leaf blocks: per cell its record, then irgrid_blocks(count) blocks;
  // the voxel map's leaf entries are record positions (in chunks).
  HugePageVector<IrgridChunk> slabs;
  bool leaf_blocks = false;
  bool empty = true;

  // The cell record and the blocks at slab position `at` (objects the
  // builder created there with placement new).
  const IrgridCell& slab_cell(uint32_t at) const {
    return *std::launder(reinterpret_cast<const IrgridCell*>(slabs.data() + at));
  }
  const IrgridTriangleBlock* slab_blocks(uint32_t at) const {
    return std::launder(reinterpret_cast<const IrgridTriangleBlock*>(slabs.data() + at + 1));
  }
  static uint32_t slab_chunks(uint32_t count) { return 1 + irgrid_blocks(count) * kIrgridChunksPerBlock; }

  // Every cell in order (either layout).
  template <typename F>
  void for_each_cell(F&& f) const {
    if (!leaf_blocks) {
      for (const IrgridCell& c : cells) f(c);
      return;
    }
    for (size_t at = 0; at < slabs.size(); at += slab_chunks(slab_cell(static_cast<uint32_t>(at)).count))
      f(slab_cell(static_cast<uint32_t>(at)));
  }

  // The deepest block a walk's last lookup went through. The next voxel of
  // a walk is a neighbour of the last, usually under the same block, so the
  // lookup resumes there instead of at the top entry (the same answer: the
  // block is the voxel map of everything sharing its prefix).
  struct LookupCache {
    uint32_t entry = 0;  // the block's inner entry
    int shift = 0, k = 0;  // k = 0: nothing cached
    int32_t prefix[3] = {0, 0, 0};  // v >> (shift + k) of the voxels under the block
  };

  // The cell owning virtual voxel v (coordinates inside the virtual grid).
  [[gnu::always_inline]] uint32_t cell_at(const int32_t v[3], LookupCache& cache) const {
    uint32_t e;
    int shift;
    const int above = cache.shift + cache.k;
    if (cache.k != 0 && (v[0] >> above) == cache.prefix[0] && (v[1] >> above) == cache.prefix[1] &&
        (v[2] >> above) == cache.prefix[2]) {
      e = cache.entry;
      shift = above;
    } else {
      e = top_nodes[(v[0] >> depth) * top.stride[0] + (v[1] >> depth) * top.stride[1] +
                    (v[2] >> depth) * top.stride[2]];
      shift = depth;
    }
    while (e & kIrgridInnerNode) {
      const int k = static_cast<int>((e >> kIrgridLevelsShift) & 3);
      cache.entry = e;
      cache.k = k;
      for (int a = 0; a < 3; ++a) cache.prefix[a] = v[a] >> shift;
      shift -= k;
      cache.shift = shift;
      const uint32_t mask = (1u << k) - 1;
      const uint32_t child = ((static_cast<uint32_t>(v[0]) >> shift) & mask) |
                             (((static_cast<uint32_t>(v[1]) >> shift) & mask) << k) |
                             (((static_cast<uint32_t>(v[2]) >> shift) & mask) << (2 * k));
      e = nodes[(e & kIrgridBlockMask) + child];
    }
    return e;
  }

  size_t bytes() const {
    return top_nodes.size() * sizeof(uint32_t) + nodes.size() * sizeof(uint32_t) +
           cells.size() * sizeof(IrgridCell) + refs.size() * sizeof(uint32_t) + tris.size() * sizeof(LeafTriangle) +
           slabs.size() * sizeof(IrgridChunk);
  }
};

}  // namespace raylab
