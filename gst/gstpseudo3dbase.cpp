#include "gstpseudo3dbase.h"

#include <algorithm>
#include <cstdarg>
#include <exception>
#include <new>
#include <string>

#include "depth_meta.h"
#include "host_allocator.h"
#include "property_guard.h"
#include "video_util.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudabufferpool.h>
#include <gst/cuda/gstcudamemory.h>
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

/* ---- properties ---- */

static void gst_pseudo3d_base_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(object);
  if (!p3d::gst::property_settable(GST_ELEMENT(self), pspec)) return;
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_DEVICE_ID: self->device_id = g_value_get_int(value); break;
    case PROP_PROCESSING: self->processing = static_cast<GstPseudo3DProcessing>(g_value_get_enum(value)); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_base_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_DEVICE_ID: g_value_set_int(value, self->device_id); break;
    case PROP_PROCESSING: g_value_set_enum(value, self->processing); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

/* ---- the GPU ---- */

// Whether the GPU runs this element's frames (processing is fixed from start() to stop()).
static gboolean gpu_in_use(GstPseudo3DBase *self) {
  return self->processing != GST_PSEUDO3D_PROCESSING_CPU && self->gpu->usable();
}

GstPseudo3DPath gst_pseudo3d_base_path(GstPseudo3DBase *self) {
  return self->cuda_caps && gpu_in_use(self) ? GST_PSEUDO3D_PATH_GPU : GST_PSEUDO3D_PATH_CPU;
}

static void release_stage(GstPseudo3DBase *self) {
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  if (klass->release) klass->release(self);
}

#if HAVE_CUDA
GstFlowReturn gst_pseudo3d_base_cuda_error(GstPseudo3DBase *self, const p3d::CudaStatus &st, const char *what) {
  GST_ELEMENT_ERROR(self, RESOURCE, FAILED, ("CUDA failure while %s: %s", what, cudaGetErrorName(st.code)),
                    ("%s", st.message().c_str()));
  return GST_FLOW_ERROR;
}

static void gst_pseudo3d_base_set_context(GstElement *element, GstContext *context) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(element);
  self->gpu->handle_set_context(element, context, self->device_id);
  GST_ELEMENT_CLASS(parent_class)->set_context(element, context);
}

// An upstream CUDA buffer on another context: with cuda-device-id -1 (or
// that context's device) the element switches to it, as nvcodec's filters
// do, and renegotiates so that its pools move too. Runs before the base
// class checks for renegotiation, so the switch is complete for this frame.
static void adopt_buffer_context(GstPseudo3DBase *self, GstBuffer *buf) {
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

// Memory of another context (another device) must not be launched on.
static gboolean check_memory_context(GstPseudo3DBase *self, GstBuffer *buf) {
  if (gst_pseudo3d_base_path(self) != GST_PSEUDO3D_PATH_GPU) return TRUE;
  for (guint i = 0; i < gst_buffer_n_memory(buf); ++i) {
    GstMemory *mem = gst_buffer_peek_memory(buf, i);
    if (!gst_is_cuda_memory(mem) || GST_CUDA_MEMORY_CAST(mem)->context != self->gpu->context()) {
      GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Input buffer is not CUDA memory of this element's CUDA context"),
                        ("cuda-device-id is %d; set it to -1 or to the upstream element's device, or insert "
                         "cudadownload ! cudaupload",
                         self->device_id));
      return FALSE;
    }
  }
  return TRUE;
}
#endif

static gboolean gst_pseudo3d_base_start(GstBaseTransform *trans) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  self->history_reset_pending = TRUE;
  const char *why = "built without CUDA";
#if HAVE_CUDA
  if (self->processing != GST_PSEUDO3D_PROCESSING_CPU) self->gpu->acquire(GST_ELEMENT(self), self->device_id, &why);
#endif
  if (self->processing == GST_PSEUDO3D_PROCESSING_GPU && !self->gpu->usable()) {
    GST_ELEMENT_ERROR(self, RESOURCE, NOT_FOUND, ("processing=gpu but %s", why),
                      ("cuda-device-id %d; use processing=auto to fall back to the CPU", self->device_id));
    return FALSE;
  }
  if (!self->gpu->usable() && self->processing != GST_PSEUDO3D_PROCESSING_CPU && !self->cpu_notice_logged) {
    GST_INFO_OBJECT(self, "%s: processing on the CPU", why);
    self->cpu_notice_logged = TRUE;
  }
  return TRUE;
}

static gboolean gst_pseudo3d_base_stop(GstBaseTransform *trans) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
#if HAVE_CUDA
  self->gpu->release([self] { release_stage(self); });
#else
  release_stage(self);
#endif
  self->cuda_caps = FALSE;
  gst_clear_caps(&self->refused_caps);
  return TRUE;
}

/* ---- caps ---- */

// The int range lo..hi (an int: lo == hi) into `out`: an int when one value
// is left, else a range.
static void set_int_range(GValue *out, gint64 lo, gint64 hi) {
  if (lo == hi) {
    g_value_init(out, G_TYPE_INT);
    g_value_set_int(out, (gint)lo);
  } else {
    g_value_init(out, GST_TYPE_INT_RANGE);
    gst_value_set_int_range(out, (gint)lo, (gint)hi);
  }
}

// Maps a caps field's value through map(lo, hi, out): an int as the range
// v..v, an int range, or a list of them, item by item; other values are
// copied.
template <typename RangeMap>
static void map_value(const GValue *in, GValue *out, const RangeMap &map) {
  if (G_VALUE_HOLDS_INT(in)) {
    map(g_value_get_int(in), g_value_get_int(in), out);
  } else if (GST_VALUE_HOLDS_INT_RANGE(in)) {
    map(gst_value_get_int_range_min(in), gst_value_get_int_range_max(in), out);
  } else if (GST_VALUE_HOLDS_LIST(in)) {
    g_value_init(out, GST_TYPE_LIST);
    for (guint i = 0; i < gst_value_list_get_size(in); ++i) {
      GValue item = G_VALUE_INIT;
      map_value(gst_value_list_get_value(in, i), &item, map);
      gst_value_list_append_and_take_value(out, &item);
    }
  } else {
    g_value_init(out, G_VALUE_TYPE(in));
    g_value_copy(in, out);
  }
}

template <typename RangeMap>
static void map_field(GstStructure *s, const char *field, const RangeMap &map) {
  const GValue *v = gst_structure_get_value(s, field);
  if (!v) return;
  GValue mapped = G_VALUE_INIT;
  map_value(v, &mapped, map);
  gst_structure_take_value(s, field, &mapped);
}

void gst_pseudo3d_scale_field(GstStructure *s, const char *field, gint num, gint den) {
  if (num == den) return;
  auto scale = [&](gint v) -> gint64 { return CLAMP((gint64)v * num / den, 1, G_MAXINT); };
  map_field(s, field, [&](gint lo, gint hi, GValue *out) {
    if (lo == hi) return set_int_range(out, scale(lo), scale(lo));
    const gint64 a = scale(lo);  // a range stays a range (but for G_MAXINT itself)
    set_int_range(out, a, std::max(scale(hi), std::min<gint64>(a + 1, G_MAXINT)));
  });
}

// The values x >= 1 with lo <= x * num / den <= hi (floor): ceil(lo * den /
// num) .. floor(((hi + 1) * den - 1) / num). None (an odd size, doubled):
// the smallest x above, whose image the caps then refuse.
void gst_pseudo3d_unscale_field(GstStructure *s, const char *field, gint num, gint den) {
  if (num == den) return;
  map_field(s, field, [&](gint lo, gint hi, GValue *out) {
    const gint64 a = CLAMP(((gint64)lo * den + num - 1) / num, 1, G_MAXINT);
    const gint64 b = CLAMP((((gint64)hi + 1) * den - 1) / num, 1, G_MAXINT);
    set_int_range(out, a, std::max(a, b));
  });
}

GstStructure *gst_pseudo3d_sizes_forward(const GstStructure *in, gint wn, gint wd, gint hn, gint hd) {
  GstStructure *s = gst_structure_copy(in);
  gst_pseudo3d_scale_field(s, "width", wn, wd);
  gst_pseudo3d_scale_field(s, "height", hn, hd);
  return s;
}

GstStructure *gst_pseudo3d_sizes_back(const GstStructure *in, gint wn, gint wd, gint hn, gint hd, gboolean rounded) {
  if (!rounded) return gst_pseudo3d_sizes_forward(in, wd, wn, hd, hn);  // the exact inverse
  GstStructure *s = gst_structure_copy(in);
  gst_pseudo3d_unscale_field(s, "width", wn, wd);
  gst_pseudo3d_unscale_field(s, "height", hn, hd);
  return s;
}

GstCaps *gst_pseudo3d_caps_of(GstStructure *s) {
  GstCaps *caps = gst_caps_new_empty();
  gst_caps_append_structure(caps, s);
  return caps;
}

void gst_pseudo3d_set_formats(GstStructure *s, const gchar *formats) {
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
  const gboolean to_src = direction == GST_PAD_SINK;
  const gchar *formats = to_src ? klass->src_formats : klass->sink_formats;

  GstCaps *out = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    const GstStructure *in = gst_caps_get_structure(caps, i);
    GstCapsFeatures *f = gst_caps_get_features(caps, i);
    GstCaps *variants = klass->transform_geometry ? klass->transform_geometry(self, direction, in)
                                                  : gst_pseudo3d_caps_of(gst_structure_copy(in));
    for (guint k = 0; k < gst_caps_get_size(variants); ++k) {
      GstStructure *s = gst_structure_copy(gst_caps_get_structure(variants, k));
      if (formats) gst_pseudo3d_set_formats(s, formats);
      out = gst_caps_merge_structure_full(out, s, f ? gst_caps_features_copy(f) : nullptr);
    }
    gst_caps_unref(variants);
  }
  if (filter) {
    GstCaps *tmp = gst_caps_intersect_full(filter, out, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(out);
    out = tmp;
  }
  GST_DEBUG_OBJECT(self, "%s caps %" GST_PTR_FORMAT " -> %" GST_PTR_FORMAT, to_src ? "sink" : "src", caps, out);
  return out;
}

#if HAVE_CUDA
// The same caps with the memory:CUDAMemory structures first: peers fixate on
// the first structure, and a caps query's filter (cudaupload offers system
// memory first) would otherwise decide the order.
static GstCaps *cuda_first(GstCaps *caps) {
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
#endif

// Brackets each negotiation (a CAPS event, the renegotiation before a
// buffer, a caps, accept-caps or allocation query; from any thread,
// possibly nested): the staged geometry's configuring value stays frozen
// (see staged_geometry.h).
static void freeze_geometry(GstPseudo3DBase *self, gboolean frozen) {
  if (!self->staged) return;
  GST_OBJECT_LOCK(self);
  self->staged->freeze(frozen);
  GST_OBJECT_UNLOCK(self);
}

static void settle_geometry(GstPseudo3DBase *self) {
  if (!self->staged) return;
  GST_OBJECT_LOCK(self);
  self->staged->settle();
  GST_OBJECT_UNLOCK(self);
}

// GstBaseTransform renegotiates a running stream before a buffer when a
// property or downstream asked for it, and any failure there posts a bare
// "not negotiated" warning and stops the stream. Two failures are not the
// user's fault and must not stop it:
//  * a flush (a seek) racing the renegotiation: downstream refuses while
//    flushing. The buffer is dropped as flushing, silently; the request
//    stays and is negotiated with the next buffer.
//  * a live value the stream cannot take (method=rgbd on a width that
//    cannot be halved, input-layout=top-bottom on an odd height): the value
//    is refused with one warning saying why, the property goes back to the
//    value of the caps in force, and the stream goes on with it.
// Any other failure is the parent's: its warning and NOT_NEGOTIATED.
static GstFlowReturn renegotiate_running_stream(GstPseudo3DBase *self) {
  GstBaseTransform *trans = GST_BASE_TRANSFORM(self);
  if (!gst_pad_needs_reconfigure(trans->srcpad) || !gst_pad_has_current_caps(trans->srcpad)) return GST_FLOW_OK;
  GST_OBJECT_LOCK(self);
  const bool change = self->staged && self->staged->pending();
  GST_OBJECT_UNLOCK(self);
  const gint flushes = g_atomic_int_get(&self->flush_starts);
  g_atomic_pointer_set(&self->live_thread, g_thread_self());  // refusals collected, the bare warning dropped
  const gboolean ok = gst_base_transform_reconfigure(trans);
  g_atomic_pointer_set(&self->live_thread, nullptr);
  gchar *refusal = self->live_refusal, *debug = self->live_refusal_debug;
  self->live_refusal = self->live_refusal_debug = nullptr;
  GstFlowReturn ret = GST_FLOW_OK;
  if (ok) {
    settle_geometry(self);
  } else if (flushes != g_atomic_int_get(&self->flush_starts) || GST_PAD_IS_FLUSHING(trans->sinkpad) ||
             GST_PAD_IS_FLUSHING(trans->srcpad)) {
    GST_DEBUG_OBJECT(self, "renegotiation met a flush: the buffer is dropped, the request stays");
    ret = GST_FLOW_FLUSHING;
  } else if (change) {
    GST_OBJECT_LOCK(self);
    self->staged->revert();
    GST_OBJECT_UNLOCK(self);
    GST_ELEMENT_WARNING(self, CORE, NEGOTIATION,
                        ("%s: the new value is refused, and the stream goes on with the previous one",
                         refusal ? refusal : "The stream cannot take the new property value"),
                        ("%s", debug ? debug : "downstream did not accept the output caps of the new value"));
  } else {
    GST_ELEMENT_WARNING(self, STREAM, FORMAT, ("not negotiated"), ("%s", debug ? debug : "not negotiated"));
    ret = GST_FLOW_NOT_NEGOTIATED;
  }
  g_free(refusal);
  g_free(debug);
  return ret;
}

// The parent's bare "not negotiated" warning, posted from inside
// renegotiate_running_stream's renegotiation, is dropped: that function
// tells the failures apart and reports them itself.
static gboolean gst_pseudo3d_base_post_message(GstElement *element, GstMessage *msg) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(element);
  if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_WARNING && GST_MESSAGE_SRC(msg) == GST_OBJECT(element) &&
      g_atomic_pointer_get(&self->live_thread) == g_thread_self()) {
    GError *err = nullptr;
    gst_message_parse_warning(msg, &err, nullptr);
    const bool bare = err && g_error_matches(err, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT) &&
                      g_strcmp0(err->message, "not negotiated") == 0;
    g_clear_error(&err);
    if (bare) {
      gst_message_unref(msg);
      return TRUE;
    }
  }
  return GST_ELEMENT_CLASS(parent_class)->post_message(element, msg);
}

static gboolean gst_pseudo3d_base_query(GstBaseTransform *trans, GstPadDirection direction, GstQuery *query) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
#if HAVE_CUDA
  if (GST_QUERY_TYPE(query) == GST_QUERY_CONTEXT && self->gpu->handle_context_query(GST_ELEMENT(self), query))
    return TRUE;
#endif
  // A caps query transforms caps twice (through this element and back), and
  // GstBaseTransform answers upstream's ALLOCATION query by first doing a
  // pending renegotiation: each is one negotiation, bracketed like the one
  // before a buffer, or a property change from another thread between its
  // transform_caps calls (or before its set_caps) would make them disagree.
  // The allocation query renegotiates first, as a buffer does: through
  // renegotiate_running_stream, for the same reasons.
  const GstQueryType type = GST_QUERY_TYPE(query);
  const bool negotiates = type == GST_QUERY_CAPS || type == GST_QUERY_ACCEPT_CAPS || type == GST_QUERY_ALLOCATION;
  if (negotiates) freeze_geometry(self, TRUE);
  const bool allocation = type == GST_QUERY_ALLOCATION && direction == GST_PAD_SINK;
  const gboolean answered = (!allocation || renegotiate_running_stream(self) == GST_FLOW_OK) &&
                            GST_BASE_TRANSFORM_CLASS(parent_class)->query(trans, direction, query);
  if (negotiates) freeze_geometry(self, FALSE);
  if (!answered) return FALSE;
#if HAVE_CUDA
  // With a GPU in use, ask neighbours for CUDA memory first: without it,
  // `cudaupload ! pseudo3d...` would negotiate system memory and run on the CPU.
  if (GST_QUERY_TYPE(query) == GST_QUERY_CAPS && gpu_in_use(self)) {
    GstCaps *result = nullptr;
    gst_query_parse_caps_result(query, &result);
    if (result && !gst_caps_is_any(result)) {
      GstCaps *ordered = cuda_first(result);
      gst_query_set_caps_result(query, ordered);
      gst_caps_unref(ordered);
    }
  }
#endif
  return TRUE;
}

// The element the user placed: a stage inside pseudo3dconvert is known to
// the user by the bin's name, not by its hidden child's ("depth").
static const gchar *placed_element_name(GstElement *e) {
  GstObject *parent = GST_OBJECT_PARENT(e);
  if (parent && GST_IS_ELEMENT(parent)) {
    GstElementFactory *f = gst_element_get_factory(GST_ELEMENT(parent));
    if (f && g_strcmp0(GST_OBJECT_NAME(f), "pseudo3dconvert") == 0) return GST_ELEMENT_NAME(parent);
  }
  return GST_ELEMENT_NAME(e);
}

static gboolean gst_pseudo3d_base_set_caps(GstBaseTransform *trans, GstCaps *incaps, GstCaps *outcaps) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstVideoInfo in, out;
  if (!gst_video_info_from_caps(&in, incaps) || !gst_video_info_from_caps(&out, outcaps)) {
    GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, ("Caps are not raw video caps"),
                      ("%" GST_PTR_FORMAT " -> %" GST_PTR_FORMAT, incaps, outcaps));
    return FALSE;
  }
  gboolean cuda_caps = FALSE;
#if HAVE_CUDA
  GstCapsFeatures *features = gst_caps_get_features(incaps, 0);
  cuda_caps = features && gst_caps_features_contains(features, GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY);
  if (cuda_caps && self->processing != GST_PSEUDO3D_PROCESSING_CPU) {
    const char *why = nullptr;
    self->gpu->acquire(GST_ELEMENT(self), self->device_id, &why);
  }
#endif
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  self->negotiating_caps = incaps;
  gboolean accepted;
  if (GST_VIDEO_INFO_IS_INTERLACED(&in))
    // The stages treat every row as part of one picture: fields would be torn apart.
    accepted = gst_pseudo3d_base_refuse_caps(self, "Interlaced video is not supported",
                                             "interlace-mode %s; put deinterlace before %s",
                                             gst_video_interlace_mode_to_string(GST_VIDEO_INFO_INTERLACE_MODE(&in)),
                                             placed_element_name(GST_ELEMENT(self)));
  else if (!cuda_caps && self->processing == GST_PSEUDO3D_PROCESSING_GPU)
    // System memory runs on the CPU (see GstPseudo3DPath): "gpu" cannot be kept.
    accepted = gst_pseudo3d_base_refuse_caps(
        self, "processing=gpu needs video in CUDA memory",
        "the input is system memory; put cudaupload ! \"video/x-raw(memory:CUDAMemory)\" before %s and "
        "cudadownload after the stages, use pseudo3dconvert, or set processing=auto to run on the CPU",
        placed_element_name(GST_ELEMENT(self)));
  else
    accepted = !klass->set_info || klass->set_info(self, incaps, &in, outcaps, &out);
  self->negotiating_caps = nullptr;
  if (!accepted) return FALSE;
  gst_clear_caps(&self->refused_caps);
  // Stored only once the stage accepted them: a refused renegotiation leaves
  // the running configuration intact.
  self->in_info = in;
  self->out_info = out;
  self->cuda_caps = cuda_caps;

  const GstPseudo3DPath path = gst_pseudo3d_base_path(self);
  if (cuda_caps && path == GST_PSEUDO3D_PATH_CPU)
    GST_WARNING_OBJECT(self, "CUDA memory negotiated but processing on the CPU through mapped memory (slow)");
  if (!cuda_caps && gpu_in_use(self))
    GST_INFO_OBJECT(self, "system memory: processing on the CPU (CUDA memory, e.g. from cudaupload, runs on the GPU)");
  GST_INFO_OBJECT(self, "negotiated %dx%d -> %dx%d, processing on the %s", in.width, in.height, out.width, out.height,
                  path == GST_PSEUDO3D_PATH_GPU ? "GPU" : "CPU");
  return TRUE;
}

gboolean gst_pseudo3d_base_refuse_caps(GstPseudo3DBase *self, const char *text, const char *debug_format, ...) {
  if (g_atomic_pointer_get(&self->live_thread) == g_thread_self()) {
    // A live property change: the stream keeps its caps, the caller warns.
    va_list args;
    va_start(args, debug_format);
    g_free(self->live_refusal_debug);
    self->live_refusal_debug = g_strdup_vprintf(debug_format, args);
    va_end(args);
    g_free(self->live_refusal);
    self->live_refusal = g_strdup(text);
    return FALSE;
  }
  GstCaps *caps = self->negotiating_caps;
  if (caps && self->refused_caps && gst_caps_is_equal(caps, self->refused_caps)) {
    GST_DEBUG_OBJECT(self, "caps refused again: %s", text);
    return FALSE;
  }
  if (caps) gst_caps_replace(&self->refused_caps, caps);
  va_list args;
  va_start(args, debug_format);
  gchar *debug = g_strdup_vprintf(debug_format, args);
  va_end(args);
  GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, ("%s", text), ("%s", debug));
  g_free(debug);
  return FALSE;
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

/* ---- allocation ---- */

static gboolean caps_are_cuda(GstCaps *caps) {
#if HAVE_CUDA
  GstCapsFeatures *features = caps && gst_caps_get_size(caps) > 0 ? gst_caps_get_features(caps, 0) : nullptr;
  return features && gst_caps_features_contains(features, GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY);
#else
  (void)caps;
  return FALSE;
#endif
}

#if HAVE_CUDA
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
  if (!caps_are_cuda(caps) || !self->gpu->usable() || gst_query_get_n_allocation_pools(query) > 0) return TRUE;
  guint size = 0;
  GstBufferPool *pool = new_cuda_pool(self, caps, &size, 0, 0);
  if (!pool) return FALSE;
  gst_query_add_allocation_pool(query, pool, size, 0, 0);
  gst_object_unref(pool);
#endif
  return TRUE;
}

// System memory: unless downstream brings a pool of its own, output buffers
// come from the failure-reporting host allocator.
static void use_host_allocator(GstQuery *query) {
  GstAllocator *host = p3d::gst::host_allocator_get();
  GstAllocationParams params;
  gst_allocation_params_init(&params);
  if (gst_query_get_n_allocation_params(query) > 0) {
    GstAllocator *current = nullptr;
    gst_query_parse_nth_allocation_param(query, 0, &current, &params);
    const gboolean plain = !current || g_strcmp0(current->mem_type, GST_ALLOCATOR_SYSMEM) == 0;
    if (current) gst_object_unref(current);
    if (plain) gst_query_set_nth_allocation_param(query, 0, host, &params);
  } else {
    gst_query_add_allocation_param(query, host, &params);
  }
  gst_object_unref(host);
}

static gboolean gst_pseudo3d_base_decide_allocation(GstBaseTransform *trans, GstQuery *query) {
  GstCaps *outcaps = nullptr;
  gst_query_parse_allocation(query, &outcaps, nullptr);
#if HAVE_CUDA
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  if (self->gpu->usable() && caps_are_cuda(outcaps)) {
    GstBufferPool *pool = nullptr;
    guint size = 0, min = 0, max = 0;
    const gboolean update = gst_query_get_n_allocation_pools(query) > 0;
    if (update) {
      gst_query_parse_nth_allocation_pool(query, 0, &pool, &size, &min, &max);
      // Only a CUDA pool on our own context will do: never launch on memory of another context.
      if (pool && (!GST_IS_CUDA_BUFFER_POOL(pool) || GST_CUDA_BUFFER_POOL_CAST(pool)->context != self->gpu->context()))
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
    return GST_BASE_TRANSFORM_CLASS(parent_class)->decide_allocation(trans, query);
  }
#endif
  if (!caps_are_cuda(outcaps) && gst_query_get_n_allocation_pools(query) == 0) use_host_allocator(query);
  return GST_BASE_TRANSFORM_CLASS(parent_class)->decide_allocation(trans, query);
}

static GstFlowReturn gst_pseudo3d_base_prepare_output_buffer(GstBaseTransform *trans, GstBuffer *input,
                                                             GstBuffer **outbuf) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  const GstFlowReturn ret = GST_BASE_TRANSFORM_CLASS(parent_class)->prepare_output_buffer(trans, input, outbuf);
  if (ret == GST_FLOW_ERROR) {
    GstCaps *caps = gst_pad_get_current_caps(GST_BASE_TRANSFORM_SRC_PAD(trans));
    GstVideoInfo info;
    gst_video_info_init(&info);
    if (caps) gst_video_info_from_caps(&info, caps);
    GST_ELEMENT_ERROR(self, RESOURCE, NO_SPACE_LEFT,
                      ("Could not allocate a %dx%d output frame (%" G_GSIZE_FORMAT " bytes)", info.width, info.height,
                       GST_VIDEO_INFO_SIZE(&info)),
                      ("%s memory", caps_are_cuda(caps) ? "CUDA device" : "system"));
    if (caps) gst_caps_unref(caps);
  }
  return ret;
}

/* ---- stream events, QoS and the frame boundary ---- */

gboolean gst_pseudo3d_base_take_history_reset(GstPseudo3DBase *self) {
  GST_OBJECT_LOCK(self);
  const gboolean reset = self->history_reset_pending;
  self->history_reset_pending = FALSE;
  GST_OBJECT_UNLOCK(self);
  return reset;
}

static void request_history_reset(GstPseudo3DBase *self, const char *why) {
  GST_DEBUG_OBJECT(self, "temporal history reset: %s", why);
  GST_OBJECT_LOCK(self);
  self->history_reset_pending = TRUE;
  GST_OBJECT_UNLOCK(self);
}

static gboolean gst_pseudo3d_base_sink_event(GstBaseTransform *trans, GstEvent *event) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  switch (GST_EVENT_TYPE(event)) {
    case GST_EVENT_FLUSH_START: g_atomic_int_inc(&self->flush_starts); break;
    case GST_EVENT_FLUSH_STOP:
    case GST_EVENT_STREAM_START:
    case GST_EVENT_SEGMENT: request_history_reset(self, GST_EVENT_TYPE_NAME(event)); break;
    case GST_EVENT_CAPS: {
      // New caps start a new configuration: the history does not carry over.
      request_history_reset(self, "caps");
      freeze_geometry(self, TRUE);
      const gboolean ret = GST_BASE_TRANSFORM_CLASS(parent_class)->sink_event(trans, event);
      if (ret) settle_geometry(self);
      freeze_geometry(self, FALSE);
      return ret;
    }
    default: break;
  }
  return GST_BASE_TRANSFORM_CLASS(parent_class)->sink_event(trans, event);
}

static GstFlowReturn gst_pseudo3d_base_submit_input_buffer(GstBaseTransform *trans, gboolean is_discont,
                                                           GstBuffer *input) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  // Upstream's DISCONT only: is_discont is also set after this element's own
  // QoS drops, which must not cost the history.
  if (GST_BUFFER_FLAG_IS_SET(input, GST_BUFFER_FLAG_DISCONT)) request_history_reset(self, "discont");
#if HAVE_CUDA
  adopt_buffer_context(self, input);
#endif
  // The parent renegotiates if a property asked for it, then applies QoS;
  // a renegotiation of a running stream is done here first, so that its
  // failure is told apart (renegotiate_running_stream).
  freeze_geometry(self, TRUE);
  const GstFlowReturn renegotiated = renegotiate_running_stream(self);
  GstFlowReturn ret;
  if (renegotiated == GST_FLOW_OK) {
    ret = GST_BASE_TRANSFORM_CLASS(parent_class)->submit_input_buffer(trans, is_discont, input);
  } else {
    gst_buffer_unref(input);
    ret = renegotiated;
  }
  freeze_geometry(self, FALSE);
  return ret;
}

static void gst_pseudo3d_base_before_transform(GstBaseTransform *trans, GstBuffer *) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(trans);
  GstPseudo3DBaseClass *klass = GST_PSEUDO3D_BASE_GET_CLASS(self);
  if (klass->frame_boundary && klass->frame_boundary(self)) gst_base_transform_reconfigure_src(trans);
}

/* ---- frames ---- */

gboolean gst_pseudo3d_base_depth_fits(GstPseudo3DBase *self, const p3d::gst::DepthPlane *plane, GstPseudo3DPath path,
                                      int width, int height) {
  if (!plane || plane->width != width || plane->height != height) return FALSE;
  const bool device = path == GST_PSEUDO3D_PATH_GPU;
  if (plane->on_device != device) return FALSE;
#if HAVE_CUDA
  if (device && plane->context != self->gpu->context()) return FALSE;
#else
  (void)self;
#endif
  return TRUE;
}

p3d::gst::DepthPlane *gst_pseudo3d_base_frame_depth(GstPseudo3DBase *self, GstBuffer *buf, GstPseudo3DPath path,
                                                    int width, int height) {
  p3d::gst::DepthPlane *depth = pseudo3d_buffer_get_depth(buf);
  const char *name = GST_ELEMENT_NAME(gst_element_get_factory(GST_ELEMENT(self)));
  if (!depth) {
    GST_ELEMENT_ERROR(self, STREAM, FORMAT, ("%s needs a depth map, and this frame carries none", name),
                      ("put pseudo3ddepth before %s; elements that change the frame between them (scaling, flipping, "
                       "cropping, videoconvert, cudaupload/cudadownload) drop the depth, so put those before "
                       "pseudo3ddepth",
                       name));
    return nullptr;
  }
  if (!gst_pseudo3d_base_depth_fits(self, depth, path, width, height)) {
    GST_ELEMENT_ERROR(self, STREAM, FORMAT, ("The frame's depth map does not fit the frame"),
                      ("depth %dx%d in %s memory, frame %dx%d in %s memory; put pseudo3ddepth right before %s",
                       depth->width, depth->height, depth->on_device ? "device" : "host", width, height,
                       path == GST_PSEUDO3D_PATH_GPU ? "device" : "host", name));
    return nullptr;
  }
  return depth;
}

p3d::gst::DepthPlanePtr gst_pseudo3d_base_new_depth(GstPseudo3DBase *self, p3d::gst::DepthPlanePool &pool,
                                                    GstPseudo3DPath path, int width, int height, int shift) {
  std::string error;
#if HAVE_CUDA
  if (path != GST_PSEUDO3D_PATH_GPU) shift = 0;  // host planes are full-size
  p3d::gst::DepthPlanePtr plane =
      pool.acquire(width, height, shift, path == GST_PSEUDO3D_PATH_GPU ? self->gpu->context() : nullptr, &error);
#else
  (void)path;
  shift = 0;
  p3d::gst::DepthPlanePtr plane = pool.acquire(width, height, 0, nullptr, &error);
#endif
  if (!plane)
    GST_ELEMENT_ERROR(self, RESOURCE, NO_SPACE_LEFT,
                      ("Could not allocate a %dx%d depth map (%" G_GSIZE_FORMAT " bytes)", width, height,
                       static_cast<gsize>(p3d::grid_cells(width, shift)) * p3d::grid_cells(height, shift) *
                           sizeof(float)),
                      ("%s", error.c_str()));
  return plane;
}

static GstMapFlags map_flags(GstPseudo3DBase *self, GstMapFlags base) {
#if HAVE_CUDA
  if (gst_pseudo3d_base_path(self) == GST_PSEUDO3D_PATH_GPU) return (GstMapFlags)(base | GST_MAP_CUDA);
#else
  (void)self;
#endif
  return base;
}

// The CPU references report bad arguments and allocation failures by
// exceptions; none may unwind through GStreamer's C frames.
template <typename F>
static GstFlowReturn guarded(GstPseudo3DBase *self, F &&f) {
  try {
    return f();
  } catch (const std::bad_alloc &) {
    GST_ELEMENT_ERROR(self, RESOURCE, NO_SPACE_LEFT,
                      ("Out of memory while processing a %dx%d frame", GST_VIDEO_INFO_WIDTH(&self->in_info),
                       GST_VIDEO_INFO_HEIGHT(&self->in_info)),
                      ("host memory for the CPU path's working buffers"));
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
  {
#if HAVE_CUDA
    p3d::gst::CudaContextScope scope(path != GST_PSEUDO3D_PATH_CPU ? self->gpu->context() : nullptr);
#endif
    ret = guarded(self, [&] { return klass->process(self, path, inbuf, &in, &out); });
  }
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
  GstFlowReturn ret;
  {
#if HAVE_CUDA
    p3d::gst::CudaContextScope scope(path != GST_PSEUDO3D_PATH_CPU ? self->gpu->context() : nullptr);
#endif
    ret = guarded(self, [&] { return klass->process_ip(self, path, buf, &frame); });
  }
  gst_video_frame_unmap(&frame);
  return ret;
}

/* ---- class ---- */

static void gst_pseudo3d_base_finalize(GObject *object) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(object);
  gst_clear_caps(&self->refused_caps);
  g_free(self->live_refusal);
  g_free(self->live_refusal_debug);
  delete self->gpu;
  self->gpu = nullptr;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_base_class_init(GstPseudo3DBaseClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass *trans_class = GST_BASE_TRANSFORM_CLASS(klass);

  gobject_class->set_property = gst_pseudo3d_base_set_property;
  gobject_class->get_property = gst_pseudo3d_base_get_property;
  gobject_class->finalize = gst_pseudo3d_base_finalize;

  /**
   * GstPseudo3DBase:processing:
   *
   * auto: the GPU for memory:CUDAMemory caps when a CUDA device is usable
   * (kernels on the frames in place), else the CPU; system-memory caps run
   * on the CPU. cpu: always the CPU. gpu: fail to start without a GPU, and
   * refuse system-memory caps with an error that says what to insert.
   */
  g_object_class_install_property(
      gobject_class, PROP_PROCESSING,
      g_param_spec_enum("processing", "Processing",
                        "Where frames are processed: auto = GPU for video in CUDA memory when a CUDA device is "
                        "usable, else CPU (system memory always runs on the CPU); cpu; gpu = GPU, an error "
                        "without a GPU or on system memory. Set it in the NULL or READY state",
                        GST_TYPE_PSEUDO3D_PROCESSING, DEFAULT_PROCESSING,
                        (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_READY)));
  /**
   * GstPseudo3DBase:cuda-device-id:
   *
   * CUDA device to run on; -1 takes the pipeline's context (or the context
   * of the incoming CUDA buffers) or the first device.
   */
  g_object_class_install_property(
      gobject_class, PROP_DEVICE_ID,
      g_param_spec_int("cuda-device-id", "CUDA device id",
                       "CUDA device to use (-1 = the pipeline's shared context or that of the incoming CUDA "
                       "buffers, else any device). Set it in the NULL or READY state",
                       -1, G_MAXINT, DEFAULT_DEVICE_ID,
                       (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_READY)));

  element_class->post_message = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_post_message);
#if HAVE_CUDA
  element_class->set_context = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_set_context);
#else
  (void)element_class;
#endif
  trans_class->query = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_query);
  trans_class->start = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_stop);
  trans_class->transform_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform_caps);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_set_caps);
  trans_class->transform_size = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform_size);
  trans_class->propose_allocation = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_propose_allocation);
  trans_class->decide_allocation = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_decide_allocation);
  trans_class->prepare_output_buffer = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_prepare_output_buffer);
  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_sink_event);
  trans_class->submit_input_buffer = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_submit_input_buffer);
  trans_class->before_transform = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_before_transform);
  trans_class->transform = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform);
  trans_class->transform_ip = GST_DEBUG_FUNCPTR(gst_pseudo3d_base_transform_ip);
  trans_class->passthrough_on_same_caps = FALSE;
  trans_class->transform_ip_on_passthrough = FALSE;

  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_BASE, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_base_init(GstPseudo3DBase *self) {
  self->device_id = DEFAULT_DEVICE_ID;
  self->processing = DEFAULT_PROCESSING;
  self->gpu = new p3d::gst::GpuContext();
  gst_video_info_init(&self->in_info);
  gst_video_info_init(&self->out_info);
  // As GstVideoFilter: late frames are dropped before they are processed.
  gst_base_transform_set_qos_enabled(GST_BASE_TRANSFORM(self), TRUE);
}
