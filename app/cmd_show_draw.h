#pragma once
// Drawing for the picture commands (`raylab show`, `raylab render --aov`):
// a quick eye-light shading of a scene, structure outlines projected over
// it, colour scales with a legend, and a small bitmap font for labels.
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

// Text in a 5x7 bitmap font scaled by `scale` (lower case, digits and
// . , - + / : = ( ) _ % < >; upper case is drawn as lower case), top-left at (x, y).
void draw_text(Image& img, int x, int y, const std::string& text, const Vec3f& colour, int scale = 1);
int text_width(const std::string& text, int scale = 1);
inline int text_height(int scale = 1) { return 7 * scale; }

// How a cost value maps onto [0, 1] of the colour map.
struct CostScale {
  double lo = 0.0, hi = 1.0;
  bool log = false;  // log10(1 + v) when the values span orders of magnitude
  double to_unit(double v) const;
  double from_unit(double t) const;
};

// A scale covering `values` (0 .. max; log when max > 100 * median of the
// non-zero values).
CostScale fit_cost_scale(const std::vector<float>& values);

// The cost values as a colour image with a legend band below: a colour bar,
// tick values and `label` (e.g. "nodes per ray"). `title` is drawn in the
// top-left corner over the image (empty = none).
Image cost_picture(const std::vector<float>& values, int width, int height, const CostScale& scale,
                   const std::string& label, const std::string& title);

// Images side by side in rows of `columns` (all the same size), on a dark background.
Image contact_sheet(const std::vector<Image>& tiles, int columns);

// Writes the outline as a wireframe: .ply (vertices with colours, edge
// elements) or .obj (v / l records), by extension. Atomic.
void write_outline_wireframe(const StructureOutline& outline, const std::string& path);

}  // namespace raylab::cli
