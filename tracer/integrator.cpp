#include "tracer/integrator.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "base/timer.h"
#include "tracer/camera.h"
#include "tracer/lights.h"
#include "base/pcg.h"
#include "tracer/sampling.h"
#include "tracer/spawn.h"

namespace raylab {

namespace {

constexpr int kTileSize = 16;
constexpr size_t kMaxPathsPerBatch = 4096;

struct Path {
  Vec3f throughput;
  Vec3f radiance;
  float prev_bsdf_pdf;  // solid-angle pdf of the direction that led here (0 for camera rays)
  uint32_t sample;      // index into the tile's sample accumulator
  Pcg32 rng;
};

float power_heuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

class TileRenderer {
 public:
  TileRenderer(const Scene& scene, const Accelerator& accel, const LightSampler& lights, const PinholeCamera& cam,
               const RenderSettings& s)
      : scene_(scene), accel_(accel), lights_(lights), cam_(cam), s_(s), spawn_(scene.bounds()) {}

  // Renders pixels [x0,x1) x [y0,y1) into img.
  void render_tile(int x0, int x1, int y0, int y1, Image& img, uint64_t& rays, uint64_t& shadow_rays) const {
    if (s_.stop && s_.stop->load(std::memory_order_relaxed)) return;  // before the tile's sample buffer is made
    const int tw = x1 - x0, th = y1 - y0;
    const size_t total = static_cast<size_t>(tw) * th * s_.spp;
    std::vector<Vec3f> sample_radiance(total, Vec3f::Zero());
    for (size_t first = 0; first < total; first += kMaxPathsPerBatch) {
      if (s_.stop && s_.stop->load(std::memory_order_relaxed)) return;
      const size_t count = std::min(kMaxPathsPerBatch, total - first);
      std::vector<Path> paths;
      std::vector<Ray> rays_batch;
      paths.reserve(count);
      rays_batch.reserve(count);
      for (size_t k = first; k < first + count; ++k) {
        const size_t pix = k / s_.spp;
        const auto smp = static_cast<uint32_t>(k % s_.spp);
        const int px = x0 + static_cast<int>(pix % tw), py = y0 + static_cast<int>(pix / tw);
        const uint64_t pixel_id = static_cast<uint64_t>(py) * s_.width + px;
        Pcg32 rng(mix64(s_.seed * 0x100000001B3ull + smp), mix64(pixel_id));
        const float jx = rng.uniform(), jy = rng.uniform();
        rays_batch.push_back(cam_.generate(static_cast<float>(px) + jx, static_cast<float>(py) + jy));
        paths.push_back(Path{Vec3f::Ones(), Vec3f::Zero(), 0.0f, static_cast<uint32_t>(k), rng});
      }
      trace_paths(paths, rays_batch, rays, shadow_rays);
      for (const Path& p : paths) sample_radiance[p.sample] = p.radiance;
    }
    const float inv_spp = 1.0f / static_cast<float>(s_.spp);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const size_t pix = static_cast<size_t>(y - y0) * tw + (x - x0);
        Vec3f sum = Vec3f::Zero();
        for (int k = 0; k < s_.spp; ++k) sum += sample_radiance[pix * s_.spp + k];
        img.set(x, y, sum * inv_spp);
      }
  }

 private:
  // Next-event estimation's shadow rays of one bounce, traced as one batch.
  struct ShadowBatch {
    std::vector<Ray> rays;
    std::vector<Vec3f> contrib;    // added to the path's radiance when the ray is not occluded
    std::vector<uint32_t> path;
    void clear() {
      rays.clear();
      contrib.clear();
      path.clear();
    }
  };

  // Samples a point on a light for the path at `origin` (normal n, BRDF f)
  // and queues its shadow ray, weighted by the power heuristic.
  void sample_light(Path& path, uint32_t path_id, const Vec3f& origin, const Vec3f& n, const Vec3f& f,
                    ShadowBatch& shadow) const {
    const float u0 = path.rng.uniform(), u1 = path.rng.uniform(), u2 = path.rng.uniform();
    const LightSampler::Sample ls = lights_.sample(u0, u1, u2);
    const Vec3f to_light = ls.point - origin;
    const float dist2 = to_light.squaredNorm();
    if (!(dist2 > 0.0f)) return;
    const float dist = std::sqrt(dist2);
    const Vec3f wi = to_light / dist;
    const float cos_s = n.dot(wi);
    const float cos_l = -ls.normal.dot(wi);
    if (!(cos_s > 0.0f && cos_l > 0.0f && ls.pdf_area > 0.0f)) return;
    const float light_pdf = ls.pdf_area * dist2 / cos_l;
    const float bsdf_pdf = cos_s * kInvPi;
    const float w = power_heuristic(light_pdf, bsdf_pdf);
    shadow.rays.push_back(shadow_ray_to(origin, ls.point));
    shadow.contrib.push_back(path.throughput.cwiseProduct(f).cwiseProduct(ls.emission) * (cos_s * w / light_pdf));
    shadow.path.push_back(path_id);
  }

  // The key light (a distant "sun"): a shadow ray towards it.
  void sample_key_light(const Path& path, uint32_t path_id, const Vec3f& origin, const Vec3f& n, const Vec3f& f,
                        ShadowBatch& shadow) const {
    const float cos_s = n.dot(scene_.key_light_dir);
    if (!(cos_s > 0.0f)) return;
    shadow.rays.emplace_back(origin, scene_.key_light_dir);
    shadow.contrib.push_back(path.throughput.cwiseProduct(f).cwiseProduct(scene_.key_light) * cos_s);
    shadow.path.push_back(path_id);
  }

  // Traces the batch's shadow rays and adds the unoccluded contributions;
  // returns the number of rays traced.
  size_t trace_shadows(const ShadowBatch& shadow, std::vector<Path>& paths, std::vector<uint8_t>& occluded) const {
    if (shadow.rays.empty()) return 0;
    occluded.resize(shadow.rays.size());
    accel_.occluded(shadow.rays, occluded);
    for (size_t j = 0; j < shadow.rays.size(); ++j)
      if (!occluded[j]) paths[shadow.path[j]].radiance += shadow.contrib[j];
    return shadow.rays.size();
  }

  void trace_paths(std::vector<Path>& paths, std::vector<Ray>& rays, uint64_t& ray_count,
                   uint64_t& shadow_count) const {
    std::vector<uint32_t> active(paths.size());
    for (uint32_t i = 0; i < active.size(); ++i) active[i] = i;
    std::vector<Hit> hits;
    ShadowBatch shadow;
    std::vector<uint8_t> occluded;
    std::vector<Ray> next_rays;
    std::vector<uint32_t> next_active;

    for (int depth = 0; !active.empty(); ++depth) {
      hits.resize(active.size());
      accel_.intersect(rays, hits);
      ray_count += rays.size();
      shadow.clear();
      next_rays.clear();
      next_active.clear();

      for (size_t k = 0; k < active.size(); ++k) {
        Path& path = paths[active[k]];
        const Ray& ray = rays[k];
        const Hit& hit = hits[k];
        if (!hit.valid()) {
          path.radiance += path.throughput.cwiseProduct(scene_.background);
          continue;
        }
        const uint32_t tri = hit.prim;
        const Vec3f& p0 = scene_.mesh.vertex(tri, 0);
        const Vec3f& p1 = scene_.mesh.vertex(tri, 1);
        const Vec3f& p2 = scene_.mesh.vertex(tri, 2);
        const Vec3f cross = (p1 - p0).cross(p2 - p0);
        const float cross_len = cross.norm();
        if (!(cross_len > 0.0f)) continue;  // degenerate triangle: end the path
        const Vec3f ng = cross / cross_len;
        const float cos_in = ng.dot(ray.dir);
        const bool front = cos_in < 0.0f;
        const Material& mat = scene_.material_of(tri);

        if (front && mat.is_emissive()) {
          float w = 1.0f;
          if (depth > 0 && path.prev_bsdf_pdf > 0.0f) {
            const float light_pdf = lights_.pdf_area(tri) * hit.t * hit.t / (-cos_in);
            w = power_heuristic(path.prev_bsdf_pdf, light_pdf);
          }
          path.radiance += w * path.throughput.cwiseProduct(mat.emission);
        }
        if (depth + 1 >= s_.max_depth || mat.albedo.maxCoeff() <= 0.0f) continue;

        const Vec3f n = front ? ng : Vec3f(-ng);
        const Vec3f p = (1.0f - hit.u - hit.v) * p0 + hit.u * p1 + hit.v * p2;
        const Vec3f origin = spawn_.origin(p, n, ray.org);
        const Vec3f f = mat.albedo * kInvPi;  // Lambertian BRDF

        if (!lights_.empty()) sample_light(path, active[k], origin, n, f, shadow);

        if (scene_.key_light.maxCoeff() > 0.0f) sample_key_light(path, active[k], origin, n, f, shadow);

        // Continue the path by cosine-weighted sampling.
        const float b1 = path.rng.uniform(), b2 = path.rng.uniform();
        float pdf;
        const Vec3f wi = sample_cosine_hemisphere(n, b1, b2, pdf);
        if (!(pdf > 0.0f)) continue;
        path.throughput = path.throughput.cwiseProduct(mat.albedo);  // f * cos / pdf
        path.prev_bsdf_pdf = pdf;
        if (depth + 1 >= s_.rr_depth) {
          const float q = std::min(0.95f, path.throughput.maxCoeff());
          if (path.rng.uniform() >= q) continue;
          path.throughput /= q;
        }
        next_rays.emplace_back(origin, wi);
        next_active.push_back(active[k]);
      }

      shadow_count += trace_shadows(shadow, paths, occluded);
      rays.swap(next_rays);
      active.swap(next_active);
    }
  }

  const Scene& scene_;
  const Accelerator& accel_;
  const LightSampler& lights_;
  const PinholeCamera& cam_;
  const RenderSettings& s_;
  SpawnOffset spawn_;
};

}  // namespace

RenderResult render(const Scene& scene, const Accelerator& accel, const RenderSettings& settings) {
  if (settings.width <= 0 || settings.height <= 0) throw std::invalid_argument("render: image size must be positive");
  if (settings.spp <= 0) throw std::invalid_argument("render: samples per pixel must be positive");
  View view = scene.view;
  view.width = settings.width;
  view.height = settings.height;
  const PinholeCamera cam(view);
  const LightSampler lights(scene);
  const TileRenderer tiles(scene, accel, lights, cam, settings);

  RenderResult result;
  result.image = Image(settings.width, settings.height);
  const int tiles_x = (settings.width + kTileSize - 1) / kTileSize;
  const int tiles_y = (settings.height + kTileSize - 1) / kTileSize;
  const int tile_count = tiles_x * tiles_y;
  std::atomic<uint64_t> rays{0}, shadow_rays{0};
  std::atomic<int> done{0};
  std::mutex print_mutex;
  bool printed = false;
  Timer timer;

  tbb::parallel_for(tbb::blocked_range<int>(0, tile_count, 1), [&](const tbb::blocked_range<int>& r) {
    for (int t = r.begin(); t < r.end(); ++t) {
      const int tx = t % tiles_x, ty = t / tiles_x;
      uint64_t nr = 0, ns = 0;
      tiles.render_tile(tx * kTileSize, std::min(settings.width, (tx + 1) * kTileSize), ty * kTileSize,
                        std::min(settings.height, (ty + 1) * kTileSize), result.image, nr, ns);
      rays += nr;
      shadow_rays += ns;
      const int d = ++done;
      if (settings.progress && timer.seconds() > 1.0) {
        std::lock_guard<std::mutex> lock(print_mutex);
        // Rate and estimate from the tiles done so far (tiles cost alike on average).
        const double elapsed = timer.seconds();
        const double left = elapsed / d * (tile_count - d);
        const double mrays = (rays.load() + shadow_rays.load()) / std::max(elapsed, 1e-9) * 1e-6;
        std::fprintf(stderr, "\r\033[Krender: %3d%% (%d/%d tiles) %.1f s elapsed, %.2f Mrays/s, ~%.0f s left",
                     100 * d / tile_count, d, tile_count, elapsed, mrays, left);
        std::fflush(stderr);
        printed = true;
      }
    }
  });
  if (printed) std::fprintf(stderr, "\n");
  result.seconds = timer.seconds();
  result.rays = rays.load();
  result.shadow_rays = shadow_rays.load();
  result.complete = !(settings.stop && settings.stop->load());
  return result;
}

}  // namespace raylab
