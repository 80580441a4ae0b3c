/**
 * SECTION:element-pseudo3dconvert
 * @title: pseudo3dconvert
 *
 * The whole 2D-to-3D chain in one element: pseudo3ddepth ! pseudo3dfilter !
 * pseudo3dwarp, the warp packing its views into the layout itself (its
 * layout, glasses, anaglyph-method and swap-eyes are pseudo3dpack's), and
 * exposing the stages' main properties under the same names. On the GPU
 * an anaglyph is then rendered in one pass with the views (see
 * pseudo3dwarp). Usable wherever one video filter is expected, such as
 * playbin's video-filter.
 *
 * Interlaced video is deinterlaced in front of the stages (GStreamer's
 * deinterlace, when gst-plugins-good is installed, in its defaults: a
 * frame for each field, so 1080i50 comes out as 1080p50, the missing lines
 * interpolated; progressive frames pass it untouched). It deinterlaces
 * system memory; interlaced video in CUDA memory is refused with a message.
 * For another mode (frame rate, a motion-adaptive method), put your own
 * deinterlace before the element.
 *
 * With processing=auto (default) and a CUDA device with nvcodec's
 * cudaupload/cudadownload available, the chain is wrapped as cudaupload !
 * ... ! cudadownload: system-memory video is uploaded once, every stage runs
 * on the GPU with the frames kept in device memory, and the result is
 * downloaded once (CUDA-memory input and output pass through the two
 * untouched). Otherwise the stages run on the CPU. The choice is made when
 * the element goes from NULL to READY.
 *
 * On the CPU each stage computes only what changed since the previous
 * frame (adaptive=true, the default, byte for byte the output of
 * adaptive=false): a still picture or a paused video costs a comparison a
 * frame. reuse-tolerance trades error for time on camera video.
 *
 * ## Example launch lines
 * |[
 * gst-launch-1.0 playbin uri=file:///path/movie.mp4 video-filter="pseudo3dconvert layout=anaglyph"
 * gst-launch-1.0 videotestsrc ! pseudo3dconvert layout=side-by-side-half ! videoconvert ! autovideosink
 * ]|
 */
#include "gstpseudo3dconvert.h"

#include "config.h"

#include <gst/video/video.h>
#include "enums.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudaloader.h>
#endif

#include "gstpseudo3ddepth.h"
#include "gstpseudo3dfilter.h"
#include "gstpseudo3dwarp.h"
#include "property_guard.h"
#include "pspec_clone.h"
#include "stereo_packing.h"

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_convert_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_convert_debug

enum Stage { STAGE_DEPTH, STAGE_FILTER, STAGE_WARP, N_STAGES };

// The proxied properties: property id - 1 indexes this table.
static const struct {
  Stage stage;
  const char *name;
} kProxied[] = {
    {STAGE_DEPTH, "method"},          {STAGE_DEPTH, "hypothesis"},      {STAGE_DEPTH, "temporal-smoothing"},
    {STAGE_DEPTH, "crop-bars"},
    {STAGE_FILTER, "radius"},         {STAGE_FILTER, "sigma-space"},    {STAGE_FILTER, "sigma-range"},
    {STAGE_FILTER, "scale"},
    {STAGE_WARP, "max-disparity"},    {STAGE_WARP, "convergence"},      {STAGE_WARP, "view"},
    {STAGE_WARP, "fill"},             {STAGE_WARP, "layout"},           {STAGE_WARP, "glasses"},
    {STAGE_WARP, "anaglyph-method"},  {STAGE_WARP, "swap-eyes"},
};
#define PROP_CUDA_DEVICE_ID (G_N_ELEMENTS(kProxied) + 1)
#define PROP_PROCESSING (G_N_ELEMENTS(kProxied) + 2)
// The stage properties that every stage has and the bin sets on all of them.
static const char *const kEveryStage[] = {"adaptive", "reuse-tolerance"};
#define PROP_EVERY_STAGE (G_N_ELEMENTS(kProxied) + 3)
#define DEFAULT_PROCESSING GST_PSEUDO3D_PROCESSING_AUTO

struct _GstPseudo3DConvert {
  GstBin parent;
  GstElement *deinterlace; /* the bin's first element; null without gst-plugins-good */
  GstElement *stage[N_STAGES];
  GstElement *upload, *to_cuda, *download; /* present while the chain runs on the GPU */
  GstPad *sinkpad, *srcpad;       /* ghost pads */
  GstPseudo3DProcessing processing;
  gint device_id;
};

#define gst_pseudo3d_convert_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DConvert, gst_pseudo3d_convert, GST_TYPE_BIN);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dconvert, "pseudo3dconvert", GST_RANK_NONE, GST_TYPE_PSEUDO3D_CONVERT);

static void gst_pseudo3d_convert_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DConvert *self = GST_PSEUDO3D_CONVERT(object);
  if (!p3d::gst::property_settable(GST_ELEMENT(self), pspec)) return;
  if (prop_id == PROP_CUDA_DEVICE_ID) {
    self->device_id = g_value_get_int(value);
    for (GstElement *e : self->stage) g_object_set_property(G_OBJECT(e), "cuda-device-id", value);
  } else if (prop_id == PROP_PROCESSING) {
    self->processing = static_cast<GstPseudo3DProcessing>(g_value_get_enum(value));
    for (GstElement *e : self->stage) g_object_set_property(G_OBJECT(e), "processing", value);
  } else if (prop_id >= 1 && prop_id <= G_N_ELEMENTS(kProxied)) {
    g_object_set_property(G_OBJECT(self->stage[kProxied[prop_id - 1].stage]), kProxied[prop_id - 1].name, value);
  } else if (prop_id >= PROP_EVERY_STAGE && prop_id < PROP_EVERY_STAGE + G_N_ELEMENTS(kEveryStage)) {
    for (GstElement *e : self->stage) g_object_set_property(G_OBJECT(e), kEveryStage[prop_id - PROP_EVERY_STAGE], value);
  } else {
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
  }
}

static void gst_pseudo3d_convert_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DConvert *self = GST_PSEUDO3D_CONVERT(object);
  if (prop_id == PROP_CUDA_DEVICE_ID) {
    g_object_get_property(G_OBJECT(self->stage[STAGE_DEPTH]), "cuda-device-id", value);
  } else if (prop_id == PROP_PROCESSING) {
    g_value_set_enum(value, self->processing);
  } else if (prop_id >= 1 && prop_id <= G_N_ELEMENTS(kProxied)) {
    g_object_get_property(G_OBJECT(self->stage[kProxied[prop_id - 1].stage]), kProxied[prop_id - 1].name, value);
  } else if (prop_id >= PROP_EVERY_STAGE && prop_id < PROP_EVERY_STAGE + G_N_ELEMENTS(kEveryStage)) {
    g_object_get_property(G_OBJECT(self->stage[STAGE_DEPTH]), kEveryStage[prop_id - PROP_EVERY_STAGE], value);
  } else {
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
  }
}

// Whether cudaupload/cudadownload can run here: nvcodec registers them only
// when a CUDA device was found.
static gboolean gpu_available(void) {
#if HAVE_CUDA
  if (!gst_cuda_load_library()) return FALSE;
  GstElementFactory *up = gst_element_factory_find("cudaupload");
  GstElementFactory *down = gst_element_factory_find("cudadownload");
  const gboolean ok = up && down;
  if (up) gst_object_unref(up);
  if (down) gst_object_unref(down);
  return ok;
#else
  return FALSE;
#endif
}

// Puts the stages between cudaupload and cudadownload, or takes those out.
static gboolean configure_processing(GstPseudo3DConvert *self) {
  const gboolean want_gpu = self->processing != GST_PSEUDO3D_PROCESSING_CPU && gpu_available();
  if (self->processing == GST_PSEUDO3D_PROCESSING_GPU && !want_gpu) {
    GST_ELEMENT_ERROR(self, RESOURCE, NOT_FOUND, ("processing=gpu but no CUDA device or no cudaupload/cudadownload"),
                      ("install gstreamer1.0-plugins-bad (nvcodec) and an NVIDIA driver, or use processing=auto"));
    return FALSE;
  }
  GstElement *first = self->stage[STAGE_DEPTH], *last = self->stage[STAGE_WARP];
  if (want_gpu && !self->upload) {
    self->upload = gst_element_factory_make("cudaupload", "upload");
    self->to_cuda = gst_element_factory_make("capsfilter", "to_cuda");
    self->download = gst_element_factory_make("cudadownload", "download");
    if (!self->upload || !self->to_cuda || !self->download) {
      gst_clear_object(&self->upload);
      gst_clear_object(&self->to_cuda);
      gst_clear_object(&self->download);
      return self->processing != GST_PSEUDO3D_PROCESSING_GPU;
    }
    // cudaupload also offers system memory: insist on device memory after it.
    GstCaps *cuda_caps = gst_caps_from_string("video/x-raw(memory:CUDAMemory)");
    g_object_set(self->to_cuda, "caps", cuda_caps, NULL);
    gst_caps_unref(cuda_caps);
    if (self->deinterlace) gst_element_unlink(self->deinterlace, first);
    g_object_set(self->upload, "cuda-device-id", self->device_id, NULL);
    g_object_set(self->download, "cuda-device-id", self->device_id, NULL);
    gst_bin_add_many(GST_BIN(self), self->upload, self->to_cuda, self->download, NULL);
    // Retarget the ghost pads first: a ghost pad's target is linked to it.
    GstPad *out = gst_element_get_static_pad(self->download, "src");
    gboolean retargeted = gst_ghost_pad_set_target(GST_GHOST_PAD(self->srcpad), out);
    if (!self->deinterlace) {
      GstPad *in = gst_element_get_static_pad(self->upload, "sink");
      retargeted = retargeted && gst_ghost_pad_set_target(GST_GHOST_PAD(self->sinkpad), in);
      gst_object_unref(in);
    }
    gst_object_unref(out);
    if (!retargeted || (self->deinterlace && !gst_element_link(self->deinterlace, self->upload)) ||
        !gst_element_link_many(self->upload, self->to_cuda, first, NULL) || !gst_element_link(last, self->download)) {
      GST_ELEMENT_ERROR(self, CORE, NEGOTIATION, ("Could not put the stages between cudaupload and cudadownload"),
                        (nullptr));
      return FALSE;
    }
    GST_INFO_OBJECT(self, "processing on the GPU (cudaupload ! stages ! cudadownload)");
  } else if (!want_gpu && self->upload) {
    if (self->deinterlace) gst_element_unlink(self->deinterlace, self->upload);
    gst_element_unlink_many(self->upload, self->to_cuda, first, NULL);
    gst_element_unlink(last, self->download);
    GstPad *out = gst_element_get_static_pad(last, "src");
    gst_ghost_pad_set_target(GST_GHOST_PAD(self->srcpad), out);
    gst_object_unref(out);
    if (self->deinterlace) {
      gst_element_link(self->deinterlace, first);
    } else {
      GstPad *in = gst_element_get_static_pad(first, "sink");
      gst_ghost_pad_set_target(GST_GHOST_PAD(self->sinkpad), in);
      gst_object_unref(in);
    }
    gst_bin_remove_many(GST_BIN(self), self->upload, self->to_cuda, self->download, NULL);
    self->upload = self->to_cuda = self->download = nullptr;
    GST_INFO_OBJECT(self, "processing on the CPU");
  }
  return TRUE;
}

static GstStateChangeReturn gst_pseudo3d_convert_change_state(GstElement *element, GstStateChange transition) {
  GstPseudo3DConvert *self = GST_PSEUDO3D_CONVERT(element);
  if (transition == GST_STATE_CHANGE_NULL_TO_READY && !configure_processing(self)) return GST_STATE_CHANGE_FAILURE;
  return GST_ELEMENT_CLASS(parent_class)->change_state(element, transition);
}

static void gst_pseudo3d_convert_class_init(GstPseudo3DConvertClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  gobject_class->set_property = gst_pseudo3d_convert_set_property;
  gobject_class->get_property = gst_pseudo3d_convert_get_property;

  const GType stage_types[N_STAGES] = {GST_TYPE_PSEUDO3D_DEPTH, GST_TYPE_PSEUDO3D_FILTER, GST_TYPE_PSEUDO3D_WARP};
  for (guint i = 0; i < G_N_ELEMENTS(kProxied); ++i) {
    // The pack's properties, which the warp takes, keep pseudo3dpack's
    // documentation and defaults (layout: anaglyph, where the warp's own
    // default is the pair itself); the stage gets them at init.
    GParamSpec *p = kProxied[i].stage == STAGE_WARP ? p3d::gst::pack_property_spec(kProxied[i].name) : nullptr;
    if (!p) {
      auto *stage_class = static_cast<GObjectClass *>(g_type_class_ref(stage_types[kProxied[i].stage]));
      p = p3d::gst::clone_pspec(g_object_class_find_property(stage_class, kProxied[i].name));
      g_type_class_unref(stage_class);
    }
    g_object_class_install_property(gobject_class, i + 1, p);
  }
  auto *depth_class = static_cast<GObjectClass *>(g_type_class_ref(GST_TYPE_PSEUDO3D_DEPTH));
  g_object_class_install_property(gobject_class, PROP_CUDA_DEVICE_ID,
                                  p3d::gst::clone_pspec(g_object_class_find_property(depth_class, "cuda-device-id")));
  for (guint i = 0; i < G_N_ELEMENTS(kEveryStage); ++i)
    g_object_class_install_property(gobject_class, PROP_EVERY_STAGE + i,
                                    p3d::gst::clone_pspec(g_object_class_find_property(depth_class, kEveryStage[i])));
  g_type_class_unref(depth_class);
  g_object_class_install_property(
      gobject_class, PROP_PROCESSING,
      g_param_spec_enum("processing", "Processing",
                        "Where system-memory video is processed: auto puts the chain between cudaupload and "
                        "cudadownload when a CUDA device is available; read when going from NULL to READY",
                        GST_TYPE_PSEUDO3D_PROCESSING, DEFAULT_PROCESSING,
                        (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_READY)));
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_PROCESSING, (GstPluginAPIFlags)0);
  element_class->change_state = GST_DEBUG_FUNCPTR(gst_pseudo3d_convert_change_state);

  gst_element_class_set_static_metadata(element_class, "pseudo3d 2D-to-3D conversion", "Filter/Effect/Video",
                                        "Turns 2D video into stereo 3D: depth estimation, depth filtering, view "
                                        "synthesis and stereo packing in one element",
                                        "pseudo3d developers");
  GstElementClass *depth_eclass = GST_ELEMENT_CLASS(g_type_class_ref(GST_TYPE_PSEUDO3D_DEPTH));
  GstElementClass *warp_eclass = GST_ELEMENT_CLASS(g_type_class_ref(GST_TYPE_PSEUDO3D_WARP));
  gst_element_class_add_pad_template(
      element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS,
                                          gst_pad_template_get_caps(gst_element_class_get_pad_template(depth_eclass, "sink"))));
  gst_element_class_add_pad_template(
      element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS,
                                          gst_pad_template_get_caps(gst_element_class_get_pad_template(warp_eclass, "src"))));
  g_type_class_unref(depth_eclass);
  g_type_class_unref(warp_eclass);
  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_convert_debug, "pseudo3dconvert", 0, "pseudo3d conversion bin");
}

static void gst_pseudo3d_convert_init(GstPseudo3DConvert *self) {
  const char *factories[N_STAGES] = {"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp"};
  for (int i = 0; i < N_STAGES; ++i) {
    self->stage[i] = gst_element_factory_make(factories[i], factories[i] + 8);  // "depth", "filter", ...
    gst_pseudo3d_base_set_hidden_in_parent(GST_PSEUDO3D_BASE(self->stage[i]), TRUE);
    gst_bin_add(GST_BIN(self), self->stage[i]);
  }
  gst_element_link_many(self->stage[0], self->stage[1], self->stage[2], NULL);
  // Interlaced video is deinterlaced in front of the stages, which take
  // progressive frames only: GStreamer's deinterlace in its defaults
  // (mode auto: progressive frames pass through untouched; every field
  // becomes a frame, so 1080i50 comes out as 1080p50; linear
  // interpolation of the missing lines). It deinterlaces system memory;
  // on CUDA memory it passes frames through, and the depth stage refuses
  // interlaced ones with its message.
  self->deinterlace = gst_element_factory_make("deinterlace", "deinterlace");
  if (self->deinterlace) {
    gst_bin_add(GST_BIN(self), self->deinterlace);
    gst_element_link(self->deinterlace, self->stage[STAGE_DEPTH]);
  }
  // The stages start at the bin's defaults (the pack's, for the warp's
  // layout: anaglyph).
  for (guint i = 0; i < G_N_ELEMENTS(kProxied); ++i) {
    GParamSpec *p = g_object_class_find_property(G_OBJECT_GET_CLASS(self), kProxied[i].name);
    GValue v = G_VALUE_INIT;
    g_value_init(&v, p->value_type);
    g_param_value_set_default(p, &v);
    g_object_set_property(G_OBJECT(self->stage[kProxied[i].stage]), kProxied[i].name, &v);
    g_value_unset(&v);
  }
  GstPad *sink = gst_element_get_static_pad(self->deinterlace ? self->deinterlace : self->stage[STAGE_DEPTH], "sink");
  GstPad *src = gst_element_get_static_pad(self->stage[STAGE_WARP], "src");
  GstElementClass *klass = GST_ELEMENT_GET_CLASS(self);
  self->sinkpad = gst_ghost_pad_new_from_template("sink", sink, gst_element_class_get_pad_template(klass, "sink"));
  self->srcpad = gst_ghost_pad_new_from_template("src", src, gst_element_class_get_pad_template(klass, "src"));
  gst_element_add_pad(GST_ELEMENT(self), self->sinkpad);
  gst_element_add_pad(GST_ELEMENT(self), self->srcpad);
  self->processing = DEFAULT_PROCESSING;
  self->device_id = -1;
  gst_object_unref(sink);
  gst_object_unref(src);
}
