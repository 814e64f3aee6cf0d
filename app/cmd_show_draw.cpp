#include "app/cmd_show_draw.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "base/atomic_file.h"
#include "tracer/ray_sets.h"

namespace raylab::cli {

namespace {

// 5x7 glyphs, one byte per row (top first), bit 4 = leftmost column.
const std::map<char, std::array<uint8_t, 7>>& glyphs() {
  static const std::map<char, std::array<uint8_t, 7>> g = {
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'+', {0x00, 0x04, 0x04, 0x1f, 0x04, 0x04, 0x00}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0c, 0x04, 0x08}},
    {'-', {0x00, 0x00, 0x00, 0x1f, 0x00, 0x00, 0x00}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, 0x0c}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'0', {0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e}},
    {'1', {0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e}},
    {'2', {0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f}},
    {'3', {0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e}},
    {'4', {0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02}},
    {'5', {0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e}},
    {'6', {0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e}},
    {'7', {0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e}},
    {'9', {0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c}},
    {':', {0x00, 0x0c, 0x0c, 0x00, 0x0c, 0x0c, 0x00}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
    {'=', {0x00, 0x00, 0x1f, 0x00, 0x1f, 0x00, 0x00}},
    {'>', {0x10, 0x08, 0x04, 0x02, 0x04, 0x08, 0x10}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1f}},
    {'a', {0x00, 0x00, 0x0e, 0x01, 0x0f, 0x11, 0x0f}},
    {'b', {0x10, 0x10, 0x1e, 0x11, 0x11, 0x11, 0x1e}},
    {'c', {0x00, 0x00, 0x0e, 0x10, 0x10, 0x11, 0x0e}},
    {'d', {0x01, 0x01, 0x0f, 0x11, 0x11, 0x11, 0x0f}},
    {'e', {0x00, 0x00, 0x0e, 0x11, 0x1f, 0x10, 0x0e}},
    {'f', {0x06, 0x09, 0x08, 0x1c, 0x08, 0x08, 0x08}},
    {'g', {0x00, 0x0f, 0x11, 0x11, 0x0f, 0x01, 0x0e}},
    {'h', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'i', {0x04, 0x00, 0x0c, 0x04, 0x04, 0x04, 0x0e}},
    {'j', {0x02, 0x00, 0x06, 0x02, 0x02, 0x12, 0x0c}},
    {'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}},
    {'l', {0x0c, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e}},
    {'m', {0x00, 0x00, 0x1a, 0x15, 0x15, 0x11, 0x11}},
    {'n', {0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'o', {0x00, 0x00, 0x0e, 0x11, 0x11, 0x11, 0x0e}},
    {'p', {0x00, 0x00, 0x1e, 0x11, 0x1e, 0x10, 0x10}},
    {'q', {0x00, 0x00, 0x0f, 0x11, 0x0f, 0x01, 0x01}},
    {'r', {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}},
    {'s', {0x00, 0x00, 0x0f, 0x10, 0x0e, 0x01, 0x1e}},
    {'t', {0x08, 0x08, 0x1c, 0x08, 0x08, 0x09, 0x06}},
    {'u', {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0d}},
    {'v', {0x00, 0x00, 0x11, 0x11, 0x11, 0x0a, 0x04}},
    {'w', {0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0a}},
    {'x', {0x00, 0x00, 0x11, 0x0a, 0x04, 0x0a, 0x11}},
    {'y', {0x00, 0x00, 0x11, 0x11, 0x0f, 0x01, 0x0e}},
    {'z', {0x00, 0x00, 0x1f, 0x02, 0x04, 0x08, 0x1f}},
  };
  return g;
}

void blend(Image& img, int x, int y, const Vec3f& c, float alpha) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  img.set(x, y, (1.0f - alpha) * img.pixel(x, y) + alpha * c);
}

// Clips the segment to depth >= near; false when nothing is left.
bool clip_near(const ViewProjector& proj, Vec3f& a, Vec3f& b, float near) {
  const float da = proj.depth(a), db = proj.depth(b);
  if (da < near && db < near) return false;
  if (da < near) a = a + (b - a) * ((near - da) / (db - da));
  else if (db < near) b = b + (a - b) * ((near - db) / (da - db));
  return true;
}

}  // namespace

Image shade_scene(const Scene& scene, const Accelerator& accel, int width, int height) {
  const RaySet primary = make_primary_rays(scene, width, height);
  std::vector<Hit> hits(primary.rays.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, hits.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    accel.intersect(std::span<const Ray>(primary.rays.data() + r.begin(), r.size()),
                    std::span<Hit>(hits.data() + r.begin(), r.size()));
  });
  Image img(width, height);
  const Vec3f miss(0.02f, 0.02f, 0.025f), surface(0.55f, 0.55f, 0.58f);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      const Hit& h = hits[i];
      if (!h.valid()) {
        img.set(x, y, miss);
        continue;
      }
      const Vec3f e1 = scene.mesh.vertex(h.prim, 1) - scene.mesh.vertex(h.prim, 0);
      const Vec3f e2 = scene.mesh.vertex(h.prim, 2) - scene.mesh.vertex(h.prim, 0);
      const Vec3f n = e1.cross(e2).normalized();
      const float c = std::fabs(n.dot(primary.rays[i].dir.normalized()));
      img.set(x, y, surface * (0.15f + 0.85f * (std::isfinite(c) ? c : 0.0f)));
    }
  return img;
}

ViewProjector::ViewProjector(const View& v, int width, int height)
    : width_(width), height_(height), eye_(v.from) {
  // The same frame as tracer/camera.h's PinholeCamera.
  forward_ = (v.at - v.from).normalized();
  right_ = forward_.cross(v.up).normalized();
  up_ = right_.cross(forward_);
  tan_half_ = std::tan(0.5f * v.fov_deg * 3.14159265358979f / 180.0f);
  aspect_ = static_cast<float>(width) / static_cast<float>(height);
}

Eigen::Vector2f ViewProjector::pixel(const Vec3f& p) const {
  const Vec3f d = p - eye_;
  const float z = d.dot(forward_);
  const float sx = d.dot(right_) / (z * tan_half_ * aspect_);
  const float sy = d.dot(up_) / (z * tan_half_);
  return Eigen::Vector2f((sx + 1.0f) * 0.5f * width_, (1.0f - sy) * 0.5f * height_);
}

void draw_world_line(Image& img, const ViewProjector& proj, const Vec3f& a0, const Vec3f& b0, const Vec3f& colour,
                     float alpha) {
  Vec3f a = a0, b = b0;
  if (!clip_near(proj, a, b, 1e-3f)) return;
  const Eigen::Vector2f pa = proj.pixel(a), pb = proj.pixel(b);
  if (!pa.allFinite() || !pb.allFinite()) return;
  // Segments far outside the image are clipped to a generous frame first,
  // so the step count stays bounded.
  const float w = static_cast<float>(img.width), h = static_cast<float>(img.height);
  Eigen::Vector2f p = pa, q = pb;
  float t0 = 0.0f, t1 = 1.0f;
  const Eigen::Vector2f d = q - p;
  const float lo[2] = {-w, -h}, hi[2] = {2 * w, 2 * h};
  for (int k = 0; k < 2; ++k) {
    if (std::fabs(d[k]) < 1e-12f) {
      if (p[k] < lo[k] || p[k] > hi[k]) return;
      continue;
    }
    float ta = (lo[k] - p[k]) / d[k], tb = (hi[k] - p[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return;
  q = p + t1 * d;
  p = p + t0 * d;
  const int steps = static_cast<int>(std::ceil(std::max(std::fabs(q.x() - p.x()), std::fabs(q.y() - p.y())))) + 1;
  for (int s = 0; s <= steps; ++s) {
    const Eigen::Vector2f r = p + (q - p) * (static_cast<float>(s) / steps);
    blend(img, static_cast<int>(std::floor(r.x())), static_cast<int>(std::floor(r.y())), colour, alpha);
  }
}

Vec3f depth_colour(int depth, int max_depth) {
  // Yellow -> orange -> magenta -> blue as depth grows.
  const float t = max_depth > 0 ? std::clamp(static_cast<float>(depth) / max_depth, 0.0f, 1.0f) : 0.0f;
  const Vec3f stops[4] = {Vec3f(1.0f, 0.85f, 0.1f), Vec3f(1.0f, 0.35f, 0.05f), Vec3f(0.85f, 0.1f, 0.6f),
                          Vec3f(0.15f, 0.35f, 1.0f)};
  const float x = t * 3.0f;
  const int i = std::min(2, static_cast<int>(x));
  const float f = x - i;
  return (1.0f - f) * stops[i] + f * stops[i + 1];
}

void draw_outline(Image& img, const ViewProjector& proj, const StructureOutline& outline) {
  const int max_depth = std::max(outline.max_depth(), 0);
  // Many elements blend into a haze: the alpha falls with their number.
  const float base_alpha = std::clamp(60.0f / std::sqrt(static_cast<float>(outline.size()) + 1.0f), 0.15f, 0.9f);
  auto alpha_of = [&](int depth) { return std::max(0.12f, base_alpha * (1.0f - 0.5f * depth / (max_depth + 1.0f))); };
  // Deepest first, so the shallow levels end up on top.
  for (int depth = max_depth; depth >= 0; --depth) {
    const Vec3f c = depth_colour(depth, max_depth);
    const float a = alpha_of(depth);
    for (const auto& b : outline.boxes) {
      if (b.depth != depth) continue;
      Vec3f corner[8];
      for (int k = 0; k < 8; ++k)
        corner[k] = Vec3f(k & 1 ? b.box.hi.x() : b.box.lo.x(), k & 2 ? b.box.hi.y() : b.box.lo.y(),
                          k & 4 ? b.box.hi.z() : b.box.lo.z());
      for (int k = 0; k < 8; ++k)
        for (int bit = 1; bit < 8; bit <<= 1)
          if (!(k & bit)) draw_world_line(img, proj, corner[k], corner[k | bit], c, a);
    }
    for (const auto& q : outline.quads) {
      if (q.depth != depth) continue;
      for (int k = 0; k < 4; ++k) draw_world_line(img, proj, q.corners[k], q.corners[(k + 1) % 4], c, a);
    }
    for (const auto& s : outline.segments)
      if (s.depth == depth) draw_world_line(img, proj, s.a, s.b, c, a);
  }
}

Vec3f cost_colour(float t) {
  // Control points chosen by eye for monotone lightness: near-black purple,
  // purple, red-orange, orange, pale yellow.
  static const Vec3f stops[] = {Vec3f(0.002f, 0.001f, 0.015f), Vec3f(0.09f, 0.01f, 0.25f), Vec3f(0.45f, 0.03f, 0.2f),
                                Vec3f(0.85f, 0.18f, 0.03f), Vec3f(0.98f, 0.6f, 0.05f), Vec3f(0.98f, 0.95f, 0.55f)};
  constexpr int n = 6;
  const float x = std::clamp(std::isfinite(t) ? t : 0.0f, 0.0f, 1.0f) * (n - 1);
  const int i = std::min(n - 2, static_cast<int>(x));
  const float f = x - i;
  return (1.0f - f) * stops[i] + f * stops[i + 1];
}

void draw_text(Image& img, int x, int y, const std::string& text, const Vec3f& colour, int scale) {
  int cx = x;
  for (char ch : text) {
    const char c = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    const auto it = glyphs().find(c);
    if (it != glyphs().end())
      for (int row = 0; row < 7; ++row)
        for (int col = 0; col < 5; ++col)
          if (it->second[row] & (0x10 >> col))
            for (int sy = 0; sy < scale; ++sy)
              for (int sx = 0; sx < scale; ++sx) blend(img, cx + col * scale + sx, y + row * scale + sy, colour, 1.0f);
    cx += 6 * scale;
  }
}

int text_width(const std::string& text, int scale) { return static_cast<int>(text.size()) * 6 * scale; }

double CostScale::to_unit(double v) const {
  if (!std::isfinite(v)) return 0.0;
  const double a = log ? std::log10(1.0 + std::max(0.0, lo)) : lo;
  const double b = log ? std::log10(1.0 + std::max(0.0, hi)) : hi;
  const double x = log ? std::log10(1.0 + std::max(0.0, v)) : v;
  return b > a ? std::clamp((x - a) / (b - a), 0.0, 1.0) : 0.0;
}

double CostScale::from_unit(double t) const {
  if (!log) return lo + t * (hi - lo);
  const double a = std::log10(1.0 + std::max(0.0, lo)), b = std::log10(1.0 + std::max(0.0, hi));
  return std::pow(10.0, a + t * (b - a)) - 1.0;
}

CostScale fit_cost_scale(const std::vector<float>& values) {
  CostScale s;
  std::vector<float> nonzero;
  for (float v : values)
    if (std::isfinite(v) && v > 0.0f) nonzero.push_back(v);
  if (nonzero.empty()) return s;
  const auto mid = nonzero.begin() + static_cast<std::ptrdiff_t>(nonzero.size() / 2);
  std::nth_element(nonzero.begin(), mid, nonzero.end());
  const double median = *mid;
  const double max = *std::max_element(nonzero.begin(), nonzero.end());
  s.lo = 0.0;
  s.hi = max;
  s.log = max > 100.0 * median;
  return s;
}

namespace {

std::string tick_text(double v) {
  if (v == 0.0) return "0";
  const double a = std::fabs(v);
  if (a >= 1e5 || a < 1e-2) return fmt::format("{:.1e}", v);
  if (a >= 100) return fmt::format("{:.0f}", v);
  if (a >= 10) return fmt::format("{:.1f}", v);
  return fmt::format("{:.2f}", v);
}

}  // namespace

Image cost_picture(const std::vector<float>& values, int width, int height, const CostScale& scale,
                   const std::string& label, const std::string& title) {
  const int text_scale = width >= 400 ? 2 : 1;
  const int band = 14 + 3 * text_height(text_scale) + 10;
  Image img(width, height + band);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      img.set(x, y, cost_colour(static_cast<float>(scale.to_unit(values[static_cast<size_t>(y) * width + x]))));
  const Vec3f bg(0.97f, 0.97f, 0.97f), ink(0.02f, 0.02f, 0.02f);
  for (int y = height; y < height + band; ++y)
    for (int x = 0; x < width; ++x) img.set(x, y, bg);
  // Colour bar with five ticks.
  const int margin = 8, bar_y = height + 6, bar_h = 10;
  const int bar_w = std::max(1, width - 2 * margin);
  for (int x = 0; x < bar_w; ++x)
    for (int y = 0; y < bar_h; ++y)
      img.set(margin + x, bar_y + y, cost_colour(static_cast<float>(x) / std::max(1, bar_w - 1)));
  const int ticks = width >= 200 ? 5 : 3;
  for (int k = 0; k < ticks; ++k) {
    const double t = static_cast<double>(k) / (ticks - 1);
    const int tx = margin + static_cast<int>(t * (bar_w - 1));
    for (int y = 0; y < 4; ++y) blend(img, tx, bar_y + bar_h + y, ink, 1.0f);
    const std::string s = tick_text(scale.from_unit(t));
    const int w = text_width(s, text_scale);
    draw_text(img, std::clamp(tx - w / 2, 0, std::max(0, width - w)), bar_y + bar_h + 5, s, ink, text_scale);
  }
  const std::string l = label + (scale.log ? ", log" : "");
  draw_text(img, margin, bar_y + bar_h + 8 + text_height(text_scale) + 2, l, ink, text_scale);
  if (!title.empty()) {
    const int w = text_width(title, text_scale), h = text_height(text_scale);
    for (int y = 2; y < 6 + h; ++y)
      for (int x = 2; x < 6 + w; ++x) blend(img, x, y, Vec3f::Zero(), 0.6f);
    draw_text(img, 4, 4, title, Vec3f::Ones(), text_scale);
  }
  return img;
}

Image contact_sheet(const std::vector<Image>& tiles, int columns) {
  if (tiles.empty()) return Image();
  const int gap = 4, tw = tiles[0].width, th = tiles[0].height;
  columns = std::max(1, std::min<int>(columns, static_cast<int>(tiles.size())));
  const int rows = (static_cast<int>(tiles.size()) + columns - 1) / columns;
  Image sheet(columns * tw + (columns + 1) * gap, rows * th + (rows + 1) * gap);
  std::fill(sheet.rgb.begin(), sheet.rgb.end(), 0.2f);
  for (size_t i = 0; i < tiles.size(); ++i) {
    const int ox = gap + static_cast<int>(i % columns) * (tw + gap), oy = gap + static_cast<int>(i / columns) * (th + gap);
    for (int y = 0; y < std::min(th, tiles[i].height); ++y)
      for (int x = 0; x < std::min(tw, tiles[i].width); ++x) sheet.set(ox + x, oy + y, tiles[i].pixel(x, y));
  }
  return sheet;
}

void write_outline_wireframe(const StructureOutline& outline, const std::string& path) {
  const std::string ext = lower_case_extension(path);
  if (ext != ".ply" && ext != ".obj") throw OutputError(fmt::format("{}: wireframes are written as .ply or .obj", path));
  std::vector<Vec3f> verts;
  std::vector<int> vdepth;
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  auto add_vertex = [&](const Vec3f& p, int depth) {
    verts.push_back(p);
    vdepth.push_back(depth);
    return static_cast<uint32_t>(verts.size() - 1);
  };
  for (const auto& b : outline.boxes) {
    uint32_t first = 0;
    for (int k = 0; k < 8; ++k) {
      const uint32_t id = add_vertex(Vec3f(k & 1 ? b.box.hi.x() : b.box.lo.x(), k & 2 ? b.box.hi.y() : b.box.lo.y(),
                                           k & 4 ? b.box.hi.z() : b.box.lo.z()),
                                     b.depth);
      if (k == 0) first = id;
    }
    for (int k = 0; k < 8; ++k)
      for (int bit = 1; bit < 8; bit <<= 1)
        if (!(k & bit)) edges.push_back({first + k, first + (k | bit)});
  }
  for (const auto& q : outline.quads) {
    uint32_t first = 0;
    for (int k = 0; k < 4; ++k) {
      const uint32_t id = add_vertex(q.corners[k], q.depth);
      if (k == 0) first = id;
    }
    for (uint32_t k = 0; k < 4; ++k) edges.push_back({first + k, first + (k + 1) % 4});
  }
  for (const auto& s : outline.segments) {
    const uint32_t a = add_vertex(s.a, s.depth);
    const uint32_t b = add_vertex(s.b, s.depth);
    edges.push_back({a, b});
  }
  const int max_depth = std::max(outline.max_depth(), 0);
  write_file_atomically(path, [&](std::ostream& os) {
    os.precision(9);
    if (ext == ".ply") {
      os << "ply\nformat ascii 1.0\ncomment raylab structure outline: " << outline.what << "\n"
         << "element vertex " << verts.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
         << "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int depth\n"
         << "element edge " << edges.size() << "\nproperty int vertex1\nproperty int vertex2\nend_header\n";
      for (size_t i = 0; i < verts.size(); ++i) {
        const Vec3f c = depth_colour(vdepth[i], max_depth) * 255.0f;
        os << verts[i].x() << ' ' << verts[i].y() << ' ' << verts[i].z() << ' ' << static_cast<int>(c.x()) << ' '
           << static_cast<int>(c.y()) << ' ' << static_cast<int>(c.z()) << ' ' << vdepth[i] << '\n';
      }
      for (const auto& [a, b] : edges) os << a << ' ' << b << '\n';
    } else {
      os << "# raylab structure outline: " << outline.what << "\n";
      for (const auto& v : verts) os << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
      for (const auto& [a, b] : edges) os << "l " << a + 1 << ' ' << b + 1 << '\n';
    }
  });
}

}  // namespace raylab::cli
