#include "accel/octree/octree_layouts.h"

#include <bit>
#include <stdexcept>

#include <fmt/format.h>

namespace raylab {

size_t octree_linear_slots(int depth) { return static_cast<size_t>(octree_level_offset(depth + 1)); }

size_t octree_hash_capacity(size_t entries) { return std::bit_ceil(std::max<size_t>(2 * entries, 2)); }

std::vector<OctLinearSlot> make_octree_linear(const OctreeTree& tree, int depth, uint64_t budget_bytes) {
  // 8^(depth+1)/7 slots must stay addressable and within the budget.
  if (depth > 10 || octree_linear_slots(depth) * sizeof(OctLinearSlot) > budget_bytes)
    throw std::length_error(fmt::format(
        "octree:storage=linear: the complete tree of depth {} needs {:.0f} MiB, more than the budget of {:.0f} MiB "
        "(lower max_depth or raise budget)",
        depth, std::ldexp(static_cast<double>(octree_level_offset(depth + 1)) * sizeof(OctLinearSlot), -20),
        std::ldexp(static_cast<double>(budget_bytes), -20)));
  std::vector<OctLinearSlot> slots(octree_linear_slots(depth));
  struct Item {
    uint32_t node;
    int level;
    uint64_t index;
  };
  std::vector<Item> stack{{0u, 0, 0u}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const OctreeNode& n = tree.nodes[it.node];
    slots[octree_level_offset(it.level) + it.index] = OctLinearSlot{n.first_ref, n.meta};
    for (uint32_t c = 0; c < 8; ++c)
      if (n.mask() >> c & 1u) stack.push_back({n.first_child + c, it.level + 1, 8 * it.index + c});
  }
  return slots;
}

std::vector<OctHashEntry> make_octree_hash(const OctreeTree& tree, size_t entries, OctHashLayout& layout) {
  const size_t capacity = octree_hash_capacity(entries);
  std::vector<OctHashEntry> table(capacity);
  layout.mask = capacity - 1;
  layout.shift = 64 - std::countr_zero(capacity);
  struct Item {
    uint32_t node;
    uint64_t code;
  };
  std::vector<Item> stack{{0u, 1u}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const OctreeNode& n = tree.nodes[it.node];
    uint64_t i = octree_code_hash(it.code) >> layout.shift;
    while (table[i].code != 0) i = (i + 1) & layout.mask;
    table[i] = OctHashEntry{it.code, n.first_ref, n.meta};
    for (uint32_t c = 0; c < 8; ++c)
      if (n.mask() >> c & 1u) stack.push_back({n.first_child + c, it.code << 3 | c});
  }
  layout.table = table.data();
  return table;
}

}  // namespace raylab
