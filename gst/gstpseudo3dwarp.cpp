/**
 * SECTION:element-pseudo3dwarp
 * @title: pseudo3dwarp
 *
 * Depth-image-based rendering: renders a left and a right view from each
 * frame and its depth map (attached by pseudo3ddepth or pseudo3dfilter) by
 * forward warping with depth ordering (the nearer surface wins, sub-pixel
 * accurate), then fills the disocclusion holes from the background side. The
 * output is one full-resolution side-by-side frame (2W x H,
 * multiview-mode=side-by-side) in a packed RGB format, ready for
 * pseudo3dpack.
 *
 * Parallax of a pixel is max-disparity% x width x (depth - convergence):
 * depth above the convergence plane comes out of the screen.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 videotestsrc ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp max-disparity=4 convergence=0.4 ! pseudo3dpack layout=side-by-side-half ! videoconvert ! autovideosink
 * ]|
 */
#include "gstpseudo3dwarp.h"

#include "depth_meta.h"
#include "enums.h"
#include "video_util.h"
#include "warp.h"

#if HAVE_CUDA
#include "warp_gpu.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_warp_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_warp_debug

enum { PROP_0, PROP_MAX_DISPARITY, PROP_CONVERGENCE, PROP_VIEW, PROP_FILL };

struct WarpState {
  p3d::WarpCpuScratch cpu;  // the CPU path's planes, reused frame to frame (streaming thread only)
#if HAVE_CUDA
  p3d::WarpRendererGpu gpu;
#endif
};

struct _GstPseudo3DWarp {
  GstPseudo3DBase parent;
  p3d::WarpParams params;
  WarpState *state;
};

#define gst_pseudo3d_warp_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DWarp, gst_pseudo3d_warp, GST_TYPE_PSEUDO3D_BASE);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dwarp, "pseudo3dwarp", GST_RANK_NONE, GST_TYPE_PSEUDO3D_WARP);

// Output: the two views side by side (2W x H), signalled as a full-size,
// left-first side-by-side pair; the pixel aspect ratio is the input's.
static GstCaps *transform_geometry(GstPseudo3DBase *, GstPadDirection from, const GstStructure *in) {
  GstStructure *s = gst_structure_copy(in);
  if (from == GST_PAD_SINK) {
    gst_pseudo3d_scale_field(s, "width", 2, 1);
    gst_structure_set(s, "multiview-mode", G_TYPE_STRING, "side-by-side", "multiview-flags",
                      GST_TYPE_VIDEO_MULTIVIEW_FLAGSET, 0, GST_FLAG_SET_MASK_EXACT, "views", G_TYPE_INT, 2, NULL);
  } else {
    gst_pseudo3d_scale_field(s, "width", 1, 2);
    gst_structure_remove_fields(s, "multiview-mode", "multiview-flags", "views", NULL);
  }
  return gst_pseudo3d_caps_of(s);
}

static gboolean set_info(GstPseudo3DBase *base, GstCaps *, GstVideoInfo *in, GstCaps *, GstVideoInfo *out) {
  if (GST_VIDEO_INFO_WIDTH(out) != 2 * GST_VIDEO_INFO_WIDTH(in) || GST_VIDEO_INFO_HEIGHT(out) != GST_VIDEO_INFO_HEIGHT(in)) {
    return gst_pseudo3d_base_refuse_caps(base, "The output must be twice as wide as the input",
                                         "input %dx%d, output %dx%d", GST_VIDEO_INFO_WIDTH(in),
                                         GST_VIDEO_INFO_HEIGHT(in), GST_VIDEO_INFO_WIDTH(out),
                                         GST_VIDEO_INFO_HEIGHT(out));
  }
  return TRUE;
}

static GstFlowReturn process(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *inbuf, GstVideoFrame *in,
                             GstVideoFrame *out) {
  GstPseudo3DWarp *self = GST_PSEUDO3D_WARP(base);
  const p3d::FrameView src = p3d::gst::frame_view(in);
  p3d::gst::DepthPlane *depth = gst_pseudo3d_base_frame_depth(base, inbuf, path, src.width, src.height);
  if (!depth) return GST_FLOW_ERROR;
  GST_OBJECT_LOCK(self);
  const p3d::WarpParams params = self->params;
  GST_OBJECT_UNLOCK(self);
  const p3d::YuvToRgb yuv = p3d::gst::yuv_params(&base->in_info);
  const p3d::FrameView dst = p3d::gst::frame_view(out);
#if HAVE_CUDA
  if (path != GST_PSEUDO3D_PATH_CPU) {
    using p3d::gst::GpuStaging;
    return p3d::gst::run_gpu(base, "rendering the views", [&]() -> p3d::CudaStatus {
      p3d::FrameView fin, fout;
      p3d::DepthGrid<float> d;
      P3D_CUDA_TRY_STATUS(p3d::gst::device_frame(base, path, GpuStaging::kInput, src, true, &fin));
      P3D_CUDA_TRY_STATUS(p3d::gst::device_depth(base, path, GpuStaging::kInput, depth->grid(), true, &d));
      P3D_CUDA_TRY_STATUS(p3d::gst::device_frame(base, path, GpuStaging::kOutput, dst, false, &fout));
      P3D_CUDA_TRY_STATUS(self->state->gpu.render(params, fin, yuv, p3d::as_const(d), fout, base->gpu->stream()));
      return p3d::gst::frame_to_host(base, path, fout, dst);
    });
  }
#endif
  const long long holes = p3d::warp_render_cpu(params, src, yuv, p3d::as_const(depth->view()), dst, self->state->cpu);
  if (holes < 0) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Frames do not fit the warp"),
                      ("input %dx%d, output %dx%d", src.width, src.height, dst.width, dst.height));
    return GST_FLOW_ERROR;
  }
  GST_LOG_OBJECT(self, "%lld hole pixels filled", holes);
  return GST_FLOW_OK;
}

static void release(GstPseudo3DBase *base) {
#if HAVE_CUDA
  GST_PSEUDO3D_WARP(base)->state->gpu = p3d::WarpRendererGpu();
#else
  (void)base;
#endif
}

static void gst_pseudo3d_warp_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DWarp *self = GST_PSEUDO3D_WARP(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_MAX_DISPARITY: self->params.max_disparity = g_value_get_float(value); break;
    case PROP_CONVERGENCE: self->params.convergence = g_value_get_float(value); break;
    case PROP_VIEW: self->params.view = static_cast<p3d::StereoView>(g_value_get_enum(value)); break;
    case PROP_FILL: self->params.fill = static_cast<p3d::HoleFill>(g_value_get_enum(value)); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_warp_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DWarp *self = GST_PSEUDO3D_WARP(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_MAX_DISPARITY: g_value_set_float(value, self->params.max_disparity); break;
    case PROP_CONVERGENCE: g_value_set_float(value, self->params.convergence); break;
    case PROP_VIEW: g_value_set_enum(value, static_cast<gint>(self->params.view)); break;
    case PROP_FILL: g_value_set_enum(value, static_cast<gint>(self->params.fill)); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_warp_finalize(GObject *object) {
  delete GST_PSEUDO3D_WARP(object)->state;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_warp_class_init(GstPseudo3DWarpClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstPseudo3DBaseClass *base_class = GST_PSEUDO3D_BASE_CLASS(klass);
  const p3d::WarpParams d;
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);

  gobject_class->set_property = gst_pseudo3d_warp_set_property;
  gobject_class->get_property = gst_pseudo3d_warp_get_property;
  gobject_class->finalize = gst_pseudo3d_warp_finalize;

  g_object_class_install_property(
      gobject_class, PROP_MAX_DISPARITY,
      g_param_spec_float("max-disparity", "Maximum disparity",
                         "Parallax between depth 0 and depth 1, in percent of the frame width (0 = no depth effect: "
                         "both views are the input)",
                         0.f, p3d::kMaxDisparityPercent, d.max_disparity, flags));
  g_object_class_install_property(
      gobject_class, PROP_CONVERGENCE,
      g_param_spec_float("convergence", "Convergence",
                         "Depth (0 = far, 1 = near) that lands on the screen plane: nearer comes out of the "
                         "screen, farther goes behind it",
                         0.f, 1.f, d.convergence, flags));
  g_object_class_install_property(
      gobject_class, PROP_VIEW,
      g_param_spec_enum("view", "Synthesized view",
                        "Which views are rendered: both (half the parallax each, symmetric holes), or only the "
                        "right (input = left view) or the left (input = right view)",
                        GST_TYPE_PSEUDO3D_VIEW, static_cast<gint>(d.view), flags));
  g_object_class_install_property(
      gobject_class, PROP_FILL,
      g_param_spec_enum("fill", "Hole filling",
                        "How disocclusion holes are filled", GST_TYPE_PSEUDO3D_FILL, static_cast<gint>(d.fill), flags));

  gst_element_class_set_static_metadata(element_class, "pseudo3d DIBR view synthesis", "Filter/Effect/Video",
                                        "Renders left and right views from a frame and its depth map, side by side",
                                        "pseudo3d developers");
  GstCaps *sink = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, p3d::kMaxFrameSide);
  GstCaps *src = p3d::gst::caps_all_domains(P3D_PACKED_FORMATS, 2 * p3d::kMaxFrameSide,
                                            ", multiview-mode=(string)side-by-side");
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, sink));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, src));
  gst_caps_unref(sink);
  gst_caps_unref(src);

  base_class->src_formats = P3D_PACKED_FORMATS;
  base_class->sink_formats = P3D_ALL_FORMATS;
  base_class->transform_geometry = transform_geometry;
  base_class->set_info = set_info;
  base_class->process = process;
  base_class->release = release;

  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_warp_debug, "pseudo3dwarp", 0, "pseudo3d DIBR view synthesis");
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_VIEW, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_FILL, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_warp_init(GstPseudo3DWarp *self) {
  self->params = p3d::WarpParams();
  self->state = new WarpState();
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), FALSE);
}
