// The one place that includes the OpenCL C++ bindings (exceptions on, OpenCL 1.2 API).
#pragma once

#include <CL/opencl.hpp>
