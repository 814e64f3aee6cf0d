#include <cmath>

#include <tbb/parallel_for.h>

#include "accel/bvh/traverse_sphere_bvh.h"

namespace raylab {

namespace {

// The vertices of every triangle below `node`.
void gather_points(const HugePageVector<Bvh2Node>& nodes, const HugePageVector<LeafTriangle>& tris, uint32_t node,
                   std::vector<Vec3f>& out) {
  uint32_t stack[kBvh2StackSize];
  int sp = 0;
  stack[sp++] = node;
  while (sp > 0) {
    const Bvh2Node& n = nodes[stack[--sp]];
    if (n.count != 0) {
      for (uint32_t i = n.index; i < n.index + n.count; ++i) out.insert(out.end(), {tris[i].p0, tris[i].p1, tris[i].p2});
    } else {
      stack[sp++] = n.index;
      stack[sp++] = n.index + 1;
    }
  }
}

}  // namespace

void outline_sphere_bvh(const SphereBvh& bvh, int max_depth, StructureOutline& out) {
  out.what = "bounding spheres (three great circles each)";
  if (bvh.nodes.empty()) return;
  struct Item {
    uint32_t node;
    int depth;
  };
  std::vector<Item> stack{{0, 0}};
  constexpr int kSegments = 12;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    if (it.depth > max_depth) continue;
    const SphereNode& n = bvh.nodes[it.node];
    const Vec3f c(n.c[0], n.c[1], n.c[2]);
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int k = 0; k < kSegments; ++k) {
        const float a0 = 2.0f * static_cast<float>(M_PI) * k / kSegments, a1 = 2.0f * static_cast<float>(M_PI) * (k + 1) / kSegments;
        Vec3f p0 = c, p1 = c;
        p0[u] += n.r * std::cos(a0), p0[v] += n.r * std::sin(a0);
        p1[u] += n.r * std::cos(a1), p1[v] += n.r * std::sin(a1);
        if (!out.add(OutlineSegment{p0, p1, it.depth})) return;
      }
    }
    if (n.count == 0) {
      stack.push_back({n.index + 1, it.depth + 1});
      stack.push_back({n.index, it.depth + 1});
    }
  }
}

SphereBvh make_sphere_bvh(Bvh2Layout layout) {
  SphereBvh out;
  const size_t count = layout.tris.empty() ? 0 : layout.nodes.size();
  out.nodes.resize(count);
  std::vector<double> sphere_vol(count), box_vol(count), sphere_area(count), box_area(count);
  tbb::parallel_for(size_t{0}, count, [&](size_t i) {
    const Bvh2Node& n = layout.nodes[i];
    std::vector<Vec3f> points;
    gather_points(layout.nodes, layout.tris, static_cast<uint32_t>(i), points);
    const Sphere s = ritter_sphere(points);
    SphereNode& sn = out.nodes[i];
    for (int a = 0; a < 3; ++a) sn.c[a] = s.center[a];
    sn.r = s.radius;
    sn.index = n.index;
    sn.count = n.count;
    const Aabb b = n.bounds();
    const Vec3d d = b.diagonal().cast<double>();
    sphere_vol[i] = s.volume();
    sphere_area[i] = s.surface_area();
    box_vol[i] = d.x() * d.y() * d.z();
    box_area[i] = 2.0 * (d.x() * d.y() + d.y() * d.z() + d.z() * d.x());
  });
  double sv = 0, bv = 0, sa = 0, ba = 0, ratio_sum = 0;
  size_t ratio_n = 0;
  for (size_t i = 0; i < count; ++i) {
    sv += sphere_vol[i];
    bv += box_vol[i];
    sa += sphere_area[i];
    ba += box_area[i];
    if (box_area[i] > 0) {
      ratio_sum += sphere_area[i] / box_area[i];
      ratio_n++;
    }
  }
  out.looseness.volume_ratio = bv > 0 ? sv / bv : 0.0;
  out.looseness.area_ratio = ba > 0 ? sa / ba : 0.0;
  out.looseness.mean_node_area_ratio = ratio_n ? ratio_sum / static_cast<double>(ratio_n) : 0.0;
  out.tris = std::move(layout.tris);
  return out;
}

}  // namespace raylab
