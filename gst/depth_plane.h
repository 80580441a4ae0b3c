// The depth map that rides along with a frame: one float plane (0 = far,
// 1 = near) in host memory or in device memory of a GstCudaContext.
// GstCudaMemory of 1.22 cannot hold single-channel formats, so the plane is
// our own allocation; a pool recycles planes so a stream allocates nothing
// per frame.
#pragma once

#include <gst/gst.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "config.h"
#include "p3d_defs.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudacontext.h>

#include "device_buffer.h"
#endif

namespace p3d::gst {

struct DepthPlane {
  int width = 0;
  int height = 0;
  bool on_device = false;
  std::vector<float> host;  // row-major, pitch = width * 4, when !on_device
#if HAVE_CUDA
  DeviceBuffer device;              // pitched, when on_device
  GstCudaContext *context = nullptr;  // owning context (ref held)
#endif
  ~DepthPlane();
  ImageView<float> view();
};

using DepthPlanePtr = std::shared_ptr<DepthPlane>;

// Recycles planes of one size and domain. Planes handed out keep the pool
// state alive, so a plane may outlive the element that made it.
class DepthPlanePool {
 public:
  DepthPlanePool();
  // A plane of width x height; on the device of `context` when given (the
  // context must be pushed by the caller), else in host memory. Returns
  // null on allocation failure (*error says why).
#if HAVE_CUDA
  DepthPlanePtr acquire(int width, int height, GstCudaContext *context, std::string *error);
#else
  DepthPlanePtr acquire(int width, int height, std::nullptr_t, std::string *error);
#endif
  void clear();  // drop the idle planes

 private:
  struct State {
    std::mutex lock;
    std::vector<std::unique_ptr<DepthPlane>> idle;
  };
  std::shared_ptr<State> state_;
};

}  // namespace p3d::gst
