#pragma once
// Post-build optimisation of a binary BVH by subtree reinsertion, after
// Bittner, Hapala & Havran, "Fast Insertion-Based Optimization of Bounding
// Volume Hierarchies" (CGF 2013), in the batched parallel form of Meister &
// Bittner, "Parallel Reinsertion for Bounding Volume Hierarchy Optimization"
// (CGF 2018):
//
//   repeat for at most max_rounds rounds, or until a round gains < min_gain:
//     pick the nodes with the worst inefficiency measure
//       (area * area/mean child area * area/min child area, Bittner 4.1),
//     for each, in parallel, find by branch and bound the position where
//       reinserting its subtree (as the sibling of another node) lowers the
//       SAH cost most, accounting for the boxes shrinking when it leaves,
//     apply the improving moves greedily by gain, skipping moves whose
//       nodes an earlier move of the round already touched, refitting boxes.
//
// Leaves are moved whole, so only inner-node areas change; the SAH cost used
// is the reporting one (bvh2_node.h constants). The result is re-laid out
// depth first. Trees that would exceed kMaxTreeDepth are left unchanged.
// The work is bounded (rounds x batch), never the wall clock: the same input
// gives the same tree however loaded the machine is.
#include "accel/bvh/build_common.h"

namespace raylab {

struct ReinsertionOptions {
  int max_rounds = 32;            // 0 leaves the tree unchanged
  double batch_fraction = 0.15;   // nodes considered per round, as a fraction of all nodes
  double min_gain = 2e-4;         // stop when a round improves the SAH cost by less (relative)
  // Measure every node every round instead of the ones the last round's
  // moves changed: the same tree, slower (for tests of that equivalence).
  bool remeasure_all = false;
};

struct ReinsertionStats {
  double sah_before = 0.0, sah_after = 0.0;
  int rounds = 0;
  size_t moves = 0;
  double ms = 0.0;
};

// The candidates of a round: the indices of the (at most) k largest non-zero
// keys, ties broken by the lower index, in no particular order. Keys are the
// measure's float bits (which order like non-negative floats; 0: never).
void select_largest_keys(const std::vector<uint32_t>& keys, size_t k, std::vector<uint32_t>& out);

BinaryBvh optimize_reinsertion(const BinaryBvh& tree, const ReinsertionOptions& options,
                               ReinsertionStats* stats = nullptr);

}  // namespace raylab
