#include "gpu/cl_context.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"

namespace scatter::gpu {
namespace {

TEST(ClContext, ListsAndPicksADevice) {
  auto devices = list_cl_devices();
  ASSERT_FALSE(devices.empty()) << "setup installs pocl-opencl-icd";
  ClContext& cl = test::shared_gpu().cl();
  EXPECT_FALSE(cl.info().name.empty());
  EXPECT_THROW(ClContext("no such device name"), GpuError);
}

TEST(ClContext, BuffersAreReferenceCounted) {
  ClContext& cl = test::shared_gpu().cl();
  cl::Buffer a(cl.context(), CL_MEM_READ_WRITE, 64);
  EXPECT_EQ(a.getInfo<CL_MEM_REFERENCE_COUNT>(), 1u);
  {
    cl::Buffer b = a;  // retain
    EXPECT_EQ(a.getInfo<CL_MEM_REFERENCE_COUNT>(), 2u);
  }  // release
  EXPECT_EQ(a.getInfo<CL_MEM_REFERENCE_COUNT>(), 1u);
}

TEST(ClContext, MissingKernelFileIsAClearError) {
  ClContext& cl = test::shared_gpu().cl();
  try {
    cl.program({"kernels/none.cl"});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("kernels/none.cl"), std::string::npos);
  }
}

}  // namespace
}  // namespace scatter::gpu
