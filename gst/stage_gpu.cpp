#include "stage_gpu.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudabufferpool.h>
#include <gst/cuda/gstcudamemory.h>
#endif

GST_DEBUG_CATEGORY_EXTERN(gst_pseudo3d_base_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_base_debug

namespace p3d::gst {

bool gpu_in_use(GstPseudo3DBase *self) {
  return self->processing != GST_PSEUDO3D_PROCESSING_CPU && self->gpu->usable();
}

void release_stage(GstPseudo3DBase *self) {
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  if (klass->release) klass->release(self);
}

bool caps_are_cuda(GstCaps *caps) {
#if HAVE_CUDA
  GstCapsFeatures *features = caps && gst_caps_get_size(caps) > 0 ? gst_caps_get_features(caps, 0) : nullptr;
  return features && gst_caps_features_contains(features, GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY);
#else
  (void)caps;
  return false;
#endif
}

GstMapFlags frame_map_flags(GstPseudo3DBase *self, GstMapFlags flags) {
#if HAVE_CUDA
  if (gst_pseudo3d_base_path(self) == GST_PSEUDO3D_PATH_GPU) return (GstMapFlags)(flags | GST_MAP_CUDA);
#else
  (void)self;
#endif
  return flags;
}

#if HAVE_CUDA
GstFlowReturn post_cuda_error(GstPseudo3DBase *self, const CudaStatus &st, const char *what) {
  GST_ELEMENT_ERROR(self, RESOURCE, FAILED, ("CUDA failure while %s: %s", what, cudaGetErrorName(st.code)),
                    ("%s", st.message().c_str()));
  return GST_FLOW_ERROR;
}

// Runs before GstBaseTransform checks for renegotiation, so the switch is
// complete for this frame.
void adopt_buffer_context(GstPseudo3DBase *self, GstBuffer *buf) {
  if (gst_pseudo3d_base_path(self) != GST_PSEUDO3D_PATH_GPU || gst_buffer_n_memory(buf) == 0) return;
  GstMemory *mem = gst_buffer_peek_memory(buf, 0);
  if (!gst_is_cuda_memory(mem)) return;
  GstCudaContext *ctx = GST_CUDA_MEMORY_CAST(mem)->context;
  if (!self->gpu->should_adopt(ctx, self->device_id)) return;
  if (!self->gpu->adopt(GST_ELEMENT(self), ctx, [self] { release_stage(self); })) {
    GST_ELEMENT_WARNING(self, RESOURCE, FAILED, ("Could not switch to the CUDA context of the incoming frames"),
                        ("processing on the CPU from now on"));
  }
  gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));
}

bool check_memory_context(GstPseudo3DBase *self, GstBuffer *buf) {
  if (gst_pseudo3d_base_path(self) != GST_PSEUDO3D_PATH_GPU) return true;
  for (guint i = 0; i < gst_buffer_n_memory(buf); ++i) {
    GstMemory *mem = gst_buffer_peek_memory(buf, i);
    if (!gst_is_cuda_memory(mem) || GST_CUDA_MEMORY_CAST(mem)->context != self->gpu->context()) {
      GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Input buffer is not CUDA memory of this element's CUDA context"),
                        ("cuda-device-id is %d; set it to -1 or to the upstream element's device, or insert "
                         "cudadownload ! cudaupload",
                         self->device_id));
      return false;
    }
  }
  return true;
}

// Peers fixate on the first structure, and a caps query's filter (cudaupload
// offers system memory first) would otherwise decide the order.
GstCaps *cuda_first(GstCaps *caps) {
  GstCaps *cuda = gst_caps_new_empty(), *rest = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    GstCapsFeatures *f = gst_caps_get_features(caps, i);
    const bool is_cuda = f && gst_caps_features_contains(f, GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY);
    GstCaps *to = is_cuda ? cuda : rest;
    to = gst_caps_merge_structure_full(to, gst_structure_copy(gst_caps_get_structure(caps, i)),
                                       f ? gst_caps_features_copy(f) : nullptr);
    if (is_cuda)
      cuda = to;
    else
      rest = to;
  }
  return gst_caps_merge(cuda, rest);
}

static GstBufferPool *new_cuda_pool(GstPseudo3DBase *self, GstCaps *caps, guint *size, guint min, guint max) {
  GstVideoInfo info;
  if (!gst_video_info_from_caps(&info, caps)) return nullptr;
  GstBufferPool *pool = gst_cuda_buffer_pool_new(self->gpu->context());
  GstStructure *config = gst_buffer_pool_get_config(pool);
  gst_buffer_pool_config_add_option(config, GST_BUFFER_POOL_OPTION_VIDEO_META);
  gst_buffer_pool_config_set_params(config, caps, GST_VIDEO_INFO_SIZE(&info), min, max);
  if (!gst_buffer_pool_set_config(pool, config)) {
    GST_ERROR_OBJECT(self, "CUDA buffer pool rejected its configuration");
    gst_object_unref(pool);
    return nullptr;
  }
  // The pool rewrites the size (pitch alignment): read it back.
  config = gst_buffer_pool_get_config(pool);
  gst_buffer_pool_config_get_params(config, nullptr, size, nullptr, nullptr);
  gst_structure_free(config);
  return pool;
}

bool propose_cuda_pool(GstPseudo3DBase *self, GstQuery *query) {
  GstCaps *caps = nullptr;
  gst_query_parse_allocation(query, &caps, nullptr);
  if (!caps_are_cuda(caps) || !self->gpu->usable() || gst_query_get_n_allocation_pools(query) > 0) return true;
  guint size = 0;
  GstBufferPool *pool = new_cuda_pool(self, caps, &size, 0, 0);
  if (!pool) return false;
  gst_query_add_allocation_pool(query, pool, size, 0, 0);
  gst_object_unref(pool);
  return true;
}

bool decide_cuda_pool(GstPseudo3DBase *self, GstQuery *query, bool *handled) {
  GstCaps *outcaps = nullptr;
  gst_query_parse_allocation(query, &outcaps, nullptr);
  *handled = self->gpu->usable() && caps_are_cuda(outcaps);
  if (!*handled) return true;
  GstBufferPool *pool = nullptr;
  guint size = 0, min = 0, max = 0;
  const bool update = gst_query_get_n_allocation_pools(query) > 0;
  if (update) {
    gst_query_parse_nth_allocation_pool(query, 0, &pool, &size, &min, &max);
    // Only a CUDA pool on our own context will do: never launch on memory of another context.
    if (pool && (!GST_IS_CUDA_BUFFER_POOL(pool) || GST_CUDA_BUFFER_POOL_CAST(pool)->context != self->gpu->context()))
      gst_clear_object(&pool);
  }
  if (!pool) {
    pool = new_cuda_pool(self, outcaps, &size, min, max);
    if (!pool) return false;
  }
  if (update)
    gst_query_set_nth_allocation_pool(query, 0, pool, size, min, max);
  else
    gst_query_add_allocation_pool(query, pool, size, min, max);
  gst_object_unref(pool);
  return true;
}
#endif

}  // namespace p3d::gst
