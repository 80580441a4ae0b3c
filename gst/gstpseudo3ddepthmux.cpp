/**
 * SECTION:element-pseudo3ddepthmux
 * @title: pseudo3ddepthmux
 *
 * Attaches depth from another source (a depth camera, a depth file, the
 * output of a depth model such as Depth-Anything) to each frame of the
 * `video` pad, as pseudo3ddepth does with the depth it estimates, so that
 * pseudo3dfilter, pseudo3dwarp and pseudo3dpack follow unchanged.
 *
 * The `depth` pad takes 8- or 16-bit grey of any size. Each frame gets the
 * latest depth picture whose running time is not after its own (the first
 * depth picture serves frames before it); once the depth stream has ended,
 * its last picture serves the rest, so one still picture can serve a whole
 * stream. A depth picture of another size than the frame is resampled to
 * it, each pixel taking the nearest depth sample (interpolated depth at an
 * object's edge would be neither the object's nor the background's).
 * `convention` says how grey values mean depth: white = near
 * (most depth maps), dark = near, or a distance (a depth camera's
 * millimetres) with `near` and `far` limits. Changing the pair while
 * playing sets one property after the other: while the pair is invalid
 * (near not below far), frames keep the last valid pair and one warning is
 * posted; a pair that was never valid is an error.
 *
 * Frames in CUDA memory get their depth in the same CUDA context, ready for
 * the GPU stages. The frames themselves pass through untouched.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 filesrc location=aloeL.jpg ! jpegdec ! videoconvert ! imagefreeze num-buffers=1 ! m.video \
 *   filesrc location=aloe-depth.png ! pngdec ! videoconvert ! video/x-raw,format=GRAY16_LE ! m.depth \
 *   pseudo3ddepthmux name=m ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack layout=anaglyph ! videoconvert ! \
 *   pngenc ! filesink location=aloe-anaglyph.png
 * ]|
 */
#include "gstpseudo3ddepthmux.h"

#include <memory>
#include <string>

#include "config.h"
#include "depth_grey.h"
#include "depth_meta.h"
#include "depth_plane.h"
#include "enums.h"
#include "video_util.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudamemory.h>

#include "gpu_context.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_depth_mux_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_depth_mux_debug

enum { PROP_0, PROP_CONVENTION, PROP_NEAR, PROP_FAR };

#define DEPTH_FORMATS "{ GRAY8, GRAY16_LE }"

struct MuxState {
  p3d::gst::DepthPlanePool pool;
  // What the current depth buffer became for the last frame: reused while
  // the depth picture, the frame size, the domain and the convention stay.
  p3d::gst::DepthPlanePtr plane;
  GstBuffer *plane_source = nullptr;  // the depth buffer it came from (no ref: compared only)
  p3d::DepthImportParams plane_params;
  void *plane_context = nullptr;
  // near and far are two properties, so setting a new pair passes through
  // a pair that may be invalid (near=20000 before far=50000): frames then
  // keep the last valid pair, with one warning, until the pair is valid.
  bool have_valid_range = false;
  float valid_near = 0.f, valid_far = 0.f;
  bool warned_invalid_range = false;
};

struct _GstPseudo3DDepthMux {
  GstAggregator parent;
  GstAggregatorPad *video_pad, *depth_pad;
  p3d::DepthImportParams params;  // properties (object lock)
  // Streaming thread (aggregate and the serialized events it runs):
  GstVideoInfo video_info, depth_info;
  gboolean have_video_info, have_depth_info;
  GstBuffer *depth;       // the depth picture in use, or null
  gboolean depth_stale;   // it came before a flush: a new one replaces it at once
  gboolean warned_unlinked;  // the unlinked depth pad was reported (until stop)
  MuxState *state;
};

#define gst_pseudo3d_depth_mux_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DDepthMux, gst_pseudo3d_depth_mux, GST_TYPE_AGGREGATOR);
GST_ELEMENT_REGISTER_DEFINE(pseudo3ddepthmux, "pseudo3ddepthmux", GST_RANK_NONE, GST_TYPE_PSEUDO3D_DEPTH_MUX);

static GstCaps *video_template_caps() { return p3d::gst::caps_all_domains(P3D_ALL_FORMATS, p3d::kMaxFrameSide); }

static GstCaps *depth_template_caps() {
  return gst_caps_from_string("video/x-raw, format=(string)" DEPTH_FORMATS
                              ", width=(int)[1, 8192], height=(int)[1, 8192], framerate=(fraction)[0/1, MAX]");
}

static GstClockTime running_time(GstAggregatorPad *pad, GstBuffer *buf) {
  const GstClockTime pts = GST_BUFFER_PTS(buf);
  if (!GST_CLOCK_TIME_IS_VALID(pts)) return GST_CLOCK_TIME_NONE;
  return gst_segment_to_running_time(&pad->segment, GST_FORMAT_TIME, pts);
}

// Moves to the depth picture for a frame at running time `rt`: the last one
// not after it, which is known once the depth pad holds a later one or has
// ended (the first one serves frames before it). FALSE: wait for more depth.
// `timeout` (live): a late depth stream does not hold frames back once there
// is a depth picture to use.
static gboolean advance_depth(GstPseudo3DDepthMux *self, GstClockTime rt, gboolean timeout) {
  for (;;) {
    GstBuffer *next = gst_aggregator_pad_peek_buffer(self->depth_pad);
    if (!next) return gst_aggregator_pad_is_eos(self->depth_pad) || (timeout && self->depth);
    const GstClockTime drt = running_time(self->depth_pad, next);
    const gboolean later = GST_CLOCK_TIME_IS_VALID(drt) && GST_CLOCK_TIME_IS_VALID(rt) && drt > rt;
    if (later && self->depth && !self->depth_stale) {
      gst_buffer_unref(next);
      return TRUE;
    }
    gst_buffer_replace(&self->depth, next);
    self->depth_stale = FALSE;
    gst_aggregator_pad_drop_buffer(self->depth_pad);
    gst_buffer_unref(next);
    if (later) return TRUE;
  }
}

#if HAVE_CUDA
static GstCudaContext *cuda_context_of(GstBuffer *buf) {
  GstMemory *mem = gst_buffer_peek_memory(buf, 0);
  return mem && gst_is_cuda_memory(mem) ? GST_CUDA_MEMORY_CAST(mem)->context : nullptr;
}
#endif

// Makes params' near/far a valid pair for convention=metric: the pair as
// set when it is valid (remembered), else the last valid one (a warning the
// first time). FALSE, after an error, when no pair was ever valid: the
// properties themselves are wrong, not merely half-changed.
static bool metric_range_usable(GstPseudo3DDepthMux *self, p3d::DepthImportParams *params) {
  MuxState &st = *self->state;
  if (params->near > 0.f && params->near < params->far) {
    st.have_valid_range = true;
    st.valid_near = params->near;
    st.valid_far = params->far;
    st.warned_invalid_range = false;
    return true;
  }
  if (params->convention != p3d::DepthConvention::Metric) return true;
  if (!st.have_valid_range) {
    GST_ELEMENT_ERROR(self, LIBRARY, SETTINGS, ("near must be above 0 and below far for convention=metric"),
                      ("near %g, far %g", params->near, params->far));
    return false;
  }
  if (!st.warned_invalid_range) {
    st.warned_invalid_range = true;
    GST_ELEMENT_WARNING(self, LIBRARY, SETTINGS,
                        ("near must be above 0 and below far for convention=metric: keeping the last valid pair"),
                        ("near %g, far %g set; near %g, far %g used until the pair is valid again", params->near,
                         params->far, st.valid_near, st.valid_far));
  }
  params->near = st.valid_near;
  params->far = st.valid_far;
  return true;
}

// The current depth picture as a plane of the frame's size, in the frame's
// memory domain; null after posting an error.
static p3d::gst::DepthPlanePtr depth_plane_for(GstPseudo3DDepthMux *self, GstBuffer *frame) {
  MuxState &st = *self->state;
  GST_OBJECT_LOCK(self);
  p3d::DepthImportParams params = self->params;
  GST_OBJECT_UNLOCK(self);
  if (!metric_range_usable(self, &params)) return nullptr;
  const int w = GST_VIDEO_INFO_WIDTH(&self->video_info), h = GST_VIDEO_INFO_HEIGHT(&self->video_info);
  void *context = nullptr;
#if HAVE_CUDA
  GstCudaContext *cuda = cuda_context_of(frame);
  context = cuda;
#else
  (void)frame;
#endif
  if (st.plane && st.plane_source == self->depth && st.plane->width == w && st.plane->height == h &&
      st.plane_context == context && st.plane_params.convention == params.convention &&
      st.plane_params.near == params.near && st.plane_params.far == params.far)
    return st.plane;

  GstVideoFrame df;
  if (!gst_video_frame_map(&df, &self->depth_info, self->depth, GST_MAP_READ)) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Could not read the depth picture"),
                      ("buffer %p does not match %" GST_PTR_FORMAT, self->depth, &self->depth_info));
    return nullptr;
  }
  p3d::ImageView<const uint8_t> src;
  src.data = static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&df, 0));
  src.width = GST_VIDEO_FRAME_WIDTH(&df);
  src.height = GST_VIDEO_FRAME_HEIGHT(&df);
  src.pitch = GST_VIDEO_FRAME_PLANE_STRIDE(&df, 0);
  const int bits = GST_VIDEO_FRAME_FORMAT(&df) == GST_VIDEO_FORMAT_GRAY8 ? 8 : 16;
  std::string error;
  p3d::gst::DepthPlanePtr host = st.pool.acquire(w, h, 0, nullptr, &error);
  if (host) p3d::import_depth_cpu(params, src, bits, host->view());
  gst_video_frame_unmap(&df);
  if (!host) {
    GST_ELEMENT_ERROR(self, RESOURCE, NO_SPACE_LEFT, ("Could not allocate the depth plane"), ("%s", error.c_str()));
    return nullptr;
  }
  p3d::gst::DepthPlanePtr plane = host;
#if HAVE_CUDA
  if (cuda) {
    // The GPU stages read the depth where the frame is.
    p3d::gst::CudaContextScope scope(cuda);
    plane = scope.ok() ? st.pool.acquire(w, h, 0, cuda, &error) : nullptr;
    if (!scope.ok()) error = "could not make the frame's CUDA context current";
    if (plane) {
      const p3d::ImageView<float> d = plane->view(), hv = host->view();
      const cudaError_t err = cudaMemcpy2D(d.data, d.pitch, hv.data, hv.pitch, static_cast<size_t>(w) * sizeof(float),
                                           h, cudaMemcpyHostToDevice);
      if (err != cudaSuccess) {
        error = std::string("cudaMemcpy2D of the depth plane failed: ") + cudaGetErrorName(err);
        plane = nullptr;
      }
    }
    if (!plane) {
      GST_ELEMENT_ERROR(self, RESOURCE, FAILED, ("Could not put the depth into CUDA memory"), ("%s", error.c_str()));
      return nullptr;
    }
  }
#endif
  st.plane = plane;
  st.plane_source = self->depth;
  st.plane_params = params;
  st.plane_context = context;
  return plane;
}

static GstFlowReturn gst_pseudo3d_depth_mux_aggregate(GstAggregator *agg, gboolean timeout) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(agg);
  GstBuffer *frame = gst_aggregator_pad_peek_buffer(self->video_pad);
  if (!frame) return gst_aggregator_pad_is_eos(self->video_pad) ? GST_FLOW_EOS : GST_FLOW_OK;
  const GstClockTime rt = running_time(self->video_pad, frame);
  if (!advance_depth(self, rt, timeout)) {
    gst_buffer_unref(frame);
    return GST_FLOW_OK;  // called again when depth comes
  }
  if (!self->depth) {
    gst_buffer_unref(frame);
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("The depth stream ended without a depth picture"),
                      ("the video needs at least one buffer on the depth pad"));
    return GST_FLOW_ERROR;
  }
  if (!self->have_video_info || !self->have_depth_info) {
    gst_buffer_unref(frame);
    GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, ("Buffers came before caps"), (nullptr));
    return GST_FLOW_NOT_NEGOTIATED;
  }
  gst_aggregator_pad_drop_buffer(self->video_pad);
  p3d::gst::DepthPlanePtr plane = depth_plane_for(self, frame);
  if (!plane) {
    gst_buffer_unref(frame);
    return GST_FLOW_ERROR;
  }
  frame = gst_buffer_make_writable(frame);
  pseudo3d_buffer_set_depth(frame, std::move(plane));
  return gst_aggregator_finish_buffer(agg, frame);
}

static gboolean gst_pseudo3d_depth_mux_sink_event(GstAggregator *agg, GstAggregatorPad *pad, GstEvent *event) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(agg);
  switch (GST_EVENT_TYPE(event)) {
    case GST_EVENT_CAPS: {
      GstCaps *caps = nullptr;
      gst_event_parse_caps(event, &caps);
      const gboolean video = pad == self->video_pad;
      GstVideoInfo info;
      if (!gst_video_info_from_caps(&info, caps)) {
        GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, ("Caps on the %s pad are not raw video", video ? "video" : "depth"),
                          ("%" GST_PTR_FORMAT, caps));
        gst_event_unref(event);
        return FALSE;
      }
      if (video) {
        if (GST_VIDEO_INFO_INTERLACE_MODE(&info) != GST_VIDEO_INTERLACE_MODE_PROGRESSIVE) {
          GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, ("Interlaced video is not supported"),
                            ("deinterlace it first: %" GST_PTR_FORMAT, caps));
          gst_event_unref(event);
          return FALSE;
        }
        self->video_info = info;
        self->have_video_info = TRUE;
        gst_aggregator_set_src_caps(agg, caps);
      } else {
        self->depth_info = info;
        self->have_depth_info = TRUE;
      }
      break;
    }
    case GST_EVENT_SEGMENT:
      if (pad == self->video_pad) {
        const GstSegment *segment;
        gst_event_parse_segment(event, &segment);
        gst_aggregator_update_segment(agg, segment);
      }
      break;
    default: break;
  }
  return GST_AGGREGATOR_CLASS(parent_class)->sink_event(agg, pad, event);
}

// A caps query on one side of the video passage: what the peer of `pad`
// (the other side) takes, within the template.
static gboolean answer_caps_from_peer(GstPad *pad, GstQuery *query) {
  GstCaps *filter = nullptr, *templ = video_template_caps();
  gst_query_parse_caps(query, &filter);
  GstCaps *peer_filter = filter ? gst_caps_intersect_full(filter, templ, GST_CAPS_INTERSECT_FIRST) : gst_caps_ref(templ);
  GstCaps *peer = gst_pad_peer_query_caps(pad, peer_filter);
  GstCaps *result = gst_caps_intersect_full(peer, templ, GST_CAPS_INTERSECT_FIRST);
  gst_query_set_caps_result(query, result);
  gst_caps_unref(result);
  gst_caps_unref(peer);
  gst_caps_unref(peer_filter);
  gst_caps_unref(templ);
  return TRUE;
}

// The video pad is a passage: its caps, allocation and the like are
// downstream's (within the template); the depth pad answers from its template.
static gboolean gst_pseudo3d_depth_mux_sink_query(GstAggregator *agg, GstAggregatorPad *pad, GstQuery *query) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(agg);
  GstPad *srcpad = GST_AGGREGATOR_SRC_PAD(agg);
  if (pad == self->video_pad) {
    switch (GST_QUERY_TYPE(query)) {
      case GST_QUERY_CAPS: return answer_caps_from_peer(srcpad, query);
      case GST_QUERY_ACCEPT_CAPS:
      case GST_QUERY_ALLOCATION:
      case GST_QUERY_POSITION:
      case GST_QUERY_DURATION:
      case GST_QUERY_URI: return gst_pad_peer_query(srcpad, query);
      default: break;
    }
  }
  return GST_AGGREGATOR_CLASS(parent_class)->sink_query(agg, pad, query);
}

static gboolean gst_pseudo3d_depth_mux_src_query(GstAggregator *agg, GstQuery *query) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(agg);
  switch (GST_QUERY_TYPE(query)) {
    case GST_QUERY_CAPS: return answer_caps_from_peer(GST_PAD(self->video_pad), query);
    case GST_QUERY_POSITION:
    case GST_QUERY_DURATION:
    case GST_QUERY_URI:
    case GST_QUERY_SEEKING: return gst_pad_peer_query(GST_PAD(self->video_pad), query);
    default: return GST_AGGREGATOR_CLASS(parent_class)->src_query(agg, query);
  }
}

static GstFlowReturn gst_pseudo3d_depth_mux_flush(GstAggregator *agg) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(agg);
  // Kept, for a still depth picture that is not sent again; a depth stream
  // that is sent again after the seek replaces it with its first picture.
  self->depth_stale = self->depth != nullptr;
  return GST_FLOW_OK;
}

static void forget_depth(GstPseudo3DDepthMux *self) {
  gst_buffer_replace(&self->depth, nullptr);
  self->depth_stale = FALSE;
  self->warned_unlinked = FALSE;
  self->have_video_info = self->have_depth_info = FALSE;
  self->state->plane.reset();
  self->state->plane_source = nullptr;
  self->state->pool.clear();
  self->state->have_valid_range = false;
  self->state->warned_invalid_range = false;
}

static gboolean gst_pseudo3d_depth_mux_stop(GstAggregator *agg) {
  forget_depth(GST_PSEUDO3D_DEPTH_MUX(agg));
  return TRUE;
}

static void gst_pseudo3d_depth_mux_set_property(GObject *object, guint prop_id, const GValue *value,
                                                GParamSpec *pspec) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_CONVENTION: self->params.convention = static_cast<p3d::DepthConvention>(g_value_get_enum(value)); break;
    case PROP_NEAR: self->params.near = g_value_get_float(value); break;
    case PROP_FAR: self->params.far = g_value_get_float(value); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_depth_mux_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_CONVENTION: g_value_set_enum(value, static_cast<gint>(self->params.convention)); break;
    case PROP_NEAR: g_value_set_float(value, self->params.near); break;
    case PROP_FAR: g_value_set_float(value, self->params.far); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_depth_mux_finalize(GObject *object) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(object);
  gst_buffer_replace(&self->depth, nullptr);
  delete self->state;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_depth_mux_class_init(GstPseudo3DDepthMuxClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstAggregatorClass *agg_class = GST_AGGREGATOR_CLASS(klass);
  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_depth_mux_debug, "pseudo3ddepthmux", 0, "pseudo3d external depth");

  gobject_class->set_property = gst_pseudo3d_depth_mux_set_property;
  gobject_class->get_property = gst_pseudo3d_depth_mux_get_property;
  gobject_class->finalize = gst_pseudo3d_depth_mux_finalize;

  const p3d::DepthImportParams d;
  const GParamFlags flags =
      static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);
  g_object_class_install_property(
      gobject_class, PROP_CONVENTION,
      g_param_spec_enum("convention", "Depth convention", "How the depth pad's grey values mean depth",
                        GST_TYPE_PSEUDO3D_DEPTH_CONVENTION, static_cast<gint>(d.convention), flags));
  g_object_class_install_property(
      gobject_class, PROP_NEAR,
      g_param_spec_float("near", "Near distance",
                         "convention=metric: the distance (in the depth's unit) that is nearest; nearer is clamped",
                         1e-6f, 1e9f, d.near, flags));
  g_object_class_install_property(
      gobject_class, PROP_FAR,
      g_param_spec_float("far", "Far distance",
                         "convention=metric: the distance (in the depth's unit) that is farthest; farther is "
                         "clamped. Must be above near (while playing, an invalid pair keeps the last valid one)",
                         1e-6f, 1e9f, d.far, flags));

  gst_element_class_set_static_metadata(element_class, "pseudo3d external depth", "Filter/Video",
                                        "Attaches depth from a second stream (grey pictures: a depth camera, a "
                                        "depth file, a depth model) to each frame for pseudo-stereo rendering",
                                        "pseudo3d developers");
  GstCaps *video = video_template_caps(), *depth = depth_template_caps();
  gst_element_class_add_pad_template(
      element_class, gst_pad_template_new_with_gtype("video", GST_PAD_SINK, GST_PAD_ALWAYS, video, GST_TYPE_AGGREGATOR_PAD));
  gst_element_class_add_pad_template(
      element_class, gst_pad_template_new_with_gtype("depth", GST_PAD_SINK, GST_PAD_ALWAYS, depth, GST_TYPE_AGGREGATOR_PAD));
  gst_element_class_add_pad_template(
      element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, video));
  gst_caps_unref(video);
  gst_caps_unref(depth);

  agg_class->aggregate = gst_pseudo3d_depth_mux_aggregate;
  agg_class->sink_event = gst_pseudo3d_depth_mux_sink_event;
  agg_class->sink_query = gst_pseudo3d_depth_mux_sink_query;
  agg_class->src_query = gst_pseudo3d_depth_mux_src_query;
  agg_class->flush = gst_pseudo3d_depth_mux_flush;
  agg_class->stop = gst_pseudo3d_depth_mux_stop;
  agg_class->negotiate = nullptr;  // src caps are the video pad's (set_src_caps)
  agg_class->get_next_time = gst_aggregator_simple_get_next_time;
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_DEPTH_CONVENTION, static_cast<GstPluginAPIFlags>(0));
}

static GstAggregatorPad *new_sink_pad(GstPseudo3DDepthMux *self, const char *name) {
  GstPadTemplate *templ = gst_element_class_get_pad_template(GST_ELEMENT_GET_CLASS(self), name);
  auto *pad = static_cast<GstAggregatorPad *>(
      g_object_new(GST_TYPE_AGGREGATOR_PAD, "name", name, "direction", GST_PAD_SINK, "template", templ, NULL));
  gst_element_add_pad(GST_ELEMENT(self), GST_PAD(pad));
  return pad;
}

// A frame reaching the video pad while nothing is linked to the depth pad
// waits for depth that cannot come (GstAggregator does not call aggregate()
// until every pad has data): say so once, as a warning, since a depth
// branch that links late (decodebin's pads) is still welcome.
static GstPadProbeReturn warn_if_depth_unlinked(GstPad *, GstPadProbeInfo *, gpointer data) {
  GstPseudo3DDepthMux *self = GST_PSEUDO3D_DEPTH_MUX(data);
  if (!self->warned_unlinked && !gst_pad_is_linked(GST_PAD(self->depth_pad))) {
    self->warned_unlinked = TRUE;
    GST_ELEMENT_WARNING(self, CORE, PAD, ("The depth pad is not linked: the frames wait for depth"),
                        ("link a depth stream to the depth pad (one still picture serves a whole video), or use "
                         "pseudo3ddepth to estimate depth from the frames"));
  }
  return GST_PAD_PROBE_OK;
}

static void gst_pseudo3d_depth_mux_init(GstPseudo3DDepthMux *self) {
  self->state = new MuxState();
  self->params = p3d::DepthImportParams();
  self->video_pad = new_sink_pad(self, "video");
  self->depth_pad = new_sink_pad(self, "depth");
  gst_pad_add_probe(GST_PAD(self->video_pad), GST_PAD_PROBE_TYPE_BUFFER, warn_if_depth_unlinked, self, nullptr);
}
