#include "gpu_context.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudaloader.h>
#include <gst/cuda/gstcudautils.h>

GST_DEBUG_CATEGORY_STATIC(pseudo3d_gpu_debug);
#define GST_CAT_DEFAULT pseudo3d_gpu_debug

namespace p3d::gst {

static void init_debug() {
  static gsize once = 0;
  if (g_once_init_enter(&once)) {
    GST_DEBUG_CATEGORY_INIT(pseudo3d_gpu_debug, "pseudo3dgpu", 0, "pseudo3d CUDA context and stream");
    g_once_init_leave(&once, 1);
  }
}

GpuContext::~GpuContext() { release([] {}); }

bool GpuContext::make_stream(GstElement *element) {
  CudaContextScope scope(context_);
  const cudaError_t err = scope.ok() ? detail::checked(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking))
                                     : cudaErrorDeviceUninitialized;
  if (err == cudaSuccess) return true;
  GST_WARNING_OBJECT(element, "cudaStreamCreateWithFlags failed: %s", cudaGetErrorName(err));
  stream_ = nullptr;
  return false;
}

bool GpuContext::acquire(GstElement *element, int device_id, const char **why) {
  init_debug();
  if (usable()) return true;
  if (!gst_cuda_load_library()) {
    *why = "the CUDA driver library is not available";
    return false;
  }
  if (!context_ && !gst_cuda_ensure_element_context(element, device_id, &context_)) {
    *why = "no usable CUDA device";
    return false;
  }
  if (!make_stream(element)) {
    gst_clear_object(&context_);
    *why = "no CUDA stream could be created";
    return false;
  }
  return true;
}

void GpuContext::release_on_context(const std::function<void()> &release_stage) {
  if (!context_) {
    release_stage();  // host resources only
    return;
  }
  // Device memory and streams of a non-primary context are freed while it is current.
  CudaContextScope scope(context_);
  if (!scope.ok()) {
    GST_WARNING("could not make the CUDA context current to free its memory");
    return;
  }
  release_stage();
  if (stream_) {
    const cudaError_t err = cudaStreamDestroy(stream_);
    if (err != cudaSuccess) GST_WARNING("cudaStreamDestroy failed: %s", cudaGetErrorName(err));
  }
}

void GpuContext::release(const std::function<void()> &release_stage) {
  release_on_context(release_stage);
  stream_ = nullptr;
  gst_clear_object(&context_);
}

bool GpuContext::should_adopt(GstCudaContext *ctx, int device_id) const {
  if (!ctx || ctx == context_) return false;
  if (device_id < 0) return true;
  guint ctx_device = 0;
  g_object_get(ctx, "cuda-device-id", &ctx_device, NULL);
  return ctx_device == static_cast<guint>(device_id);
}

bool GpuContext::adopt(GstElement *element, GstCudaContext *other, const std::function<void()> &release_stage) {
  init_debug();
  GST_INFO_OBJECT(element, "switching to the CUDA context of the incoming buffers (%" GST_PTR_FORMAT " -> %" GST_PTR_FORMAT
                           ")",
                  context_, other);
  release(release_stage);
  context_ = static_cast<GstCudaContext *>(gst_object_ref(other));
  if (make_stream(element)) return true;
  gst_clear_object(&context_);
  return false;
}

void GpuContext::handle_set_context(GstElement *element, GstContext *context, int device_id) {
  if (gst_cuda_load_library()) gst_cuda_handle_set_context(element, context, device_id, &context_);
}

bool GpuContext::handle_context_query(GstElement *element, GstQuery *query) {
  return context_ && gst_cuda_handle_context_query(element, query, context_);
}

CudaStatus GpuContext::sync() const {
  P3D_CUDA_TRY(cudaStreamSynchronize(stream_));
  return {};
}

}  // namespace p3d::gst
#endif
