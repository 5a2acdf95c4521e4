#include "pipelines/reference/convex.hpp"

#include <gtest/gtest.h>

#include "scene/shapes.hpp"

namespace scatter {
namespace {

TEST(IsConvex, SpheresAndBoxesAreAndTheTorusIsNot) {
  Shape sphere;
  sphere.kind = Shape::Kind::Sphere;
  EXPECT_TRUE(is_convex(sphere.tessellate(32)));
  Shape box;
  box.kind = Shape::Kind::Box;
  EXPECT_TRUE(is_convex(box.tessellate(8)));  // repeated positions per face still close it
  Shape torus;
  torus.kind = Shape::Kind::Torus;
  EXPECT_FALSE(is_convex(torus.tessellate(32)));
  Mesh open = sphere.tessellate(32);
  open.indices.resize(open.indices.size() - 3);  // a hole
  EXPECT_FALSE(is_convex(open));
}

}  // namespace
}  // namespace scatter
