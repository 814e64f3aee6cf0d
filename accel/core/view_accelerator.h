#pragma once
// The shell of a structure traced through one view (a small struct of
// pointers into its arrays) by one walk: the options it was made with, the
// view, and the single-ray kernel BatchAccelerator calls. The kernel is the
// walk overloaded on the view's type, `traverse_view` (declared beside each
// structure's walk, as the grids overload traverse_grid), so a structure adds
// only its build and outline.
#include "accel/core/batch_accelerator.h"

namespace raylab {

template <typename Structure, typename Options, typename View>
class ViewAccelerator : public BatchAccelerator<Structure> {
 public:
  ViewAccelerator(const Options& opt, TriangleTest test) : BatchAccelerator<Structure>(test), opt_(opt) {}

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return traverse_view<kTest, kAnyHit, kCount>(view_, ray, stats);
  }

 protected:
  Options opt_;
  View view_;
};

}  // namespace raylab
