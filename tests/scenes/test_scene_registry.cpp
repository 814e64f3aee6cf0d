// The scene registry: names and parameters of the procedural scenes and mesh
// files load_scene() accepts (scenes/scene_registry.h).
#include <gtest/gtest.h>

#include <stdexcept>

#include "scenes/scene_registry.h"

namespace raylab {
namespace {

TEST(SceneRegistry, UnknownScenesAndParametersAreErrors) {
  EXPECT_EQ(load_scene("soup:n=123").num_triangles(), 123u);
  EXPECT_EQ(load_scene("cornell").num_triangles(), 32u);
  EXPECT_THROW(load_scene("nosuchscene"), SpecError);
  EXPECT_THROW(load_scene("soup:n=-5"), SpecError);
  EXPECT_THROW(load_scene("soup:q=1"), SpecError);
  EXPECT_THROW(load_scene("terrain:roughness=1"), SpecError);  // parameters declare their valid values
  EXPECT_THROW(load_scene("missing/file.ply"), std::runtime_error);
}

}  // namespace
}  // namespace raylab
