#pragma once
// Hashed storage of a grid's occupied cells (the "hashed storage" of
// uniform grids: memory proportional to the occupied cells, not to the
// resolution). Keys are linear cell indices x + rx*(y + ry*z) (< 2^60),
// spread by the 64-bit finaliser of MurmurHash3 (Appleby), so neighbouring
// cells land in unrelated slots. Open addressing with linear probing over
// one flat array of 16-byte slots, load factor at most 1/2; the full key is
// stored and compared, so a cell is never confused with another.
#include <bit>
#include <cstdint>
#include <vector>

namespace raylab {

inline uint64_t mix_cell_key(uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  k *= 0xc4ceb9fe1a85ec53ULL;
  k ^= k >> 33;
  return k;
}

struct CellSlot {
  uint64_t key;    // kEmptyKey when free
  uint32_t begin;  // first reference of the cell
  uint32_t count;  // number of references
};
static_assert(sizeof(CellSlot) == 16);

class CellHashTable {
 public:
  static constexpr uint64_t kEmptyKey = ~uint64_t{0};

  // Table for `cells` occupied cells: capacity the next power of two >= 2*cells.
  explicit CellHashTable(size_t cells = 0) {
    const size_t cap = std::bit_ceil(std::max<size_t>(2 * cells, 2));
    slots_.assign(cap, CellSlot{kEmptyKey, 0, 0});
    mask_ = cap - 1;
  }

  // Inserts a key not yet present; returns the number of probes it took.
  uint32_t insert(uint64_t key, uint32_t begin, uint32_t count) {
    uint64_t h = mix_cell_key(key) & mask_;
    uint32_t probes = 1;
    while (slots_[h].key != kEmptyKey) {
      h = (h + 1) & mask_;
      ++probes;
    }
    slots_[h] = CellSlot{key, begin, count};
    return probes;
  }

  // The cell's slot, or nullptr when the cell is empty (not stored).
  const CellSlot* find(uint64_t key) const {
    uint64_t h = mix_cell_key(key) & mask_;
    while (true) {
      const CellSlot& s = slots_[h];
      if (s.key == key) return &s;
      if (s.key == kEmptyKey) return nullptr;
      h = (h + 1) & mask_;
    }
  }

  size_t capacity() const { return slots_.size(); }
  size_t bytes() const { return slots_.capacity() * sizeof(CellSlot); }

 private:
  std::vector<CellSlot> slots_;
  uint64_t mask_ = 1;
};

}  // namespace raylab
