// The test hook of the fault-injection test (tests/gpu/test_gpu_elements.cpp):
// a C symbol the test looks up in the loaded plugin module, arming
// p3d::cuda_fault_inject_after() inside the plugin (which links its own copy
// of the CUDA code). Does nothing in a build without CUDA, and is compiled
// into the plugin only when the test suites are built (gst/meson.build).
#include <gmodule.h>

#include "config.h"

#if HAVE_CUDA
#include "cuda_check.h"
#endif

extern "C" G_MODULE_EXPORT void pseudo3d_test_inject_cuda_fault(int after_calls);

void pseudo3d_test_inject_cuda_fault(int after_calls) {
#if HAVE_CUDA
  p3d::cuda_fault_inject_after(after_calls);
#else
  (void)after_calls;
#endif
}
