#include "gstpseudo3dbase.h"

#include <exception>
#include <new>

#include "depth_meta.h"
#include "video_util.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudabufferpool.h>
#include <gst/cuda/gstcudaloader.h>
#include <gst/cuda/gstcudamemory.h>
#include <gst/cuda/gstcudautils.h>
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_base_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_base_debug

enum { PROP_0, PROP_DEVICE_ID, PROP_PROCESSING };
#define DEFAULT_DEVICE_ID (-1)
#define DEFAULT_PROCESSING GST_PSEUDO3D_PROCESSING_AUTO

#define gst_pseudo3d_base_parent_class parent_class
G_DEFINE_ABSTRACT_TYPE_WITH_CODE(GstPseudo3DBase, gst_pseudo3d_base, GST_TYPE_BASE_TRANSFORM,
                                 GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_base_debug, "pseudo3dbase", 0,
                                                         "pseudo3d base transform"))

static void gst_pseudo3d_base_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(object);
  switch (prop_id) {
    case PROP_DEVICE_ID:
      GST_OBJECT_LOCK(self);
      self->device_id = g_value_get_int(value);
      GST_OBJECT_UNLOCK(self);
      break;
    case PROP_PROCESSING:
      GST_OBJECT_LOCK(self);
      self->processing = static_cast<GstPseudo3DProcessing>(g_value_get_enum(value));
      GST_OBJECT_UNLOCK(self);
      break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
}

static void gst_pseudo3d_base_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(object);
  switch (prop_id) {
    case PROP_DEVICE_ID: g_value_set_int(value, self->device_id); break;
    case PROP_PROCESSING: g_value_set_enum(value, self->processing); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
}

GstPseudo3DPath gst_pseudo3d_base_path(GstPseudo3DBase *self) {
#if HAVE_CUDA
  if (self->context && self->processing != GST_PSEUDO3D_PROCESSING_CPU)
    return self->cuda_caps ? GST_PSEUDO3D_PATH_GPU : GST_PSEUDO3D_PATH_STAGED;
#else
  (void)self;
#endif
  return GST_PSEUDO3D_PATH_CPU;
}

#if HAVE_CUDA
GstFlowReturn gst_pseudo3d_base_cuda_error(GstPseudo3DBase *self, const p3d::CudaStatus &st, const char *what) {
  GST_ELEMENT_ERROR(self, RESOURCE, FAILED, ("CUDA failure while %s: %s", what, cudaGetErrorName(st.code)),
                    ("%s", st.message().c_str()));
  return GST_FLOW_ERROR;
}

GstFlowReturn gst_pseudo3d_base_sync(GstPseudo3DBase *self) {
  const cudaError_t err = cudaStreamSynchronize(self->stream);
  if (err != cudaSuccess)
    return gst_pseudo3d_base_cuda_error(self, p3d::CudaStatus{err, "cudaStreamSynchronize(stream)", __FILE__, __LINE__},
                                        "waiting for the GPU");
  return GST_FLOW_OK;
}

namespace p3d::gst {

CudaStatus device_frame(GstPseudo3DBase *self, GstPseudo3DPath path, GpuStaging::Slot slot, const FrameView &frame,
                        bool read, FrameView *dev) {
  if (path == GST_PSEUDO3D_PATH_GPU) {
    *dev = frame;
    return {};
  }
  return read ? self->staging->upload(slot, frame, dev, self->stream) : self->staging->allocate(slot, frame, dev);
}

CudaStatus device_depth(GstPseudo3DBase *self, GstPseudo3DPath path, GpuStaging::Slot slot, ImageView<float> depth,
                        bool read, ImageView<float> *dev) {
  if (path == GST_PSEUDO3D_PATH_GPU) {
    *dev = depth;
    return {};
  }
  return read ? self->staging->upload_depth(slot, as_const(depth), dev, self->stream)
              : self->staging->allocate_depth(slot, depth.width, depth.height, dev);
}

CudaStatus frame_to_host(GstPseudo3DBase *self, GstPseudo3DPath path, const FrameView &dev, const FrameView &host) {
  if (path != GST_PSEUDO3D_PATH_STAGED) return {};
  return self->staging->download(dev, host, self->stream);
}

CudaStatus depth_to_host(GstPseudo3DBase *self, GstPseudo3DPath path, ImageView<const float> dev,
                         ImageView<float> host) {
  if (path != GST_PSEUDO3D_PATH_STAGED) return {};
  return self->staging->download_depth(dev, host, self->stream);
}

}  // namespace p3d::gst

static void release_cuda(GstPseudo3DBase *self) {
  if (self->context) {
    // Device memory of this context is freed while it is current.
    CudaContextScope scope(self->context);
    GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
    if (scope.ok()) {
      if (klass->release_gpu) klass->release_gpu(self);
      delete self->staging;
      self->staging = nullptr;
    }
  }
  if (self->context && self->stream) {
    CudaContextScope scope(self->context);
    if (scope.ok()) {
      const cudaError_t err = cudaStreamDestroy(self->stream);
      if (err != cudaSuccess) GST_WARNING_OBJECT(self, "cudaStreamDestroy failed: %s", cudaGetErrorName(err));
    }
  }
  self->stream = nullptr;
  gst_clear_object(&self->context);
}

// A context and a stream, or none (then the CPU path runs, said once).
static void acquire_cuda(GstPseudo3DBase *self) {
  if (self->context && self->stream) return;
  if (!gst_cuda_load_library()) {
    if (!self->cpu_notice_logged)
      GST_INFO_OBJECT(self, "CUDA driver library not available: processing on the CPU");
    self->cpu_notice_logged = TRUE;
    return;
  }
  if (!gst_cuda_ensure_element_context(GST_ELEMENT(self), self->device_id, &self->context)) {
    if (!self->cpu_notice_logged)
      GST_INFO_OBJECT(self, "no usable CUDA device (cuda-device-id %d): processing on the CPU", self->device_id);
    self->cpu_notice_logged = TRUE;
    return;
  }
  CudaContextScope scope(self->context);
  cudaError_t err = scope.ok() ? cudaStreamCreateWithFlags(&self->stream, cudaStreamNonBlocking) : cudaErrorDeviceUninitialized;
  if (err != cudaSuccess) {
    GST_WARNING_OBJECT(self, "cudaStreamCreateWithFlags failed (%s): processing on the CPU", cudaGetErrorName(err));
    self->stream = nullptr;
    gst_clear_object(&self->context);
    return;
  }
  self->staging = new p3d::gst::GpuStaging();
}

static void gst_pseudo3d_base_set_context(GstElement *element, GstContext *context) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(element);
  if (gst_cuda_load_library()) gst_cuda_handle_set_context(element, context, self->device_id, &self->context);
  GST_ELEMENT_CLASS(parent_class)->set_context(element, context);
}

static gboolean gst_pseudo3d_base_query(GstBaseTransform *trans, GstPadDirection direction, GstQuery *query) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  if (GST_QUERY_TYPE(query) == GST_QUERY_CONTEXT && self->context &&
      gst_cuda_handle_context_query(GST_ELEMENT(self), query, self->context))
    return TRUE;
  return GST_BASE_TRANSFORM_CLASS(parent_class)->query(trans, direction, query);
}
#endif

static gboolean gst_pseudo3d_base_start(GstBaseTransform *trans) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
#if HAVE_CUDA
  if (self->processing != GST_PSEUDO3D_PROCESSING_CPU) acquire_cuda(self);
  const gboolean have_gpu = self->context != nullptr;
#else
  if (!self->cpu_notice_logged) GST_INFO_OBJECT(self, "built without CUDA: processing on the CPU");
  self->cpu_notice_logged = TRUE;
  const gboolean have_gpu = FALSE;
#endif
  if (self->processing == GST_PSEUDO3D_PROCESSING_GPU && !have_gpu) {
    GST_ELEMENT_ERROR(self, RESOURCE, NOT_FOUND, ("processing=gpu but no usable CUDA device"),
                      ("cuda-device-id %d; use processing=auto to fall back to the CPU", self->device_id));
    return FALSE;
  }
  return TRUE;
}

static gboolean gst_pseudo3d_base_stop(GstBaseTransform *trans) {
#if HAVE_CUDA
  release_cuda(GST_PSEUDO3D_BASE(trans));
#else
  (void)trans;
#endif
  return TRUE;
}

/* ---- caps ---- */

// value * num / den for an int, an int range or a list of them.
static void scale_dimension(const GValue *in, GValue *out, gint num, gint den) {
  auto scale = [&](gint v) -> gint {
    const gint64 r = (gint64)v * num / den;
    return (gint)CLAMP(r, 1, G_MAXINT);
  };
  if (G_VALUE_HOLDS_INT(in)) {
    g_value_init(out, G_TYPE_INT);
    g_value_set_int(out, scale(g_value_get_int(in)));
  } else if (GST_VALUE_HOLDS_INT_RANGE(in)) {
    g_value_init(out, GST_TYPE_INT_RANGE);
    gint lo = scale(gst_value_get_int_range_min(in)), hi = scale(gst_value_get_int_range_max(in));
    if (lo >= hi) hi = lo + 1;
    gst_value_set_int_range(out, lo, hi);
  } else if (GST_VALUE_HOLDS_LIST(in)) {
    g_value_init(out, GST_TYPE_LIST);
    for (guint i = 0; i < gst_value_list_get_size(in); ++i) {
      GValue item = G_VALUE_INIT;
      scale_dimension(gst_value_list_get_value(in, i), &item, num, den);
      gst_value_list_append_and_take_value(out, &item);
    }
  } else {
    g_value_init(out, G_VALUE_TYPE(in));
    g_value_copy(in, out);
  }
}

static void set_formats(GstStructure *s, const gchar *formats) {
  // formats is "{ A, B }": parse it through a throwaway caps string.
  gchar *str = g_strdup_printf("x, format=(string)%s", formats);
  GstStructure *tmp = gst_structure_from_string(str, NULL);
  g_free(str);
  gst_structure_set_value(s, "format", gst_structure_get_value(tmp, "format"));
  gst_structure_free(tmp);
  // Colorimetry belongs to the format family: let it be re-derived.
  gst_structure_remove_fields(s, "colorimetry", "chroma-site", NULL);
}

static GstCaps *gst_pseudo3d_base_transform_caps(GstBaseTransform *trans, GstPadDirection direction, GstCaps *caps,
                                                 GstCaps *filter) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  gint wn = 1, wd = 1, hn = 1, hd = 1;
  if (klass->get_size_ratio) klass->get_size_ratio(self, &wn, &wd, &hn, &hd);
  const gboolean to_src = direction == GST_PAD_SINK;
  if (!to_src) {
    std::swap(wn, wd);
    std::swap(hn, hd);
  }
  const gchar *formats = to_src ? klass->src_formats : klass->sink_formats;

  GstCaps *out = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    GstStructure *s = gst_structure_copy(gst_caps_get_structure(caps, i));
    GstCapsFeatures *f = gst_caps_features_copy(gst_caps_get_features(caps, i));
    if (wn != wd || hn != hd) {
      const char *dims[2] = {"width", "height"};
      const gint nums[2] = {wn, hn}, dens[2] = {wd, hd};
      for (int d = 0; d < 2; ++d) {
        const GValue *v = gst_structure_get_value(s, dims[d]);
        if (!v) continue;
        GValue scaled = G_VALUE_INIT;
        scale_dimension(v, &scaled, nums[d], dens[d]);
        gst_structure_take_value(s, dims[d], &scaled);
      }
    }
    if (formats) set_formats(s, formats);
    if (klass->set_src_multiview) {
      gst_structure_remove_fields(s, "multiview-mode", "multiview-flags", "views", NULL);
      if (to_src)
        klass->set_src_multiview(self, s);
      else  // the src PAR may be folded by half-aspect: it constrains nothing upstream
        gst_structure_remove_field(s, "pixel-aspect-ratio");
    }
    out = gst_caps_merge_structure_full(out, s, f);
  }
  if (filter) {
    GstCaps *tmp = gst_caps_intersect_full(filter, out, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(out);
    out = tmp;
  }
  GST_DEBUG_OBJECT(self, "%s caps %" GST_PTR_FORMAT " -> %" GST_PTR_FORMAT, to_src ? "sink" : "src", caps, out);
  return out;
}

static gboolean gst_pseudo3d_base_set_caps(GstBaseTransform *trans, GstCaps *incaps, GstCaps *outcaps) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstVideoInfo in, out;
  if (!gst_video_info_from_caps(&in, incaps) || !gst_video_info_from_caps(&out, outcaps)) {
    GST_ERROR_OBJECT(self, "caps are not video caps: %" GST_PTR_FORMAT " / %" GST_PTR_FORMAT, incaps, outcaps);
    return FALSE;
  }
  self->in_info = in;
  self->out_info = out;
  self->cuda_caps = FALSE;
#if HAVE_CUDA
  GstCapsFeatures *features = gst_caps_get_features(incaps, 0);
  self->cuda_caps = features && gst_caps_features_contains(features, GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY);
  if (self->cuda_caps) acquire_cuda(self);
  if (self->cuda_caps && gst_pseudo3d_base_path(self) == GST_PSEUDO3D_PATH_CPU)
    GST_WARNING_OBJECT(self, "CUDA memory negotiated but processing on the CPU through mapped memory (slow)");
#endif
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  if (klass->set_info && !klass->set_info(self, incaps, &self->in_info, outcaps, &self->out_info)) return FALSE;
  static const char *const path_names[] = {"CPU", "GPU", "GPU (staged through system memory)"};
  GST_INFO_OBJECT(self, "negotiated %dx%d -> %dx%d, processing on the %s", in.width, in.height, out.width, out.height,
                  path_names[gst_pseudo3d_base_path(self)]);
  return TRUE;
}

// An output buffer holds one frame of the output caps, whatever padding the
// input buffer carries (decoders often pad).
static gboolean gst_pseudo3d_base_transform_size(GstBaseTransform *, GstPadDirection, GstCaps *, gsize,
                                                 GstCaps *othercaps, gsize *othersize) {
  GstVideoInfo info;
  if (!gst_video_info_from_caps(&info, othercaps)) return FALSE;
  *othersize = GST_VIDEO_INFO_SIZE(&info);
  return TRUE;
}

/* ---- allocation (CUDA memory: pools on our context, as cudaconvertscale does) ---- */

#if HAVE_CUDA
static GstBufferPool *new_cuda_pool(GstPseudo3DBase *self, GstCaps *caps, guint *size, guint min, guint max) {
  GstVideoInfo info;
  if (!gst_video_info_from_caps(&info, caps)) return nullptr;
  GstBufferPool *pool = gst_cuda_buffer_pool_new(self->context);
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
#endif

static gboolean gst_pseudo3d_base_propose_allocation(GstBaseTransform *trans, GstQuery *decide_query,
                                                     GstQuery *query) {
  if (!GST_BASE_TRANSFORM_CLASS(parent_class)->propose_allocation(trans, decide_query, query)) return FALSE;
  if (decide_query == nullptr) return TRUE; /* passthrough: downstream answered */
  gst_query_add_allocation_meta(query, GST_VIDEO_META_API_TYPE, nullptr);
#if HAVE_CUDA
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstCaps *caps = nullptr;
  gst_query_parse_allocation(query, &caps, nullptr);
  if (!caps || !self->context || gst_query_get_n_allocation_pools(query) > 0) return TRUE;
  GstCapsFeatures *features = gst_caps_get_features(caps, 0);
  if (!features || !gst_caps_features_contains(features, GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY)) return TRUE;
  guint size = 0;
  GstBufferPool *pool = new_cuda_pool(self, caps, &size, 0, 0);
  if (!pool) return FALSE;
  gst_query_add_allocation_pool(query, pool, size, 0, 0);
  gst_object_unref(pool);
#endif
  return TRUE;
}

static gboolean gst_pseudo3d_base_decide_allocation(GstBaseTransform *trans, GstQuery *query) {
#if HAVE_CUDA
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstCaps *outcaps = nullptr;
  gst_query_parse_allocation(query, &outcaps, nullptr);
  GstCapsFeatures *features = outcaps ? gst_caps_get_features(outcaps, 0) : nullptr;
  if (self->context && features && gst_caps_features_contains(features, GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY)) {
    GstBufferPool *pool = nullptr;
    guint size = 0, min = 0, max = 0;
    const gboolean update = gst_query_get_n_allocation_pools(query) > 0;
    if (update) {
      gst_query_parse_nth_allocation_pool(query, 0, &pool, &size, &min, &max);
      // Only a CUDA pool on our own context will do: never launch on memory of another context.
      if (pool && (!GST_IS_CUDA_BUFFER_POOL(pool) || GST_CUDA_BUFFER_POOL_CAST(pool)->context != self->context))
        gst_clear_object(&pool);
    }
    if (!pool) {
      pool = new_cuda_pool(self, outcaps, &size, min, max);
      if (!pool) return FALSE;
    }
    if (update)
      gst_query_set_nth_allocation_pool(query, 0, pool, size, min, max);
    else
      gst_query_add_allocation_pool(query, pool, size, min, max);
    gst_object_unref(pool);
  }
#endif
  return GST_BASE_TRANSFORM_CLASS(parent_class)->decide_allocation(trans, query);
}

// The depth map describes the input geometry: keep it only where the stage
// keeps the frame size.
static gboolean gst_pseudo3d_base_transform_meta(GstBaseTransform *trans, GstBuffer *outbuf, GstMeta *meta,
                                                 GstBuffer *inbuf) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  if (meta->info->api == PSEUDO3D_DEPTH_META_API_TYPE)
    return GST_VIDEO_INFO_WIDTH(&self->in_info) == GST_VIDEO_INFO_WIDTH(&self->out_info) &&
           GST_VIDEO_INFO_HEIGHT(&self->in_info) == GST_VIDEO_INFO_HEIGHT(&self->out_info);
  return GST_BASE_TRANSFORM_CLASS(parent_class)->transform_meta(trans, outbuf, meta, inbuf);
}

/* ---- processing ---- */

static GstMapFlags map_flags(GstPseudo3DBase *self, GstMapFlags base) {
#if HAVE_CUDA
  if (gst_pseudo3d_base_path(self) == GST_PSEUDO3D_PATH_GPU) return (GstMapFlags)(base | GST_MAP_CUDA);
#else
  (void)self;
#endif
  return base;
}

#if HAVE_CUDA
// Memory of another context (another device) must not be launched on.
static gboolean check_memory_context(GstPseudo3DBase *self, GstBuffer *buf) {
  if (gst_pseudo3d_base_path(self) != GST_PSEUDO3D_PATH_GPU) return TRUE;
  for (guint i = 0; i < gst_buffer_n_memory(buf); ++i) {
    GstMemory *mem = gst_buffer_peek_memory(buf, i);
    if (!gst_is_cuda_memory(mem) || reinterpret_cast<GstCudaMemory *>(mem)->context != self->context) {
      GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Input buffer is not CUDA memory of this element's CUDA context"),
                        ("set cuda-device-id to the upstream element's device, or insert cudadownload ! cudaupload"));
      return FALSE;
    }
  }
  return TRUE;
}
#endif

// The CPU references report bad arguments and allocation failures by
// exceptions; none may unwind through GStreamer's C frames.
template <typename F>
static GstFlowReturn guarded(GstPseudo3DBase *self, F &&f) {
  try {
    return f();
  } catch (const std::bad_alloc &) {
    GST_ELEMENT_ERROR(self, RESOURCE, NO_SPACE_LEFT, ("Out of memory while processing a frame"), (nullptr));
  } catch (const std::exception &e) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Processing a frame failed"), ("%s", e.what()));
  }
  return GST_FLOW_ERROR;
}

static GstFlowReturn gst_pseudo3d_base_transform(GstBaseTransform *trans, GstBuffer *inbuf, GstBuffer *outbuf) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  const GstPseudo3DPath path = gst_pseudo3d_base_path(self);
#if HAVE_CUDA
  if (!check_memory_context(self, inbuf)) return GST_FLOW_ERROR;
#endif
  GstVideoFrame in, out;
  // NO_REF: stages attach metas to outbuf, which a held ref would make unwritable.
  const auto no_ref = static_cast<GstMapFlags>(GST_VIDEO_FRAME_MAP_FLAG_NO_REF);
  if (!gst_video_frame_map(&in, &self->in_info, inbuf, (GstMapFlags)(map_flags(self, GST_MAP_READ) | no_ref))) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Could not map the input frame"), (nullptr));
    return GST_FLOW_ERROR;
  }
  if (!gst_video_frame_map(&out, &self->out_info, outbuf, (GstMapFlags)(map_flags(self, GST_MAP_WRITE) | no_ref))) {
    gst_video_frame_unmap(&in);
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Could not map the output frame"), (nullptr));
    return GST_FLOW_ERROR;
  }
  GstFlowReturn ret;
#if HAVE_CUDA
  CudaContextScope scope(path != GST_PSEUDO3D_PATH_CPU ? self->context : nullptr);
#endif
  ret = guarded(self, [&] { return klass->process(self, path, inbuf, &in, &out); });
  gst_video_frame_unmap(&out);
  gst_video_frame_unmap(&in);
  return ret;
}

static GstFlowReturn gst_pseudo3d_base_transform_ip(GstBaseTransform *trans, GstBuffer *buf) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  const GstPseudo3DPath path = gst_pseudo3d_base_path(self);
#if HAVE_CUDA
  if (!check_memory_context(self, buf)) return GST_FLOW_ERROR;
#endif
  GstVideoFrame frame;
  // NO_REF: a mapped frame holding a ref would make buf unwritable, and the
  // stage must attach its meta to buf.
  if (!gst_video_frame_map(&frame, &self->in_info, buf,
                           (GstMapFlags)(map_flags(self, GST_MAP_READ) | GST_VIDEO_FRAME_MAP_FLAG_NO_REF))) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Could not map the frame"), (nullptr));
    return GST_FLOW_ERROR;
  }
#if HAVE_CUDA
  CudaContextScope scope(path != GST_PSEUDO3D_PATH_CPU ? self->context : nullptr);
#endif
  const GstFlowReturn ret = guarded(self, [&] { return klass->process_ip(self, path, buf, &frame); });
  gst_video_frame_unmap(&frame);
  return ret;
}

static void gst_pseudo3d_base_class_init(GstPseudo3DBaseClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass *trans_class = GST_BASE_TRANSFORM_CLASS(klass);

  gobject_class->set_property = gst_pseudo3d_base_set_property;
  gobject_class->get_property = gst_pseudo3d_base_get_property;

  /**
   * GstPseudo3DBase:cuda-device-id:
   *
   * CUDA device to run on when the caps are memory:CUDAMemory; -1 takes the
   * pipeline's context or the first device. Without a usable device the
   * element processes on the CPU.
   */
  /**
   * GstPseudo3DBase:processing:
   *
   * auto: the GPU when a CUDA device is usable (memory:CUDAMemory caps in
   * place; system-memory caps through an upload and a download per frame),
   * else the CPU. cpu: always the CPU. gpu: fail to start without a GPU.
   */
  g_object_class_install_property(
      gobject_class, PROP_PROCESSING,
      g_param_spec_enum("processing", "Processing",
                        "Where frames are processed: auto = GPU when a CUDA device is usable (system-memory frames "
                        "are uploaded and downloaded per frame), else CPU; cpu; gpu = an error without a GPU",
                        GST_TYPE_PSEUDO3D_PROCESSING, DEFAULT_PROCESSING,
                        (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_READY)));
  g_object_class_install_property(
      gobject_class, PROP_DEVICE_ID,
      g_param_spec_int("cuda-device-id", "CUDA device id",
                       "CUDA device to use (-1 = the pipeline's shared context, else any device); "
                       "read when the element starts",
                       -1, G_MAXINT, DEFAULT_DEVICE_ID,
                       (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_READY)));

#if HAVE_CUDA
  element_class->set_context = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_set_context);
  trans_class->query = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_query);
#else
  (void)element_class;
#endif
  trans_class->start = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_stop);
  trans_class->transform_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform_caps);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_set_caps);
  trans_class->transform_size = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform_size);
  trans_class->propose_allocation = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_propose_allocation);
  trans_class->decide_allocation = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_decide_allocation);
  trans_class->transform_meta = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform_meta);
  trans_class->transform = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform);
  trans_class->transform_ip = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform_ip);
  trans_class->passthrough_on_same_caps = FALSE;
  trans_class->transform_ip_on_passthrough = FALSE;

  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_BASE, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_base_init(GstPseudo3DBase *self) {
  self->device_id = DEFAULT_DEVICE_ID;
  self->processing = DEFAULT_PROCESSING;
  gst_video_info_init(&self->in_info);
  gst_video_info_init(&self->out_info);
}
