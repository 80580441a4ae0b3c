#include "depth_plane.h"

#include <algorithm>

#include "bars.h"

namespace p3d::gst {

DepthPlane::~DepthPlane() {
#if HAVE_CUDA
  if (context) {
    // Device memory belongs to a non-primary context: free it there.
    if (gst_cuda_context_push(context)) {
      device.release();
      gst_cuda_context_pop(nullptr);
    }
    gst_object_unref(context);
  }
#endif
}

ImageView<float> DepthPlane::view() {
  const int w = grid_cells(width, shift), h = grid_cells(height, shift);
#if HAVE_CUDA
  if (on_device) return ImageView<float>{device.as<float>(), w, h, device.pitch()};
#endif
  return ImageView<float>{host.data(), w, h, static_cast<size_t>(w) * sizeof(float)};
}

#if HAVE_CUDA
bool DepthPlane::set_active(PixelRect rect, cudaStream_t stream, std::string *error) {
#else
bool DepthPlane::set_active(PixelRect rect, std::nullptr_t, std::string *) {
#endif
  active = rect;
  if (!cropped()) return true;
  const ImageView<float> cells = view();
  for (const PixelRect &b : cells_outside(rect, shift, cells.width, cells.height)) {
    if (b.empty()) continue;
#if HAVE_CUDA
    if (on_device) {
      // 0.0f is all-zero bytes.
      const cudaError_t e = cudaMemset2DAsync(cells.row(b.y0) + b.x0, cells.pitch, 0, b.width() * sizeof(float),
                                              b.height(), stream);
      if (e != cudaSuccess) {
        if (error) *error = std::string("cudaMemset2DAsync: ") + cudaGetErrorString(e);
        return false;
      }
      continue;
    }
#endif
    for (int y = b.y0; y < b.y1; ++y) std::fill(cells.row(y) + b.x0, cells.row(y) + b.x1, 0.f);
  }
  return true;
}

DepthPlanePool::DepthPlanePool() : state_(std::make_shared<State>()) {}

void DepthPlanePool::clear() {
  std::lock_guard<std::mutex> g(state_->lock);
  state_->idle.clear();
}

#if HAVE_CUDA
DepthPlanePtr DepthPlanePool::acquire(int width, int height, int shift, GstCudaContext *context, std::string *error) {
#else
DepthPlanePtr DepthPlanePool::acquire(int width, int height, int shift, std::nullptr_t context, std::string *error) {
#endif
  const bool device = context != nullptr;
  if (!device) shift = 0;  // host planes are full-size
  std::unique_ptr<DepthPlane> plane;
  {
    std::lock_guard<std::mutex> g(state_->lock);
    auto &idle = state_->idle;
    for (auto it = idle.begin(); it != idle.end(); ++it) {
      DepthPlane &p = **it;
      bool same = p.width == width && p.height == height && p.shift == shift && p.on_device == device;
#if HAVE_CUDA
      same = same && p.context == context;
#endif
      if (same) {
        plane = std::move(*it);
        idle.erase(it);
        break;
      }
    }
    // Idle planes of another size are of no further use (caps changed).
    if (!plane) idle.clear();
  }
  if (!plane) {
    plane = std::make_unique<DepthPlane>();
    plane->width = width;
    plane->height = height;
    plane->shift = shift;
    plane->on_device = device;
    if (device) {
#if HAVE_CUDA
      plane->context = static_cast<GstCudaContext *>(gst_object_ref(context));
      const CudaStatus st = plane->device.ensure_2d(static_cast<size_t>(grid_cells(width, shift)) * sizeof(float),
                                                    grid_cells(height, shift));
      if (!st.ok()) {
        if (error) *error = st.message();
        return nullptr;
      }
#endif
    } else {
      try {
        plane->host.resize(static_cast<size_t>(width) * height);
      } catch (const std::bad_alloc &) {
        if (error) *error = "out of host memory for a depth plane";
        return nullptr;
      }
    }
  }
  plane->active = whole_picture(width, height);
  // Back into the pool when the last user lets go (if the pool still lives).
  std::weak_ptr<State> weak = state_;
  return DepthPlanePtr(plane.release(), [weak](DepthPlane *p) {
    if (auto st = weak.lock()) {
      std::lock_guard<std::mutex> g(st->lock);
      if (st->idle.size() < 8) {
        st->idle.emplace_back(p);
        return;
      }
    }
    delete p;
  });
}

}  // namespace p3d::gst
