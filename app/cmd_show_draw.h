#pragma once
// Drawing for the picture commands (`raylab show`, `raylab render --aov`):
// a quick eye-light shading of a scene, structure outlines projected over
// it, colour scales with a legend, and labels (app/label_font.h).
// Everything draws into a linear RGB Image (tracer/image.h).
#include <string>
#include <vector>

#include "accel/accelerator.h"
#include "scenes/scene.h"
#include "tracer/image.h"

namespace raylab::cli {

// The scene seen from its view at width x height, shaded by the cosine
// between the surface normal and the view ray ("eye light"): one primary
// ray per pixel through `accel`, no path tracing. Misses are dark grey.
Image shade_scene(const Scene& scene, const Accelerator& accel, int width, int height);

// Projects world points to pixel positions of a pinhole view.
class ViewProjector {
 public:
  ViewProjector(const View& view, int width, int height);
  // Camera-space depth along the view direction (> 0 in front of the camera).
  float depth(const Vec3f& p) const { return (p - eye_).dot(forward_); }
  // Pixel position (x right, y down) of a point with depth > 0.
  Eigen::Vector2f pixel(const Vec3f& p) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
  Vec3f eye_, forward_, right_, up_;
  float tan_half_, aspect_;
};

// A line from a to b (world space), clipped against the near plane, drawn
// with `alpha` blending.
void draw_world_line(Image& img, const ViewProjector& proj, const Vec3f& a, const Vec3f& b, const Vec3f& colour,
                     float alpha);

// The colour of structure depth `depth` out of `max_depth` (shallow =
// warm yellow, deep = blue), so levels are told apart in the overlay.
Vec3f depth_colour(int depth, int max_depth);

// Draws every element of the outline over `img` (boxes' 12 edges, quads'
// 4 edges, segments), coloured by depth; deeper levels get lower alpha so
// the shallow levels stay readable.
void draw_outline(Image& img, const ViewProjector& proj, const StructureOutline& outline);

// --- colour scales and labels ---

// A perceptually ordered colour map (dark purple -> orange -> pale yellow)
// for t in [0, 1]; our own control points, interpolated in linear RGB.
Vec3f cost_colour(float t);

// How a cost value maps onto [0, 1] of the colour map.
struct CostScale {
  double lo = 0.0, hi = 1.0;
  bool log = false;  // log10(1 + v) when the values span orders of magnitude
  double to_unit(double v) const;
  double from_unit(double t) const;
};

// How a cost picture's colours are scaled (render --aov-scale).
enum class ScaleKind { Auto, Linear, Log };

// A scale covering `values`: 0 .. max, linear or log10(1 + v); Auto takes
// log when max > 100 * median of the non-zero values.
CostScale fit_cost_scale(const std::vector<float>& values, ScaleKind kind = ScaleKind::Auto);

// `text` broken into lines no wider than `width` pixels at `px` (at spaces,
// and after ',' and ':' as specs have no spaces); a word wider than that
// stays on a line of its own.
std::vector<std::string> wrap_text(const std::string& text, int width, int px);

// The label size for a picture `width` pixels wide (11 to 16 px).
int label_size_for(int width);

// The cost values as a colour image with `title` (wrapped to fit; empty =
// none) in a band above and a legend band below: a colour bar, round tick
// values and `label` (e.g. "nodes per ray (log scale)": the caller says the scale).
// `title_rows` reserves at least that many title lines (tiles of one sheet
// line up). Empty `values`: a grey picture saying "no per-ray counters".
Image cost_picture(const std::vector<float>& values, int width, int height, const CostScale& scale,
                   const std::string& label, const std::string& title, int title_rows = 0);

// `raylab show`'s picture: the overlay with `title` (wrapped to fit) in a
// band above and a legend below: one swatch per depth 0 .. max_depth in the
// colour its elements are drawn in.
Image structure_picture(const Image& overlay, const std::string& title, int max_depth);

// Images side by side in rows of `columns` (all the same size), on a dark background.
Image contact_sheet(const std::vector<Image>& tiles, int columns);

// Writes the outline as a wireframe: .ply (vertices with colours, edge
// elements) or .obj (v / l records), by extension. Atomic.
void write_outline_wireframe(const StructureOutline& outline, const std::string& path);

}  // namespace raylab::cli
