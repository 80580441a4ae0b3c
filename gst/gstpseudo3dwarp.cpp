/**
 * SECTION:element-pseudo3dwarp
 * @title: pseudo3dwarp
 *
 * Depth-image-based rendering: renders a left and a right view from each
 * frame and its depth map (attached by pseudo3ddepth or pseudo3dfilter) by
 * forward warping with depth ordering (the nearer surface wins, sub-pixel
 * accurate), then fills the disocclusion holes from the background side.
 *
 * By default (layout=side-by-side) the output is the pair itself, one
 * full-resolution side-by-side frame (2W x H, multiview-mode=side-by-side)
 * in a packed RGB format, ready for pseudo3dpack. With another layout the
 * element packs the pair itself, as pseudo3dpack would (the same layouts,
 * glasses, anaglyph methods, swap-eyes, multiview signalling and NV12/I420
 * output for encoders), and on the GPU an anaglyph is rendered in one pass
 * with the views where it can be: the row kernel writes the anaglyph pixels
 * itself, and the full pair never goes through memory (docs/benchmarks.md,
 * "Fused pack"). pseudo3dconvert packs this way. The views keep the input's
 * transfer and primaries, which the output caps state (R'G'B' with the
 * input's transfer and primaries; 4:2:0 as pseudo3dpack writes it), and
 * an anaglyph of PQ or HLG input is refused, as pseudo3dpack refuses it.
 *
 * 10-bit input (P010_10LE, I420_10LE) and RGBA64_LE are rendered with 16
 * bits a sample, into RGBA64_LE, or P010_10LE/I420_10LE for encoders: the
 * output keeps the input's depth. On CUDA memory (which holds no
 * RGBA64_LE) 10-bit input is packed into P010_10LE or I420_10LE.
 *
 * Parallax of a pixel is max-disparity% x width x (depth - convergence):
 * depth above the convergence plane comes out of the screen.
 *
 * Every property can be changed while playing; a layout or swap-eyes change
 * that alters the output caps is renegotiated before the next frame.
 *
 * ## Example launch lines
 * |[
 * gst-launch-1.0 videotestsrc ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp max-disparity=4 convergence=0.4 ! pseudo3dpack layout=side-by-side-half ! videoconvert ! autovideosink
 * gst-launch-1.0 videotestsrc ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp layout=anaglyph ! videoconvert ! autovideosink
 * ]|
 */
#include "gstpseudo3dwarp.h"

#include <tuple>

#include "caps_geometry.h"
#include "depth_meta.h"
#include "enums.h"
#include "stage_adaptive.h"
#include "stage_depth.h"
#include "stage_gpu.h"
#include "stereo_packing.h"
#include "video_util.h"
#include "warp.h"

#if HAVE_CUDA
#include "bars_gpu.h"
#include "warp_gpu.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_warp_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_warp_debug

enum {
  PROP_0,
  PROP_MAX_DISPARITY,
  PROP_CONVERGENCE,
  PROP_VIEW,
  PROP_FILL,
  PROP_PACK,  // the pack's properties: N_PACK_PROPERTIES ids from here (stereo_packing.h)
};

// The default layout: the rendered pair itself.
constexpr p3d::PackLayout kDefaultLayout = p3d::PackLayout::SideBySide;

struct WarpState {
  p3d::WarpCpuScratch cpu;  // the CPU path's planes, reused frame to frame (streaming thread only)
  // adaptive (stage_adaptive.h), streaming thread: the previous frame's
  // inputs, parameters and output.
  p3d::gst::InputHistory inputs{p3d::ChangeReach::Spans};  // the warp redoes the columns a change reaches
  p3d::gst::KeptParams<std::tuple<p3d::WarpParams, p3d::PackParams, p3d::YuvToRgb, p3d::PixelRect>> params;
  p3d::gst::OutputHistory output{p3d::ChangeReach::Spans};
  // The views of a picture narrower than the frame (pillarbox bars), kept
  // from frame to frame like the pair buffer.
  std::vector<uint8_t> active_pair;
#if HAVE_CUDA
  p3d::WarpRendererGpu gpu;
  p3d::ActiveWarpGpu active_gpu;
  // adaptive on CUDA memory: the inputs compared and the output kept on
  // the device (cuda/change_gpu.h).
  p3d::gst::WholeOutputGpu adaptive_gpu;
#endif

  void forget() {
    inputs.reset();
    params.reset();
    output.reset();
#if HAVE_CUDA
    adaptive_gpu.reset();
#endif
  }
};

struct _GstPseudo3DWarp {
  GstPseudo3DBase parent;
  p3d::WarpParams params;  // object lock
  p3d::gst::StereoPacking *packing;
  WarpState *state;
};

#define gst_pseudo3d_warp_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DWarp, gst_pseudo3d_warp, GST_TYPE_PSEUDO3D_BASE);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dwarp, "pseudo3dwarp", GST_RANK_NONE, GST_TYPE_PSEUDO3D_WARP);

// Output: the layout's frame of the two views (the pair side by side, 2W x
// H, by default), signalled as pseudo3dpack signals it, in a packed RGB
// format or, for encoders, 4:2:0, of the input's sample depth; the pixel
// aspect ratio is the input's. Towards the sink: the input sizes that give
// it, in any format of the output's depth.
static GstCaps *transform_geometry(GstPseudo3DBase *base, GstPadDirection from, const GstStructure *in) {
  p3d::gst::StereoPacking *packing = GST_PSEUDO3D_WARP(base)->packing;
  const p3d::gst::PackingGeometry g = packing->negotiating();
  if (from == GST_PAD_SINK) return packing->output_caps(in, g);
  GstCaps *caps = gst_caps_new_empty();
  // The exact sizes first (gst_pseudo3d_sizes_back()).
  for (const auto way : {p3d::gst::SizeWay::BackExact, p3d::gst::SizeWay::BackRounded}) {
    GstStructure *s = packing->through(in, way, g.layout);
    gst_structure_remove_fields(s, "multiview-mode", "multiview-flags", "views", NULL);
    gst_pseudo3d_set_formats(s, p3d::gst::formats_for(p3d::gst::FormatKind::All, p3d::gst::format_depths(in)));
    caps = gst_caps_merge_structure(caps, s);
  }
  return caps;
}

static gboolean set_info(GstPseudo3DBase *base, GstCaps *, GstVideoInfo *in, GstCaps *, GstVideoInfo *out) {
  p3d::gst::StereoPacking *packing = GST_PSEUDO3D_WARP(base)->packing;
  p3d::gst::PackedFrame f;
  const char *why = nullptr;
  // A rendered pair always fits the layout; its colours may not fit an anaglyph.
  if (packing->frame_for(packing->commit(), in, &f, &why) == p3d::gst::InputFit::NeedsSdr)
    return gst_pseudo3d_base_refuse_caps(base, p3d::gst::kNeedsSdrText, p3d::gst::kNeedsSdrHint, why);
  if (GST_VIDEO_INFO_WIDTH(out) != f.width || GST_VIDEO_INFO_HEIGHT(out) != f.height) {
    return gst_pseudo3d_base_refuse_caps(base, "The output does not have the size of the layout's frame",
                                         "input %dx%d, output %dx%d, layout's frame %dx%d", GST_VIDEO_INFO_WIDTH(in),
                                         GST_VIDEO_INFO_HEIGHT(in), GST_VIDEO_INFO_WIDTH(out),
                                         GST_VIDEO_INFO_HEIGHT(out), f.width, f.height);
  }
  if (p3d::gst::is_deep_info(in) != p3d::gst::is_deep_info(out))
    return gst_pseudo3d_base_refuse_caps(base, p3d::gst::kDepthMismatchText, "input %s, output %s",
                                         GST_VIDEO_INFO_NAME(in), GST_VIDEO_INFO_NAME(out));
  packing->set_negotiated(f.params, out);
  return TRUE;
}

static gboolean frame_boundary(GstPseudo3DBase *base) {
  return GST_PSEUDO3D_WARP(base)->packing->frame_boundary(&base->in_info, &base->out_info) ==
         p3d::gst::StereoPacking::Boundary::Renegotiate;
}

// The CPU path. With adaptive the columns that a changed source or depth
// reaches are warped again (warp_pack_changed_cpu), the fill runs over
// what those reach and the pack over the output rows they touch; the rest
// is the previous output.
static GstFlowReturn render_cpu(GstPseudo3DWarp *self, GstBuffer *inbuf, const p3d::FrameView &src,
                                const p3d::WarpParams &params, const p3d::PackParams &pack, const p3d::YuvToRgb &yuv,
                                p3d::PixelRect rect, const p3d::gst::AdaptiveSettings &adaptive, GstVideoFrame *out) {
  GstPseudo3DBase *base = GST_PSEUDO3D_BASE(self);
  WarpState *state = self->state;
  const p3d::gst::DepthPlanePtr depth = p3d::gst::frame_depth_plane(inbuf);
  const p3d::FrameView dst = p3d::gst::frame_view(out);
  p3d::ChangeMap changes;
  p3d::FrameView previous;
  bool whole = true;
  // While frames keep changing, uncompared (ChangeBackOff): the history
  // is dropped, and so is the output kept.
  // What the warp redoes of a change follows its fill (warp_change_reach).
  const p3d::ChangeReach reach = p3d::warp_change_reach(params);
  state->inputs.set_reach(reach);
  state->output.set_reach(reach);
  const bool compare = state->inputs.begin(adaptive.on);
  if (compare) {
    changes = state->inputs.compare(src, depth, adaptive.tolerance);
    // A busy change: the whole frame costs less than keeping the rest.
    whole = state->params.changed({params, pack, yuv, rect}) || p3d::busy_for(reach, changes) ||
            !state->output.previous(&base->out_info, &previous);
  } else {
    state->params.reset();
    state->output.reset();
  }
  // The pair into the output where the layout is the pair itself, else
  // into the pair buffer (kept from frame to frame), then packed.
  const p3d::FrameView pair = self->packing->pair_target(pack, src.width, src.height, dst);
  p3d::ActiveArea active{rect, pair};
  active.pair.width = 2 * rect.width();
  active.pair.height = rect.height();
  active.pair.stride[0] = p3d::packed_pixel_bytes(pair.format) * active.pair.width;
  if (rect.x0 != 0 || rect.x1 != src.width) {  // a pillarbox: the views are placed from their own buffer
    state->active_pair.resize(static_cast<size_t>(active.pair.stride[0]) * active.pair.height);
    active.pair.plane[0] = state->active_pair.data();
  }
  // The rows it does not write come from the kept previous output.
  p3d::KeptOutput kept{whole ? nullptr : &previous, {}};
  const long long holes = p3d::warp_pack_changed_cpu(params, pack, src, yuv, p3d::as_const(depth->view()), pair, dst,
                                                     state->cpu, whole ? nullptr : &changes, &active, &kept);
  if (holes < 0) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Frames do not fit the warp"),
                      ("input %dx%d, output %dx%d", src.width, src.height, dst.width, dst.height));
    return GST_FLOW_ERROR;
  }
  if (compare) state->output.update(&base->out_info, out, changes, whole, kept.written);
  GST_LOG_OBJECT(self, "%lld hole pixels filled", holes);
  return GST_FLOW_OK;
}

static GstFlowReturn process(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *inbuf, GstVideoFrame *in,
                             GstVideoFrame *out) {
  GstPseudo3DWarp *self = GST_PSEUDO3D_WARP(base);
  const p3d::FrameView src = p3d::gst::frame_view(in);
  p3d::gst::DepthPlane *depth = p3d::gst::frame_depth(base, inbuf, path, src.width, src.height);
  if (!depth) return GST_FLOW_ERROR;
  GST_OBJECT_LOCK(self);
  const p3d::WarpParams params = self->params;
  GST_OBJECT_UNLOCK(self);
  const p3d::PackParams pack = self->packing->frame_params();
  const p3d::YuvToRgb yuv = p3d::gst::yuv_params(&base->in_info);
  if (gst_pseudo3d_base_take_history_reset(base)) self->state->forget();
  // The views are rendered from the picture the depth was estimated on
  // (pseudo3ddepth's crop-bars); on the GPU from the whole frame where the
  // rect's corner is not on a cell of the depth's grid.
  p3d::PixelRect rect = depth->active_rect();
#if HAVE_CUDA
  if (path == GST_PSEUDO3D_PATH_GPU) {
    WarpState *state = self->state;
    const p3d::PixelRect whole = p3d::whole_picture(src.width, src.height);
    const p3d::FrameView dst = p3d::gst::frame_view(out);
    const p3d::DepthGrid<const float> grid = p3d::as_const(depth->grid());
    if (!p3d::sub_grid_fits(grid, rect)) rect = whole;
    // Adaptive: the inputs compared and the decision taken on the device;
    // the kernels of a frame whose inputs did not change return at once
    // and the kept output is copied into it; while frames keep changing,
    // uncompared (ChangeBackOff). fill=neighbor-average, whose steps the
    // host checks, renders every frame.
    const p3d::gst::AdaptiveSettings adaptive = p3d::gst::adaptive_settings(base);
    const bool adaptive_fill = adaptive.on && p3d::warp_sanitize(params).fill != p3d::HoleFill::NeighborAverage;
    if (!adaptive_fill) state->forget();
    const bool keep = state->adaptive_gpu.begin(adaptive_fill);
    const bool changed_params = keep && state->params.changed({params, pack, yuv, rect});
    // A changed source row reaches the rows of the views within
    // warp_rows_reach() of it: only those are rendered again, into the
    // pair the renderer keeps (the others' bytes stay there), then packed.
    const int reach_rows =
        rect != whole
            ? p3d::warp_rows_reach(p3d::active_warp_params(params, src.width, rect.width()), rect.width(), rect.height())
            : p3d::warp_rows_reach(params, src.width, src.height);
    const GstFlowReturn ret = p3d::gst::run_gpu(base, "rendering the views", [&]() -> p3d::CudaStatus {
      cudaStream_t stream = base->gpu->stream();
      p3d::StageGate gate;
      if (keep)
        P3D_CUDA_TRY_STATUS(state->adaptive_gpu.decide(src, p3d::gst::frame_depth_plane(inbuf), adaptive.tolerance,
                                                       dst, changed_params, stream, &gate, reach_rows));
      if (rect != whole)
        P3D_CUDA_TRY_STATUS(state->active_gpu.render(state->gpu, params, pack, src, yuv, grid, rect, dst, stream, gate));
      else
        P3D_CUDA_TRY_STATUS(state->gpu.render_packed(params, pack, src, yuv, grid, dst, stream, nullptr, gate));
      if (keep) P3D_CUDA_TRY_STATUS(state->adaptive_gpu.finish(dst, stream));
      return p3d::CudaStatus{};
    });
    state->adaptive_gpu.end(ret == GST_FLOW_OK);
    return ret;
  }
#endif
  return render_cpu(self, inbuf, src, params, pack, yuv, rect, p3d::gst::adaptive_settings(base), out);
}

static void release(GstPseudo3DBase *base) {
  GST_PSEUDO3D_WARP(base)->state->forget();
#if HAVE_CUDA
  GST_PSEUDO3D_WARP(base)->state->gpu = p3d::WarpRendererGpu();
  GST_PSEUDO3D_WARP(base)->state->active_gpu = p3d::ActiveWarpGpu();
  GST_PSEUDO3D_WARP(base)->state->adaptive_gpu = p3d::gst::WholeOutputGpu();
#endif
}

static void gst_pseudo3d_warp_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DWarp *self = GST_PSEUDO3D_WARP(object);
  if (self->packing->set_property(prop_id, value)) return;
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
  if (self->packing->get_property(prop_id, value)) return;
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
  delete GST_PSEUDO3D_WARP(object)->packing;
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

  // The pack's properties; layout's default here is the pair itself.
  p3d::gst::install_pack_properties(
      gobject_class, PROP_PACK, kDefaultLayout,
      "Stereo format of the output: side-by-side (default) is the rendered pair itself, for pseudo3dpack; any other "
      "packs it here, as pseudo3dpack would (on the GPU an anaglyph in one pass with the views). A change while "
      "playing renegotiates the output caps before the next frame");

  gst_element_class_set_static_metadata(element_class, "pseudo3d DIBR view synthesis", "Filter/Effect/Video",
                                        "Renders left and right views from a frame and its depth map, side by "
                                        "side or packed in a stereo layout",
                                        "pseudo3d developers");
  GstCaps *sink = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, p3d::kMaxFrameSide);
  GstCaps *src = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, 2 * p3d::kMaxFrameSide);
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, sink));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, src));
  gst_caps_unref(sink);
  gst_caps_unref(src);

  base_class->transform_geometry = transform_geometry;  // formats too: packed RGB or 4:2:0 out
  base_class->set_info = set_info;
  base_class->frame_boundary = frame_boundary;
  base_class->process = process;
  base_class->release = release;

  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_warp_debug, "pseudo3dwarp", 0, "pseudo3d DIBR view synthesis");
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_VIEW, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_FILL, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_warp_init(GstPseudo3DWarp *self) {
  self->params = p3d::WarpParams();
  self->packing = new p3d::gst::StereoPacking(GST_BASE_TRANSFORM(self), PROP_PACK, p3d::gst::PairSource::Rendered,
                                              kDefaultLayout);
  GST_PSEUDO3D_BASE(self)->staged = self->packing->staged();
  self->state = new WarpState();
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), FALSE);
  // The input is never the output (2D in, a stereo frame out): upstream
  // must not be offered the output's caps first, or it would label 2D
  // video as a pair and convert its colours to the output's colorimetry
  // (a PQ film turned to BT.709 before the 3D stages).
  gst_base_transform_set_prefer_passthrough(GST_BASE_TRANSFORM(self), FALSE);
}
