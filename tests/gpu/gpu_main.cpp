// GPU suite entry: skipped (exit 77, meson's convention) without a usable
// CUDA device, so CI on a machine without a GPU reports it as skipped.
#include <cstdio>

#include <gtest/gtest.h>

#include "device_buffer.h"

int main(int argc, char **argv) {
  ::testing::InitGoogleTest(&argc, argv);
  if (!p3d::cuda_device_present()) {
    std::fprintf(stderr, "no usable CUDA device: GPU tests skipped\n");
    return 77;
  }
  return RUN_ALL_TESTS();
}
