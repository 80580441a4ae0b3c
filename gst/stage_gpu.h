// The GPU side of a pseudo3d stage (GstPseudo3DBase): whether its frames
// run on the GPU, the CUDA context of incoming buffers (adopted or
// refused), CUDA buffer pools for the allocation queries, the map flags of
// device frames, and the "launch, check, wait" block of every GPU frame
// with its one element error. Without CUDA in the build only the questions
// remain, answering "no GPU".
#pragma once

#include <gst/gst.h>

#include "config.h"
#include "gstpseudo3dbase.h"

namespace p3d::gst {

// Whether the GPU runs this element's CUDA-memory frames (processing is
// fixed from start() to stop()).
bool gpu_in_use(GstPseudo3DBase *self);
// The stage's release hook: frees its buffers and pools.
void release_stage(GstPseudo3DBase *self);
// Whether the caps' first structure is memory:CUDAMemory.
bool caps_are_cuda(GstCaps *caps);
// `flags` for mapping a frame of the negotiated caps: with GST_MAP_CUDA on
// the GPU path, so that the stage gets device pointers.
GstMapFlags frame_map_flags(GstPseudo3DBase *self, GstMapFlags flags);

#if HAVE_CUDA
// An upstream CUDA buffer on another context: with cuda-device-id -1 (or
// that context's device) the element switches to it, as nvcodec's filters
// do, and renegotiates so that its pools move too.
void adopt_buffer_context(GstPseudo3DBase *self, GstBuffer *buf);
// FALSE, after one element error, when a GPU-path buffer is not CUDA memory
// of the element's context (kernels must not launch on another device's).
bool check_memory_context(GstPseudo3DBase *self, GstBuffer *buf);
// The same caps with the memory:CUDAMemory structures first (new caps).
GstCaps *cuda_first(GstCaps *caps);
// propose_allocation: a CUDA pool on the element's context for CUDA caps
// that have none yet. FALSE when the pool cannot be configured.
bool propose_cuda_pool(GstPseudo3DBase *self, GstQuery *query);
// decide_allocation for CUDA output caps on a usable GPU (*handled then
// TRUE): downstream's pool is kept only if it is a CUDA pool of this
// element's context, else a new one is made. FALSE when that fails.
bool decide_cuda_pool(GstPseudo3DBase *self, GstQuery *query, bool *handled);

// Posts a GST_ELEMENT_ERROR naming the failed CUDA call; returns GST_FLOW_ERROR.
GstFlowReturn post_cuda_error(GstPseudo3DBase *self, const CudaStatus &st, const char *what);

// The GPU part of one frame, the same for every stage: `launch` queues the
// work on the element's stream (returning the first failure), then the
// stream is waited for, so the buffer leaves with its work done. A failure
// posts one element error naming `what` and the failed call.
template <typename Launch>
GstFlowReturn run_gpu(GstPseudo3DBase *self, const char *what, Launch &&launch) {
  CudaStatus st = launch();
  if (st.ok()) st = self->gpu->sync();
  return st.ok() ? GST_FLOW_OK : post_cuda_error(self, st, what);
}
#endif

}  // namespace p3d::gst
