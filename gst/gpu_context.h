// The CUDA side of an element, in one place: the GstCudaContext (shared with
// the rest of the pipeline through GstContext), the element's stream, and
// the rules for getting, switching and releasing them. The element base owns one GpuContext; the
// stages never touch a context or a stream directly.
//
// Without CUDA in the build the class is empty and every GPU question
// answers "no GPU".
#pragma once

#include <gst/gst.h>

#include <functional>

#include "config.h"

#if HAVE_CUDA
#include <cuda_runtime_api.h>
#include <gst/cuda/gstcudacontext.h>

#include "cuda_check.h"
#endif

namespace p3d::gst {

#if HAVE_CUDA
class GpuContext {
 public:
  GpuContext() = default;
  ~GpuContext();
  GpuContext(const GpuContext &) = delete;
  GpuContext &operator=(const GpuContext &) = delete;

  // Gets a context for `element` (the pipeline's, a peer's, or a new one on
  // device_id; -1 = any) and a stream on it. Returns false, leaving the
  // element on the CPU, when there is no usable CUDA device; *why says why.
  bool acquire(GstElement *element, int device_id, const char **why);
  // Calls `release_stage` (with the context current, if there is one), then
  // frees the stream and drops the context.
  void release(const std::function<void()> &release_stage);
  // Switches to `other` (the context of an upstream buffer): frees what
  // lives on the old context as release() does and makes a stream on the
  // new one. Returns false (staying without a context) if that fails.
  bool adopt(GstElement *element, GstCudaContext *other, const std::function<void()> &release_stage);

  // Whether a CUDA buffer of context `ctx` should be adopted by an element
  // whose cuda-device-id is device_id: -1 takes any device, else only ctx's own.
  bool should_adopt(GstCudaContext *ctx, int device_id) const;

  // GstElement::set_context and the CONTEXT query, as nvcodec's elements do.
  void handle_set_context(GstElement *element, GstContext *context, int device_id);
  bool handle_context_query(GstElement *element, GstQuery *query);

  bool usable() const { return context_ && stream_; }
  GstCudaContext *context() const { return context_; }
  cudaStream_t stream() const { return stream_; }

  // Waits for the stream (1.22's CUDA memory has no stream tracking, so a
  // buffer may only leave once the work on it is done).
  CudaStatus sync() const;

 private:
  void release_on_context(const std::function<void()> &release_stage);
  bool make_stream(GstElement *element);

  GstCudaContext *context_ = nullptr;
  cudaStream_t stream_ = nullptr;
};

// Makes a context current on this thread for the scope (no-op for null).
class CudaContextScope {
 public:
  explicit CudaContextScope(GstCudaContext *ctx) : pushed_(ctx && gst_cuda_context_push(ctx)) {}
  ~CudaContextScope() {
    if (pushed_) gst_cuda_context_pop(nullptr);
  }
  CudaContextScope(const CudaContextScope &) = delete;
  CudaContextScope &operator=(const CudaContextScope &) = delete;
  bool ok() const { return pushed_; }

 private:
  bool pushed_;
};
#else
class GpuContext {
 public:
  bool usable() const { return false; }
};
#endif

}  // namespace p3d::gst
