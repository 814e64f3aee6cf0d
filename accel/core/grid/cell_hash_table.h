#pragma once
// Hashed storage of a grid's occupied cells (the "hashed storage" of
// uniform grids: memory proportional to the occupied cells, not to the
// resolution). Keys are linear cell indices x + rx*(y + ry*z) (< 2^60),
// spread by the 64-bit finaliser of MurmurHash3 (Appleby), so neighbouring
// cells land in unrelated slots. Open addressing with linear probing over
// one flat array of 16-byte slots, twice as many slots as cells (load factor
// 1/2, so 32 bytes per occupied cell); the hash is mapped onto the slots by
// Lemire's multiply-shift range reduction, so the capacity need not be a
// power of two. The full key is stored and compared, so a cell is never
// confused with another.
#include <algorithm>
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

  // Table for `cells` occupied cells (2 * cells slots, at least 2).
  explicit CellHashTable(size_t cells = 0) : slots_(std::max<size_t>(2 * cells, 2), CellSlot{kEmptyKey, 0, 0}) {}

  // Inserts a key not yet present; returns the number of probes it took.
  uint32_t insert(uint64_t key, uint32_t begin, uint32_t count) {
    size_t h = home(key);
    uint32_t probes = 1;
    while (slots_[h].key != kEmptyKey) {
      h = next(h);
      ++probes;
    }
    slots_[h] = CellSlot{key, begin, count};
    return probes;
  }

  // The cell's slot, or nullptr when the cell is empty (not stored).
  const CellSlot* find(uint64_t key) const {
    size_t h = home(key);
    while (true) {
      const CellSlot& s = slots_[h];
      if (s.key == key) return &s;
      if (s.key == kEmptyKey) return nullptr;
      h = next(h);
    }
  }

  // Rewrites every stored cell's run (begin, count) through f(begin, count)
  // (the cells' references turned into SIMD blocks, cell_blocks.h).
  template <typename F>
  void remap_runs(F&& f) {
    for (CellSlot& s : slots_)
      if (s.key != kEmptyKey) f(s.begin, s.count);
  }

  size_t capacity() const { return slots_.size(); }
  // Every slot, free ones with key kEmptyKey (for pictures and checks, not traversal).
  const std::vector<CellSlot>& slots() const { return slots_; }
  size_t bytes() const { return slots_.capacity() * sizeof(CellSlot); }

 private:
  size_t home(uint64_t key) const {
    return static_cast<size_t>((static_cast<unsigned __int128>(mix_cell_key(key)) * slots_.size()) >> 64);
  }
  size_t next(size_t h) const { return h + 1 == slots_.size() ? 0 : h + 1; }

  std::vector<CellSlot> slots_;
};

// The number of runs of equal keys in pairs sorted by key.
template <typename Pair, typename KeyOf>
size_t count_key_runs(const std::vector<Pair>& pairs, KeyOf key) {
  size_t runs = 0;
  for (size_t i = 0; i < pairs.size(); ++i) runs += (i == 0 || key(pairs[i]) != key(pairs[i - 1]));
  return runs;
}

struct CellTableFigures {
  uint64_t probe_sum = 0;  // over the occupied cells
  uint32_t max_probes = 0;
  uint32_t max_list = 0;  // longest cell list
};

// The cells of (cell key, triangle id) pairs sorted by key, `runs` distinct
// keys: each run becomes one cell whose list is refs[first, first + count).
template <typename Pair, typename KeyOf, typename IdOf>
CellTableFigures fill_cell_table(const std::vector<Pair>& pairs, size_t runs, KeyOf key, IdOf id,
                                 CellHashTable& table, std::vector<uint32_t>& refs) {
  table = CellHashTable(runs);
  refs.resize(pairs.size());
  CellTableFigures f;
  for (size_t i = 0; i < pairs.size();) {
    size_t j = i;
    while (j < pairs.size() && key(pairs[j]) == key(pairs[i])) {
      refs[j] = id(pairs[j]);
      ++j;
    }
    const uint32_t count = static_cast<uint32_t>(j - i);
    const uint32_t probes = table.insert(key(pairs[i]), static_cast<uint32_t>(i), count);
    f.probe_sum += probes;
    f.max_probes = std::max(f.max_probes, probes);
    f.max_list = std::max(f.max_list, count);
    i = j;
  }
  return f;
}

}  // namespace raylab
