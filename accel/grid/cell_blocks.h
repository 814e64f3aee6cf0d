#pragma once
// The grids' cells as SIMD triangle blocks (simd=1 with the watertight test):
// every cell's list of triangle ids becomes a run of 4-wide blocks
// (accel/core/simd/leaf_blocks.h), so a visited cell tests its triangles four
// at a time with the vector watertight test, which gives the scalar test's
// hits bit for bit (triangle_block.h). The blocks replace the id list and the
// triangle copies: one load stream per cell instead of id -> triangle.
//
// A grid's references are one array in which each cell's list is a run
// [begin, end); runs tile the array. to_cell_blocks() turns that array into
// blocks, a run of n ids into ceil(n / 4) consecutive blocks, and returns
// for every run boundary its position in blocks, so the grid rewrites its
// offsets (reference positions) into block positions and keeps its layout.
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/core/huge_page_allocator.h"
#include "accel/core/simd/leaf_blocks.h"
#include "base/triangle_mesh.h"

namespace raylab {

// 4 wide, as the k-d tree's leaf blocks (kd_leaf_blocks.h).
inline constexpr int kCellBlockWidth = 4;
using CellTriangleBlock = TriangleBlock<kCellBlockWidth>;

inline uint32_t cell_block_count(uint32_t count) { return triangle_blocks<kCellBlockWidth>(count); }

// Bytes per reference that a memory budget must allow for: an id (4 bytes),
// or with blocks at least a quarter of a block (40 bytes; the exact figure
// is checked with blocks_of_runs once the lists exist).
inline uint64_t reference_bytes(bool leaf_blocks) {
  return leaf_blocks ? sizeof(CellTriangleBlock) / kCellBlockWidth : sizeof(uint32_t);
}

// The blocks the runs of compressed rows (offsets[c] .. offsets[c + 1]) need.
inline uint64_t blocks_of_runs(std::span<const uint32_t> offsets) {
  uint64_t blocks = 0;
  for (size_t c = 0; c + 1 < offsets.size(); ++c) blocks += cell_block_count(offsets[c + 1] - offsets[c]);
  return blocks;
}

struct CellBlocks {
  HugePageVector<CellTriangleBlock> blocks;  // on huge pages (huge_page_allocator.h)
  // block_at[p] for every run boundary p (a run's begin or end, refs.size()
  // included): the position of that run's first block (or of the end).
  std::vector<uint32_t> block_at;
};

// `boundaries`: every run's begin (ends are the next run's begin, or
// refs.size()), in any order, repeats allowed.
inline CellBlocks to_cell_blocks(const TriangleMesh& mesh, std::span<const uint32_t> refs,
                                 std::span<const uint32_t> boundaries) {
  CellBlocks out;
  const size_t n = refs.size();
  std::vector<uint8_t> is_start(n + 1, 0);
  for (const uint32_t b : boundaries) is_start[b] = 1;
  is_start[n] = 1;
  // Runs in order and their first blocks.
  std::vector<uint32_t> starts;
  for (size_t p = 0; p <= n; ++p)
    if (is_start[p]) starts.push_back(static_cast<uint32_t>(p));
  std::vector<uint32_t> first(starts.size());
  uint64_t total = 0;
  for (size_t r = 0; r < starts.size(); ++r) {
    first[r] = static_cast<uint32_t>(total);
    if (r + 1 < starts.size()) total += cell_block_count(starts[r + 1] - starts[r]);
  }
  if (total > UINT32_MAX) throw std::runtime_error("grid: more than 2^32 triangle blocks");
  out.blocks.resize(total);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, starts.size() - 1, 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k)
      fill_leaf_blocks<kCellBlockWidth>(mesh, refs.data() + starts[k], starts[k + 1] - starts[k],
                                          out.blocks.data() + first[k]);
  });
  out.block_at.assign(n + 1, 0);
  for (size_t r = 0; r < starts.size(); ++r) out.block_at[starts[r]] = first[r];
  return out;
}

}  // namespace raylab
