#pragma once
// The three memory layouts of one octree, behind the same two calls the walk
// makes (node(handle, level) and child(handle, node, c)):
//
//  - pointer (storage=pointer): the canonical array, 12 bytes per node,
//    each inner node finding its 8-child block by one index (octree_node.h);
//  - linear (storage=linear): the pointerless complete-tree array of the
//    lecture notes: the nodes of level l are stored contiguously from
//    (8^l - 1) / 7 on, the children of node i of level l are nodes 8i..8i+7
//    of level l + 1, so no child index is stored at all (8 bytes per slot);
//    every slot of the complete tree down to the deepest leaf exists, so the
//    memory is 8^(depth+1)/7 slots whatever the scene;
//  - hash (storage=hash): the hashed octree of Morton location codes
//    (Ericson, Real-Time Collision Detection, 7.3.5; Warren & Salmon 1993):
//    the root's code is 1, child c of code k has code 8k + c, and only the
//    nodes with triangles in their subtree are stored, in an open-addressing
//    table (linear probing, load <= 1/2) of 16-byte entries.
//
// Handles are 64-bit: a node index (pointer), an index within the level
// (linear) or a location code (hash).
#include <cstdint>
#include <vector>

#include "accel/octree/octree_node.h"

namespace raylab {

enum class OctreeStorage : uint8_t { Pointer, Linear, Hash };

// What the walk reads of a node.
struct OctNodeRec {
  uint32_t first_child;  // pointer layout only
  uint32_t first_ref;
  uint32_t meta;  // count << 8 | child mask (as OctreeNode)
};

struct OctPointerLayout {
  static constexpr uint64_t kRoot = 0;
  const OctreeNode* nodes = nullptr;
  [[gnu::always_inline]] OctNodeRec node(uint64_t h, int) const {
    const OctreeNode& n = nodes[h];
    return OctNodeRec{n.first_child, n.first_ref, n.meta};
  }
  [[gnu::always_inline]] uint64_t child(uint64_t, const OctNodeRec& n, uint32_t c) const { return n.first_child + c; }
  // The 96-byte child block (two cache lines), fetched while the children's
  // intervals are computed: the walk otherwise waits on these loads.
  [[gnu::always_inline]] void prefetch_children(const OctNodeRec& n) const {
    const char* p = reinterpret_cast<const char*>(nodes + n.first_child);
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
  }
};

struct OctLinearSlot {
  uint32_t first_ref = 0;
  uint32_t meta = 0;
};

// First slot of each level in the complete-tree array: (8^l - 1) / 7.
inline uint64_t octree_level_offset(int level) { return ((uint64_t{1} << (3 * level)) - 1) / 7; }

struct OctLinearLayout {
  static constexpr uint64_t kRoot = 0;
  const OctLinearSlot* slots = nullptr;
  [[gnu::always_inline]] OctNodeRec node(uint64_t h, int level) const {
    const OctLinearSlot& s = slots[octree_level_offset(level) + h];
    return OctNodeRec{0, s.first_ref, s.meta};
  }
  [[gnu::always_inline]] uint64_t child(uint64_t h, const OctNodeRec&, uint32_t c) const { return 8 * h + c; }
  void prefetch_children(const OctNodeRec&) const {}
};

struct OctHashEntry {
  uint64_t code = 0;  // 0 = free slot (every location code has its leading 1 bit)
  uint32_t first_ref = 0;
  uint32_t meta = 0;
};

inline uint64_t octree_code_hash(uint64_t code) { return code * 0x9E3779B97F4A7C15ull; }

struct OctHashLayout {
  static constexpr uint64_t kRoot = 1;
  const OctHashEntry* table = nullptr;
  uint64_t mask = 0;  // capacity - 1
  int shift = 64;     // 64 - log2(capacity)

  // Every node the walk asks for is in the table: the walk only descends into
  // children whose bit is set in the parent's mask.
  [[gnu::always_inline]] OctNodeRec node(uint64_t code, int) const {
    uint64_t i = shift < 64 ? octree_code_hash(code) >> shift : 0;
    while (table[i].code != code) i = (i + 1) & mask;
    return OctNodeRec{0, table[i].first_ref, table[i].meta};
  }
  [[gnu::always_inline]] uint64_t child(uint64_t code, const OctNodeRec&, uint32_t c) const { return code << 3 | c; }
  void prefetch_children(const OctNodeRec&) const {}
};

// Memory of each layout for a tree of this shape (the two not built are
// reported too, so one build compares all three).
size_t octree_linear_slots(int depth);
size_t octree_hash_capacity(size_t entries);

// The linear array of `tree` (depth = the tree's deepest level); throws
// std::length_error when it would exceed `budget_bytes`.
std::vector<OctLinearSlot> make_octree_linear(const OctreeTree& tree, int depth, uint64_t budget_bytes);
// The hashed table of `tree`'s non-empty nodes (the root always).
std::vector<OctHashEntry> make_octree_hash(const OctreeTree& tree, size_t entries, OctHashLayout& layout);

}  // namespace raylab
