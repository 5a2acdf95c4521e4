#include "scene/shapes.hpp"

#include <gtest/gtest.h>

namespace scatter {
namespace {

Shape sphere() {
  return Shape{Shape::Kind::Sphere, {0.1, -0.2, 0.3}, 0.8};
}
Shape box() {
  Shape s;
  s.kind = Shape::Kind::Box;
  s.size = {2, 1, 0.5};
  return s;
}
Shape torus() {
  Shape s;
  s.kind = Shape::Kind::Torus;
  s.major_radius = 0.6;
  s.minor_radius = 0.2;
  s.axis = normalize(Vec3{0, 1, 1});
  return s;
}

TEST(Shapes, TessellationsAreWatertightOutwardAndCloseInVolume) {
  for (const Shape& s : {sphere(), box(), torus()}) {
    Mesh m = s.tessellate(128);
    WatertightReport r = check_watertight(m);
    EXPECT_TRUE(r.watertight()) << r.summary();
    // A fine tessellation is inscribed: a little smaller than the exact solid, never inside-out.
    EXPECT_GT(m.volume(), 0.99 * s.volume());
    EXPECT_LE(m.volume(), 1.0001 * s.volume());
  }
}

TEST(Shapes, InsideTests) {
  EXPECT_TRUE(sphere().inside({0.1, -0.2, 1.0}));
  EXPECT_FALSE(sphere().inside({0.1, -0.2, 1.2}));
  EXPECT_TRUE(box().inside({0.99, 0.49, 0.24}));
  EXPECT_FALSE(box().inside({0.5, 0.6, 0}));
  Shape t = torus();
  Vec3 u = normalize(cross(Vec3{1, 0, 0}, t.axis));
  EXPECT_FALSE(t.inside({0, 0, 0}));  // the hole
  EXPECT_TRUE(t.inside(u * 0.6));     // centre of the tube
  EXPECT_FALSE(t.inside(u * 0.6 + t.axis * 0.21));
}

TEST(Shapes, AnalyticVolumes) {
  EXPECT_NEAR(sphere().volume(), 4.0 / 3 * M_PI * 0.512, 1e-12);
  EXPECT_NEAR(box().volume(), 1.0, 1e-12);
  EXPECT_NEAR(torus().volume(), 2 * M_PI * M_PI * 0.6 * 0.04, 1e-12);
}

}  // namespace
}  // namespace scatter
