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
  int width = 0;   // the picture's size
  int height = 0;
  // The plane holds one value a cell of 2^shift x 2^shift pixels
  // (p3d_defs.h DepthGrid): the GPU stages hand on the estimator's block
  // depths and the filter's coarse-grid results as they are, not copied to
  // every pixel. Host planes are always full-size (shift 0): the CPU
  // stages and the meta's scaling read them per pixel.
  int shift = 0;
  bool on_device = false;
  // The picture between letterbox or pillarbox bars (common/bars.h) that
  // the depth was estimated on; outside it the plane holds 0 (on a grid,
  // the cells the rect's last row and column reach belong to the rect).
  // The whole picture unless pseudo3ddepth cropped the bars.
  PixelRect active;
  std::vector<float> host;  // row-major, pitch = width * 4, when !on_device
#if HAVE_CUDA
  DeviceBuffer device;              // pitched, when on_device
  GstCudaContext *context = nullptr;  // owning context (ref held)
#endif
  ~DepthPlane();
  // The stored values: grid_cells(width, shift) x grid_cells(height, shift),
  // the full-size map at shift 0.
  ImageView<float> view();
  DepthGrid<float> grid() { return DepthGrid<float>{view(), width, height, shift}; }
  bool cropped() const { return !active.empty() && active != whole_picture(width, height); }
  PixelRect active_rect() const { return cropped() ? active : whole_picture(width, height); }
  // Sets the active rect and writes 0 to the cells outside it (whose
  // corners lie on cells: sub_grid_fits), on `stream` for a device plane.
  // False when the device refused the write (*error says why).
#if HAVE_CUDA
  bool set_active(PixelRect rect, cudaStream_t stream, std::string *error);
#else
  bool set_active(PixelRect rect, std::nullptr_t stream, std::string *error);
#endif
};

using DepthPlanePtr = std::shared_ptr<DepthPlane>;

// Recycles planes of one size and domain. Planes handed out keep the pool
// state alive, so a plane may outlive the element that made it.
class DepthPlanePool {
 public:
  DepthPlanePool();
  // A plane of a width x height picture holding a value a 2^shift x
  // 2^shift cell (shift > 0 only on the device); on the device of `context`
  // when given (the context must be pushed by the caller), else in host
  // memory. Returns null on allocation failure (*error says why).
#if HAVE_CUDA
  DepthPlanePtr acquire(int width, int height, int shift, GstCudaContext *context, std::string *error);
#else
  DepthPlanePtr acquire(int width, int height, int shift, std::nullptr_t, std::string *error);
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
