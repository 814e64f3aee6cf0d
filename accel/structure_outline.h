#pragma once
// A picture of an acceleration structure as plain geometry: boxes (BVH
// nodes, grid cells), quads (k-d split planes clipped to their cell) and
// segments, each tagged with its depth in the structure. `raylab show`
// writes it as a wireframe (PLY/OBJ) and draws it over a rendering of the
// scene; the structures fill it through Accelerator::outline().
//
// Depth: 0 is the structure's root (the scene box, the root node), 1 its
// children or first-level cells, and so on. An outline asked for at
// max_depth D holds the elements of depth <= D (a structure may stop at its
// last level when D is larger).
//
// Large structures have millions of nodes: `budget` caps the number of
// elements; add() returns false once it is reached and `truncated` records
// that the picture is incomplete (structures stop walking then).
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "base/aabb.h"

namespace raylab {

struct OutlineBox {
  Aabb box;
  int depth = 0;
  bool leaf = false;  // a leaf node / an occupied cell (drawn differently from inner nodes)
};

struct OutlineQuad {
  std::array<Vec3f, 4> corners;  // in order around the quad
  int depth = 0;
};

struct OutlineSegment {
  Vec3f a, b;
  int depth = 0;
};

struct StructureOutline {
  std::string what;  // what the elements are, e.g. "BVH node boxes" (set by the structure)
  std::vector<OutlineBox> boxes;
  std::vector<OutlineQuad> quads;
  std::vector<OutlineSegment> segments;
  size_t budget = 2'000'000;
  bool truncated = false;

  size_t size() const { return boxes.size() + quads.size() + segments.size(); }
  bool empty() const { return size() == 0; }
  bool full() {
    if (size() < budget) return false;
    truncated = true;
    return true;
  }

  bool add(const OutlineBox& b) {
    if (full()) return false;
    boxes.push_back(b);
    return true;
  }
  bool add(const OutlineQuad& q) {
    if (full()) return false;
    quads.push_back(q);
    return true;
  }
  bool add(const OutlineSegment& s) {
    if (full()) return false;
    segments.push_back(s);
    return true;
  }

  // The start most structures share: names the elements and, unless the
  // structure is empty, draws its root box at depth 0. True when the
  // structure should go on with depth 1 and below.
  bool begin(std::string elements, bool structure_empty, const Aabb& root, int max_depth) {
    what = std::move(elements);
    return !structure_empty && add(OutlineBox{root, 0, false}) && max_depth >= 1;
  }

  // The quad of the plane x[axis] = pos clipped to `box`.
  static OutlineQuad split_plane(const Aabb& box, int axis, float pos, int depth) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    OutlineQuad q;
    q.depth = depth;
    const float us[4] = {box.lo[u], box.hi[u], box.hi[u], box.lo[u]};
    const float vs[4] = {box.lo[v], box.lo[v], box.hi[v], box.hi[v]};
    for (int i = 0; i < 4; ++i) {
      q.corners[i][axis] = pos;
      q.corners[i][u] = us[i];
      q.corners[i][v] = vs[i];
    }
    return q;
  }

  // Bounds of every element (empty when there is none).
  Aabb bounds() const {
    Aabb b;
    for (const auto& x : boxes) b.extend(x.box);
    for (const auto& q : quads)
      for (const auto& c : q.corners) b.extend(c);
    for (const auto& s : segments) {
      b.extend(s.a);
      b.extend(s.b);
    }
    return b;
  }
  int max_depth() const {
    int d = -1;
    for (const auto& x : boxes) d = std::max(d, x.depth);
    for (const auto& q : quads) d = std::max(d, q.depth);
    for (const auto& s : segments) d = std::max(d, s.depth);
    return d;
  }
};

}  // namespace raylab
