#pragma once
// Pinhole camera from a scene View.
#include <cmath>

#include "base/ray.h"
#include "scenes/scene.h"

namespace raylab {

class PinholeCamera {
 public:
  explicit PinholeCamera(const View& v) : width_(v.width), height_(v.height), eye_(v.from) {
    forward_ = (v.at - v.from).normalized();
    // Right-handed: right = forward x up, so with forward +z and up +y the
    // image's right is -x (the Cornell box's green wall).
    right_ = forward_.cross(v.up).normalized();
    up_ = right_.cross(forward_);
    const float tan_half = std::tan(0.5f * v.fov_deg * 3.14159265358979f / 180.0f);
    up_ *= tan_half;
    right_ *= tan_half * static_cast<float>(v.width) / static_cast<float>(v.height);
  }

  int width() const { return width_; }
  int height() const { return height_; }

  // Ray through image position (x, y) in pixels; (0, 0) is the top-left
  // corner of the image, (width, height) the bottom-right. Unit direction.
  Ray generate(float x, float y) const {
    const float sx = 2.0f * x / static_cast<float>(width_) - 1.0f;
    const float sy = 1.0f - 2.0f * y / static_cast<float>(height_);
    const Vec3f d = (forward_ + sx * right_ + sy * up_).normalized();
    return Ray(eye_, d);
  }

 private:
  int width_, height_;
  Vec3f eye_, forward_, right_, up_;
};

}  // namespace raylab
