#pragma once
// Embree's SOA packets (RTCRayHit4/8/16, RTCRay4/8/16) for the adapter's
// packet modes: filled once in prepare(), in the order the rays are given,
// and traced on any sub-range [begin, end) of the prepared set.
#include <embree3/rtcore.h>

#include <span>
#include <type_traits>
#include <vector>

#include "accel/embree/embree_ray_map.h"

namespace raylab::embree_adapter {

// SOA packet types and calls per width (4, 8 or 16).
template <int N>
struct PacketApi {
  static_assert(N == 4 || N == 8 || N == 16, "Embree packets are 4, 8 or 16 wide");
  using RayHitN = std::conditional_t<N == 4, RTCRayHit4, std::conditional_t<N == 8, RTCRayHit8, RTCRayHit16>>;
  using RayN = std::conditional_t<N == 4, RTCRay4, std::conditional_t<N == 8, RTCRay8, RTCRay16>>;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHitN* r) {
    if constexpr (N == 4) rtcIntersect4(v, s, c, r);
    else if constexpr (N == 8) rtcIntersect8(v, s, c, r);
    else rtcIntersect16(v, s, c, r);
  }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, RayN* r) {
    if constexpr (N == 4) rtcOccluded4(v, s, c, r);
    else if constexpr (N == 8) rtcOccluded8(v, s, c, r);
    else rtcOccluded16(v, s, c, r);
  }
};

// Embree requires the valid mask aligned like the packet.
template <int N>
struct alignas(4 * N) ValidMask {
  int v[N] = {};
};

template <class RayN>
inline void put_ray(RayN& p, int k, const RTCRay& r) {
  // Lane k of each of the packet's arrays, grouped as origin, direction,
  // interval and time, and the ray's flags.
  p.org_x[k] = r.org_x, p.org_y[k] = r.org_y, p.org_z[k] = r.org_z;
  p.dir_x[k] = r.dir_x, p.dir_y[k] = r.dir_y, p.dir_z[k] = r.dir_z;
  p.tnear[k] = r.tnear, p.tfar[k] = r.tfar, p.time[k] = r.time;
  p.mask[k] = r.mask, p.id[k] = r.id, p.flags[k] = r.flags;
}

template <int N>
struct Packets {
  std::vector<typename PacketApi<N>::RayHitN> hit;  // closest-hit sets
  std::vector<typename PacketApi<N>::RayN> ray;     // occlusion sets
  std::vector<ValidMask<N>> valid;
};


// Rays grouped into packets in the order given; the partial last packet and
// the rays the side list marks as untraced are masked out (valid = 0).
template <int N>
inline void fill_packets(const std::vector<RTCRayHit>& aos, const std::vector<RayFix>& fixes, bool occlusion,
                  Packets<N>& out) {
  const size_t n = aos.size(), np = (n + N - 1) / N;
  out.valid.assign(np, ValidMask<N>{});
  if (occlusion) out.ray.resize(np);
  else out.hit.resize(np);
  RTCRay dummy;
  set_dummy_ray(dummy);
  for (size_t p = 0; p < np; ++p) {
    for (int k = 0; k < N; ++k) {
      const size_t i = p * N + k;
      const RTCRay& r = i < n ? aos[i].ray : dummy;
      out.valid[p].v[k] = i < n ? -1 : 0;
      if (occlusion) {
        put_ray(out.ray[p], k, r);
      } else {
        put_ray(out.hit[p].ray, k, r);
        out.hit[p].hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        out.hit[p].hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
        out.hit[p].hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
    }
  }
  for (const RayFix& f : fixes)
    if (!f.traced) out.valid[f.index / N].v[f.index % N] = 0;
}

// Valid mask of packet p restricted to [begin, end).
template <int N>
const int* packet_mask(const Packets<N>& pk, size_t p, size_t begin, size_t end, ValidMask<N>& local) {
  const size_t base = p * N;
  if (base >= begin && base + N <= end) return pk.valid[p].v;
  for (int k = 0; k < N; ++k) local.v[k] = (base + k >= begin && base + k < end) ? pk.valid[p].v[k] : 0;
  return local.v;
}

// Traces packets [begin / N, end / N] of a prepared set, masked to the rays
// in [begin, end): closest hits into a Hit span, occlusion into bytes.
template <int N, class Out>
inline void trace_packets(const Packets<N>& pk, RTCScene s, RTCIntersectContext& ctx, size_t begin, size_t end,
                          std::span<Out> out) {
  constexpr bool kOcclusion = std::is_same_v<Out, uint8_t>;
  ValidMask<N> local;
  for (size_t p = begin / N; p * N < end; ++p) {
    auto packet = [&] {
      if constexpr (kOcclusion) return pk.ray[p];
      else return pk.hit[p];
    }();
    const int* valid = packet_mask(pk, p, begin, end, local);
    if constexpr (kOcclusion) PacketApi<N>::occluded(valid, s, &ctx, &packet);
    else PacketApi<N>::intersect(valid, s, &ctx, &packet);
    const size_t base = p * N;
    for (int k = 0; k < N; ++k) {
      const size_t i = base + k;
      if (i < begin || i >= end) continue;
      if constexpr (kOcclusion) {
        out[i - begin] = packet.tfar[k] < 0.0f ? 1 : 0;  // tfar = -inf on a hit
      } else if (packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {
        out[i - begin] = Hit{packet.ray.tfar[k], packet.hit.u[k], packet.hit.v[k], packet.hit.primID[k]};
      } else {
        out[i - begin] = Hit{};
      }
    }
  }
}

}  // namespace raylab::embree_adapter
