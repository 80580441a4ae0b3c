#include "gstpseudo3dbase.h"

#include <cstdarg>
#include <exception>
#include <new>

#include "caps_geometry.h"
#include "host_allocator.h"
#include "property_guard.h"
#include "stage_gpu.h"
#include "video_util.h"

GST_DEBUG_CATEGORY(gst_pseudo3d_base_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_base_debug

enum { PROP_0, PROP_DEVICE_ID, PROP_PROCESSING, PROP_ADAPTIVE, PROP_REUSE_TOLERANCE };
#define DEFAULT_DEVICE_ID (-1)
#define DEFAULT_PROCESSING GST_PSEUDO3D_PROCESSING_AUTO
#define DEFAULT_ADAPTIVE TRUE

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
    case PROP_ADAPTIVE: self->adaptive = g_value_get_boolean(value); break;
    case PROP_REUSE_TOLERANCE: self->reuse_tolerance = g_value_get_float(value); break;
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
    case PROP_ADAPTIVE: g_value_set_boolean(value, self->adaptive); break;
    case PROP_REUSE_TOLERANCE: g_value_set_float(value, self->reuse_tolerance); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

/* ---- the GPU ---- */

using p3d::gst::caps_are_cuda;
using p3d::gst::gpu_in_use;
using p3d::gst::release_stage;

GstPseudo3DPath gst_pseudo3d_base_path(GstPseudo3DBase *self) {
  return self->cuda_caps && gpu_in_use(self) ? GST_PSEUDO3D_PATH_GPU : GST_PSEUDO3D_PATH_CPU;
}

#if HAVE_CUDA
static void gst_pseudo3d_base_set_context(GstElement *element, GstContext *context) {
  GstPseudo3DBase *self = GST_PSEUDO3D_BASE(element);
  self->gpu->handle_set_context(element, context, self->device_id);
  GST_ELEMENT_CLASS(parent_class)->set_context(element, context);
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
  self->latency->reset();
  gst_clear_caps(&self->refused_caps);
  return TRUE;
}

/* ---- caps ---- */

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
      // CUDA memory holds what its allocator takes (keep_cuda_formats).
      if (f && gst_caps_features_contains(f, "memory:CUDAMemory") && !p3d::gst::keep_cuda_formats(s)) {
        gst_structure_free(s);
        continue;
      }
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

// Upstream's latency plus what this stage's frames take (processing_latency.h).
static void add_processing_latency(GstPseudo3DBase *self, GstQuery *query) {
  gboolean live;
  GstClockTime min, max;
  gst_query_parse_latency(query, &live, &min, &max);
  self->latency->set_live(live);
  const GstClockTime own = self->latency->reported();
  if (GST_CLOCK_TIME_IS_VALID(min)) min += own;
  if (GST_CLOCK_TIME_IS_VALID(max)) max += own;
  gst_query_set_latency(query, live, min, max);
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
  if (type == GST_QUERY_LATENCY && direction == GST_PAD_SRC) add_processing_latency(self, query);
#if HAVE_CUDA
  // With a GPU in use, ask neighbours for CUDA memory first: without it,
  // `cudaupload ! pseudo3d...` would negotiate system memory and run on the CPU.
  if (GST_QUERY_TYPE(query) == GST_QUERY_CAPS && gpu_in_use(self)) {
    GstCaps *result = nullptr;
    gst_query_parse_caps_result(query, &result);
    if (result && !gst_caps_is_any(result)) {
      GstCaps *ordered = p3d::gst::cuda_first(result);
      gst_query_set_caps_result(query, ordered);
      gst_caps_unref(ordered);
    }
  }
#endif
  return TRUE;
}

void gst_pseudo3d_base_set_hidden_in_parent(GstPseudo3DBase *self, gboolean hidden) { self->hidden_in_parent = hidden; }

// The element the user placed: a stage hidden in a bin is known to the user
// by the bin's name, not by its own ("depth").
static const gchar *placed_element_name(GstPseudo3DBase *self) {
  GstObject *parent = GST_OBJECT_PARENT(self);
  if (self->hidden_in_parent && parent && GST_IS_ELEMENT(parent)) return GST_ELEMENT_NAME(parent);
  return GST_ELEMENT_NAME(self);
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
  cuda_caps = caps_are_cuda(incaps);
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
    // deinterlace takes system memory only (pseudo3dconvert's own passes
    // CUDA memory through).
    accepted = gst_pseudo3d_base_refuse_caps(
        self, "Interlaced video is not supported", "interlace-mode %s; put deinterlace before %s%s",
        gst_video_interlace_mode_to_string(GST_VIDEO_INFO_INTERLACE_MODE(&in)), placed_element_name(self),
        cuda_caps ? ", in system memory (before cudaupload, or a decoder's output in system memory): deinterlace "
                    "does not take CUDA memory"
                  : "");
  else if (!cuda_caps && self->processing == GST_PSEUDO3D_PROCESSING_GPU)
    // System memory runs on the CPU (see GstPseudo3DPath): "gpu" cannot be kept.
    accepted = gst_pseudo3d_base_refuse_caps(
        self, "processing=gpu needs video in CUDA memory",
        "the input is system memory; put cudaupload ! \"video/x-raw(memory:CUDAMemory)\" before %s and "
        "cudadownload after the stages, or set processing=auto to run on the CPU",
        placed_element_name(self));
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
  self->latency->restart();

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

static gboolean gst_pseudo3d_base_propose_allocation(GstBaseTransform *trans, GstQuery *decide_query,
                                                     GstQuery *query) {
  if (!GST_BASE_TRANSFORM_CLASS(parent_class)->propose_allocation(trans, decide_query, query)) return FALSE;
  if (decide_query == nullptr) return TRUE; /* passthrough: downstream answered */
  gst_query_add_allocation_meta(query, GST_VIDEO_META_API_TYPE, nullptr);
#if HAVE_CUDA
  if (!p3d::gst::propose_cuda_pool(GST_PSEUDO3D_BASE(trans), query)) return FALSE;
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
  bool cuda = false;
  if (!p3d::gst::decide_cuda_pool(GST_PSEUDO3D_BASE(trans), query, &cuda)) return FALSE;
  if (cuda) return GST_BASE_TRANSFORM_CLASS(parent_class)->decide_allocation(trans, query);
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
  p3d::gst::adopt_buffer_context(self, input);
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


// The CPU references report bad arguments and allocation failures by
// exceptions; none may unwind through GStreamer's C frames.
template <typename F>
static GstFlowReturn guarded(GstPseudo3DBase *self, F &&f) {
  try {
    const gint64 start = g_get_monotonic_time();
    const GstFlowReturn ret = f();
    const gint64 took_us = g_get_monotonic_time() - start;
    if (ret == GST_FLOW_OK && self->latency->observe(static_cast<uint64_t>(took_us) * 1000u) &&
        self->latency->live()) {
      GST_INFO_OBJECT(self, "a frame takes up to %" GST_TIME_FORMAT ": posting a latency message",
                      GST_TIME_ARGS(self->latency->reported()));
      gst_element_post_message(GST_ELEMENT(self), gst_message_new_latency(GST_OBJECT(self)));
    }
    return ret;
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
  if (!p3d::gst::check_memory_context(self, inbuf)) return GST_FLOW_ERROR;
#endif
  GstVideoFrame in, out;
  // NO_REF: stages attach metas to outbuf, which a held ref would make unwritable.
  const auto no_ref = static_cast<GstMapFlags>(GST_VIDEO_FRAME_MAP_FLAG_NO_REF);
  if (!gst_video_frame_map(&in, &self->in_info, inbuf, (GstMapFlags)(p3d::gst::frame_map_flags(self, GST_MAP_READ) | no_ref))) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Could not map the input frame"), (nullptr));
    return GST_FLOW_ERROR;
  }
  if (!gst_video_frame_map(&out, &self->out_info, outbuf, (GstMapFlags)(p3d::gst::frame_map_flags(self, GST_MAP_WRITE) | no_ref))) {
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
  if (!p3d::gst::check_memory_context(self, buf)) return GST_FLOW_ERROR;
#endif
  GstVideoFrame frame;
  // NO_REF: a mapped frame holding a ref would make buf unwritable, and the
  // stage must attach its meta to buf.
  if (!gst_video_frame_map(&frame, &self->in_info, buf,
                           (GstMapFlags)(p3d::gst::frame_map_flags(self, GST_MAP_READ) | GST_VIDEO_FRAME_MAP_FLAG_NO_REF))) {
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
  delete self->latency;
  self->latency = nullptr;
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

  /**
   * GstPseudo3DBase:adaptive:
   *
   * Work that follows what changed: the stage compares its inputs with the
   * previous frame's, tile by tile, and recomputes only the output that a
   * changed tile can reach; an unchanged frame costs a comparison. With
   * reuse-tolerance 0 the output is byte for byte that of adaptive=false.
   */
  g_object_class_install_property(
      gobject_class, PROP_ADAPTIVE,
      g_param_spec_boolean("adaptive", "Adaptive",
                           "Recompute only what changed since the previous frame (tiles of 32x32 pixels and the "
                           "output they reach); an unchanged frame costs a comparison. With reuse-tolerance 0 the "
                           "output is byte for byte that of adaptive=false. On CUDA memory the comparison and "
                           "the decisions stay on the device. A stage whose frames keep changing computes them "
                           "whole for a while without comparing",
                           DEFAULT_ADAPTIVE,
                           (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING)));
  /**
   * GstPseudo3DBase:reuse-tolerance:
   *
   * With adaptive: a tile whose bytes changed by at most this mean
   * (8-bit levels) since the frame its results come from counts as
   * unchanged. 0 is exact; above 0 the output departs from
   * adaptive=false's (error against time in docs/quality.md).
   */
  g_object_class_install_property(
      gobject_class, PROP_REUSE_TOLERANCE,
      g_param_spec_float("reuse-tolerance", "Reuse tolerance",
                         "With adaptive: mean change of a tile's bytes (8-bit levels) up to which its previous "
                         "results are kept; 0 = exact (any changed byte counts). Above 0 the output departs from "
                         "adaptive=false's: error against time in docs/quality.md",
                         0.f, 255.f, 0.f,
                         (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING)));

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
  self->adaptive = DEFAULT_ADAPTIVE;
  self->reuse_tolerance = 0.f;
  self->gpu = new p3d::gst::GpuContext();
  self->latency = new p3d::gst::ProcessingLatency();
  gst_video_info_init(&self->in_info);
  gst_video_info_init(&self->out_info);
  // As GstVideoFilter: late frames are dropped before they are processed.
  gst_base_transform_set_qos_enabled(GST_BASE_TRANSFORM(self), TRUE);
}
