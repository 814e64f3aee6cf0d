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

#include "app/label_font.h"
#include "base/atomic_file.h"
#include "tracer/ray_sets.h"

namespace raylab::cli {

namespace {

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
  // Yellow -> orange -> red -> magenta -> blue -> cyan as depth grows: six
  // hues, so neighbouring levels stay apart up to depth 6 or so.
  const float t = max_depth > 0 ? std::clamp(static_cast<float>(depth) / max_depth, 0.0f, 1.0f) : 0.0f;
  static const Vec3f stops[] = {Vec3f(1.0f, 0.9f, 0.1f),  Vec3f(1.0f, 0.45f, 0.02f), Vec3f(0.9f, 0.08f, 0.12f),
                                Vec3f(0.7f, 0.12f, 0.8f), Vec3f(0.15f, 0.3f, 1.0f),  Vec3f(0.05f, 0.8f, 0.85f)};
  constexpr int n = 6;
  const float x = t * (n - 1);
  const int i = std::min(n - 2, static_cast<int>(x));
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

CostScale fit_cost_scale(const std::vector<float>& values, ScaleKind kind) {
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
  s.log = kind == ScaleKind::Log || (kind == ScaleKind::Auto && max > 100.0 * median);
  return s;
}

std::vector<std::string> wrap_text(const std::string& text, int width, int px) {
  std::vector<std::string> lines;
  std::string line;
  size_t start = 0;
  while (start < text.size()) {
    // The next word with the separator that ends it (a space, or ',' ':' '=' kept on this line).
    size_t end = text.find_first_of(" ,:", start);
    end = end == std::string::npos ? text.size() : end + 1;
    const std::string word = text.substr(start, end - start);
    start = end;
    if (!line.empty() && text_width(line + word, px) > width) {
      while (!line.empty() && line.back() == ' ') line.pop_back();
      lines.push_back(line);
      line.clear();
    }
    line += line.empty() && word == " " ? "" : word;
  }
  while (!line.empty() && line.back() == ' ') line.pop_back();
  if (!line.empty()) lines.push_back(line);
  return lines;
}

int label_size_for(int width) { return std::clamp(width / 30, 11, 16); }

namespace {

std::string tick_text(double v) {
  if (v == 0.0) return "0";
  const double a = std::fabs(v);
  if (a >= 1e5 || a < 1e-2) return fmt::format("{:.1e}", v);
  if (a >= 100 || a == std::round(a)) return fmt::format("{:.0f}", v);
  if (a >= 10) return fmt::format("{:.1f}", v);
  return fmt::format("{:.2f}", v);
}

// Round tick values for the colour bar: 0 and round linear steps, or 0 and
// 1, 10, 100, ... (with 3, 30, ... over few decades) on a log scale.
std::vector<double> colour_bar_ticks(const CostScale& s) {
  std::vector<double> t = {s.lo};
  if (!(s.hi > s.lo)) return t;
  if (s.log) {
    const int top = static_cast<int>(std::floor(std::log10(std::max(1.0, s.hi))));
    for (int e = 0; e <= top; ++e)
      for (double m : top <= 2 ? std::vector<double>{1, 3} : std::vector<double>{1}) {
        const double v = m * std::pow(10.0, e);
        if (v > s.lo && v <= s.hi) t.push_back(v);
      }
    return t;
  }
  const double raw = (s.hi - s.lo) / 4.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
  for (double v = s.lo + step; v <= s.hi * (1 + 1e-9); v += step) t.push_back(v);
  return t;
}

void fill_rect(Image& img, int x0, int y0, int x1, int y1, const Vec3f& c) {
  for (int y = std::max(0, y0); y < std::min(img.height, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(img.width, x1); ++x) img.set(x, y, c);
}

// `picture` with bands of `above` and `below` pixels of background added.
Image with_bands(const Image& picture, int above, int below, const Vec3f& bg) {
  Image img(picture.width, picture.height + above + below);
  fill_rect(img, 0, 0, img.width, img.height, bg);
  for (int y = 0; y < picture.height; ++y)
    for (int x = 0; x < picture.width; ++x) img.set(x, y + above, picture.pixel(x, y));
  return img;
}

}  // namespace

Image cost_picture(const std::vector<float>& values, int width, int height, const CostScale& scale,
                   const std::string& label, const std::string& title, int title_rows) {
  const int px = label_size_for(width), line = text_height(px);
  const int margin = 6, bar_h = 10;
  const Vec3f bg(0.97f, 0.97f, 0.97f), ink(0.02f, 0.02f, 0.02f);
  // Title lines above the picture (never over it), the colour bar, its ticks
  // and the label below.
  const std::vector<std::string> title_lines = title.empty() ? std::vector<std::string>{} : wrap_text(title, width - 2 * margin, px);
  const std::string& legend = label;
  const std::vector<std::string> legend_lines = wrap_text(legend, width - 2 * margin, px);
  const int rows = std::max(static_cast<int>(title_lines.size()), title_rows);
  const int above = rows == 0 ? 0 : rows * line + 6;
  const int below = 6 + bar_h + 5 + line + 2 + static_cast<int>(legend_lines.size()) * line + 4;
  Image picture(width, height);
  if (values.empty()) {
    fill_rect(picture, 0, 0, width, height, Vec3f::Constant(0.2f));
    const std::string note = "no per-ray counters";
    const int npx = fitting_text_size(note, width - 2 * margin, 8, px);
    draw_text(picture, std::max(0, (width - text_width(note, npx)) / 2), (height - text_height(npx)) / 2, note,
              Vec3f::Ones(), npx);
  } else {
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        picture.set(x, y, cost_colour(static_cast<float>(scale.to_unit(values[static_cast<size_t>(y) * width + x]))));
  }
  Image img = with_bands(picture, above, below, bg);
  for (size_t i = 0; i < title_lines.size(); ++i) draw_text(img, margin, 3 + static_cast<int>(i) * line, title_lines[i], ink, px);
  const int bar_y = above + height + 6;
  const int bar_w = std::max(1, width - 2 * margin);
  for (int x = 0; x < bar_w; ++x)
    for (int y = 0; y < bar_h; ++y)
      img.set(margin + x, bar_y + y, cost_colour(static_cast<float>(x) / std::max(1, bar_w - 1)));
  // Ticks at round values; a label is skipped when it would overlap the previous one.
  int last_right = -1000;
  for (double v : colour_bar_ticks(scale)) {
    const int tx = margin + static_cast<int>(scale.to_unit(v) * (bar_w - 1));
    for (int y = 0; y < 4; ++y) blend(img, tx, bar_y + bar_h + y, ink, 1.0f);
    const std::string s = tick_text(v);
    const int w = text_width(s, px);
    const int left = std::clamp(tx - w / 2, 0, std::max(0, width - w));
    if (left < last_right + px / 2) continue;  // at least half an em between labels
    draw_text(img, left, bar_y + bar_h + 4, s, ink, px);
    last_right = left + w;
  }
  const int label_y = bar_y + bar_h + 5 + line + 2;
  for (size_t i = 0; i < legend_lines.size(); ++i)
    draw_text(img, margin, label_y + static_cast<int>(i) * line, legend_lines[i], ink, px);
  return img;
}

Image structure_picture(const Image& overlay, const std::string& title, int max_depth) {
  const int width = overlay.width, px = label_size_for(width), line = text_height(px), margin = 6;
  const Vec3f bg(0.97f, 0.97f, 0.97f), ink(0.02f, 0.02f, 0.02f);
  const std::vector<std::string> title_lines = wrap_text(title, width - 2 * margin, px);
  // The depth legend: a swatch per level in the colour its lines are drawn
  // in, laid out in rows that fit the width.
  struct Item {
    std::string text;
    int depth;
  };
  std::vector<Item> items;
  for (int d = 0; d <= max_depth; ++d) items.push_back({d == 0 ? "0 (root)" : std::to_string(d), d});
  const int swatch = std::max(8, line - 4), gap = px;
  const std::string lead = "depth:";
  std::vector<std::vector<Item>> rows(1);
  int x = margin + text_width(lead, px) + gap / 2;
  for (const auto& it : items) {
    const int w = swatch + 4 + text_width(it.text, px) + gap;
    if (x + w > width - margin && !rows.back().empty()) {
      rows.emplace_back();
      x = margin + text_width(lead, px) + gap / 2;
    }
    rows.back().push_back(it);
    x += w;
  }
  const int above = static_cast<int>(title_lines.size()) * line + 6;
  const int below = static_cast<int>(rows.size()) * (line + 2) + 8;
  Image img = with_bands(overlay, above, below, bg);
  for (size_t i = 0; i < title_lines.size(); ++i) draw_text(img, margin, 3 + static_cast<int>(i) * line, title_lines[i], ink, px);
  int y = above + overlay.height + 5;
  for (const auto& row : rows) {
    draw_text(img, margin, y, lead, ink, px);
    x = margin + text_width(lead, px) + gap / 2;
    for (const auto& it : row) {
      const int sy = y + (line - swatch) / 2;
      fill_rect(img, x, sy, x + swatch, sy + swatch, depth_colour(it.depth, max_depth));
      draw_text(img, x + swatch + 4, y, it.text, ink, px);
      x += swatch + 4 + text_width(it.text, px) + gap;
    }
    y += line + 2;
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
