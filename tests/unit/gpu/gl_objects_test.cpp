#include "gpu/gl_objects.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"
#include "core/errors.hpp"

namespace scatter::gpu {
namespace {

TEST(GlContext, IsOpenGL45Core) {
  GlContext& gl = test::shared_gpu().gl();
  gl.make_current();
  GLint major = 0, minor = 0, profile = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_GE(major * 10 + minor, 45);
  EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
  EXPECT_FALSE(gl.renderer().empty());
}

// EGL gives every caller the same display: destroying one context must leave the others working.
TEST(GlContext, DestroyingOneContextLeavesOthersWorking) {
  auto first = std::make_unique<GlContext>();
  GlContext second;
  first.reset();
  EXPECT_NO_THROW(second.make_current());
  GlObject t = GlObject::create(GlKind::Texture);
  EXPECT_NE(t.get(), 0u);
  t.reset();
  test::shared_gpu().gl().make_current();
}

TEST(GlObject, MoveTransfersOwnershipAndResetDeletes) {
  test::shared_gpu().gl().make_current();
  GlObject a = GlObject::create(GlKind::Texture);
  glBindTexture(GL_TEXTURE_2D, a.get());  // a texture name becomes a texture when first bound
  glBindTexture(GL_TEXTURE_2D, 0);
  GLuint name = a.get();
  ASSERT_TRUE(glIsTexture(name));
  GlObject b = std::move(a);
  EXPECT_FALSE(a);
  EXPECT_EQ(b.get(), name);
  {
    GlObject c;
    c = std::move(b);
    EXPECT_TRUE(glIsTexture(name));
  }  // c's destructor deletes it
  EXPECT_FALSE(glIsTexture(name));
}

TEST(GlObject, ShaderErrorsCarryTheInfoLog) {
  test::shared_gpu().gl().make_current();
  try {
    build_program("shaders/surface/mesh.vert", "shaders/surface/missing.frag");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("shaders/surface/missing.frag"), std::string::npos);
  }
  // A program that builds links cleanly.
  GlObject p = build_program("shaders/surface/mesh.vert", "shaders/surface/blinn_phong.frag");
  GLint ok = 0;
  glGetProgramiv(p.get(), GL_LINK_STATUS, &ok);
  EXPECT_EQ(ok, GL_TRUE);
}

}  // namespace
}  // namespace scatter::gpu
