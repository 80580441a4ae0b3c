/**
 * SECTION:element-pseudo3dfilter
 * @title: pseudo3dfilter
 *
 * Cross-bilateral filter of the depth map attached by pseudo3ddepth, guided
 * by the frame's luma, so that depth edges follow image edges. The frame
 * passes on unchanged with the filtered depth attached. radius=0 passes
 * buffers through untouched. From 4K up the filter runs on a coarser grid
 * by default (scale=0: cells of 4 x 4 pixels from 2160 rows up), so depth
 * edges follow image edges to a cell; scale=1 filters every pixel.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 filesrc location=in.png ! pngdec ! videoconvert ! pseudo3ddepth ! pseudo3dfilter radius=8 sigma-range=10 ! pseudo3dwarp ! pseudo3dpack ! videoconvert ! pngenc ! filesink location=out.png
 * ]|
 */
#include "gstpseudo3dfilter.h"

#include <tuple>

#include "bars.h"
#include "bilateral.h"
#include "depth_meta.h"
#include "enums.h"
#include "stage_adaptive.h"
#include "stage_depth.h"
#include "stage_gpu.h"
#include "video_util.h"

#if HAVE_CUDA
#include "bilateral_gpu.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_filter_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_filter_debug

enum { PROP_0, PROP_RADIUS, PROP_SIGMA_SPACE, PROP_SIGMA_RANGE, PROP_MODE, PROP_SCALE };

struct FilterState {
#if HAVE_CUDA
  p3d::BilateralFilterGpu gpu;
  // adaptive on CUDA memory: the inputs compared on the device, and the
  // tiles within the filter's reach of a change.
  p3d::gst::InputHistoryGpu inputs_gpu;
  p3d::ChangeMapGpu dirty_gpu;
  p3d::ChangeBackOff backoff_gpu;
#endif
  p3d::gst::DepthPlanePool pool;
  // adaptive (stage_adaptive.h), streaming thread: the previous frame's
  // inputs, parameters and output plane.
  p3d::gst::InputHistory inputs;
  p3d::gst::KeptParams<std::tuple<p3d::BilateralParams, p3d::PixelRect>> params;
  p3d::gst::DepthPlanePtr last_out;
  p3d::BilateralScratch scratch;

  void forget() {
    inputs.reset();
#if HAVE_CUDA
    inputs_gpu.reset();
    backoff_gpu.reset();
#endif
    params.reset();
    last_out.reset();
  }
};

struct _GstPseudo3DFilter {
  GstPseudo3DBase parent;
  p3d::BilateralParams params;
  FilterState *state;
};

#define gst_pseudo3d_filter_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DFilter, gst_pseudo3d_filter, GST_TYPE_PSEUDO3D_BASE);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dfilter, "pseudo3dfilter", GST_RANK_NONE, GST_TYPE_PSEUDO3D_FILTER);

// A flat scene (adaptive=true, on the CPU): a depth map of one value in
// the rect is its own filtered map (bilateral_keeps), so the frame keeps
// its depth plane as it is.
static bool flat_depth(p3d::gst::DepthPlane *depth, p3d::PixelRect rect) {
  return p3d::bilateral_keeps(p3d::sub_image(p3d::as_const(depth->view()), rect));
}

// The CPU filter with adaptive=true: the tiles within the filter's reach
// of a changed guide or depth tile are filtered again, the others keep the
// previous output; no change at all keeps the previous plane itself.
static GstFlowReturn filter_adaptive(GstPseudo3DFilter *self, GstBuffer *buf, const p3d::FrameView &guide,
                                     const p3d::BilateralParams &params, p3d::PixelRect rect, float tolerance) {
  GstPseudo3DBase *base = GST_PSEUDO3D_BASE(self);
  FilterState *state = self->state;
  const p3d::gst::DepthPlanePtr depth = p3d::gst::frame_depth_plane(buf);
  const p3d::ChangeMap changes = state->inputs.compare(guide, depth, tolerance);
  const bool whole = state->params.changed({params, rect}) || !state->last_out;
  GST_LOG_OBJECT(self, "%.0f%% of the tiles changed%s", 100.0 * changes.fraction(), whole ? ", filtering all" : "");
  if (flat_depth(depth.get(), rect)) {
    state->last_out = depth;
    return GST_FLOW_OK;
  }
  p3d::gst::DepthPlanePtr out = p3d::gst::new_depth(base, state->pool, GST_PSEUDO3D_PATH_CPU, depth->width, depth->height);
  if (!out || !p3d::gst::set_active(base, out.get(), rect)) return GST_FLOW_ERROR;
  const p3d::ImageView<const float> prev =
      state->last_out ? p3d::sub_image(p3d::as_const(state->last_out->view()), rect) : p3d::ImageView<const float>();
  const p3d::ChangeMap active_changes = changes.cropped(rect);
  if (p3d::bilateral_filter_changed_cpu(params, p3d::sub_frame(guide, rect),
                                        p3d::sub_image(p3d::as_const(depth->view()), rect), prev,
                                        p3d::sub_image(out->view(), rect), whole ? nullptr : &active_changes,
                                        state->scratch))
    state->last_out = std::move(out);
  pseudo3d_buffer_set_depth(buf, state->last_out);
  return GST_FLOW_OK;
}

// The filter runs on the picture its depth was estimated on (the depth
// plane's active rect: pseudo3ddepth's crop-bars). On the GPU, where the
// rect's corner is not on a cell of the depth's or the output's grid, it
// runs on the whole frame.
static p3d::PixelRect filter_rect(GstPseudo3DPath path, p3d::gst::DepthPlane *depth,
                                  const p3d::BilateralParams &params) {
  const p3d::PixelRect rect = depth->active_rect(), whole = p3d::whole_picture(depth->width, depth->height);
  if (path != GST_PSEUDO3D_PATH_GPU || rect == whole) return rect;
  const int shift = p3d::bilateral_grid_shift(p3d::bilateral_sanitize(params), rect.width(), rect.height());
  const p3d::DepthGrid<float> grid = depth->grid();
  return p3d::sub_grid_fits(grid, rect) ? p3d::rect_on_cells(rect, shift, depth->width, depth->height) : whole;
}

static GstFlowReturn process_ip(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *buf,
                                GstVideoFrame *frame) {
  GstPseudo3DFilter *self = GST_PSEUDO3D_FILTER(base);
  const p3d::FrameView guide = p3d::gst::frame_view(frame);
  p3d::gst::DepthPlane *depth = p3d::gst::frame_depth(base, buf, path, guide.width, guide.height);
  if (!depth) return GST_FLOW_ERROR;
  GST_OBJECT_LOCK(self);
  // The automatic grid step is the frame's, inside bars too.
  const p3d::BilateralParams params = p3d::frame_scaled(self->params, guide.width, guide.height);
  GST_OBJECT_UNLOCK(self);
  if (gst_pseudo3d_base_take_history_reset(base)) self->state->forget();
  const p3d::PixelRect rect = filter_rect(path, depth, params);
  const p3d::gst::AdaptiveSettings adaptive = p3d::gst::adaptive_settings(base);
  FilterState *state = self->state;
  if (path == GST_PSEUDO3D_PATH_CPU) {
    // While frames keep changing, uncompared (ChangeBackOff): the history
    // is dropped, and so is the output kept.
    if (state->inputs.begin(adaptive.on)) return filter_adaptive(self, buf, guide, params, rect, adaptive.tolerance);
    state->params.reset();
    state->last_out.reset();
    if (adaptive.on && flat_depth(depth, rect)) return GST_FLOW_OK;
  } else if (!adaptive.on) {
    state->forget();
  }
  // On CUDA memory the output holds a value a cell of the coarse grid (no
  // full-size copy; depth_plane.h) where the grid step is a power of two.
  const int shift = p3d::bilateral_grid_shift(p3d::bilateral_sanitize(params), rect.width(), rect.height());
  p3d::gst::DepthPlanePtr out = p3d::gst::new_depth(base, state->pool, path, depth->width, depth->height, shift);
  if (!out || !p3d::gst::set_active(base, out.get(), rect)) return GST_FLOW_ERROR;
  const p3d::FrameView active = p3d::sub_frame(guide, rect);
#if HAVE_CUDA
  if (path == GST_PSEUDO3D_PATH_GPU) {
    // Adaptive: the blocks of outputs within the filter's reach of a
    // changed guide or depth tile are filtered, the others copied from the
    // previous output plane, which the stage holds; while frames keep
    // changing, uncompared (ChangeBackOff); on a coarse grid never
    // (filter_compares_on_gpu).
    const bool compare = adaptive.on && p3d::filter_compares_on_gpu(shift) && state->backoff_gpu.compare_next();
    if (!compare) {
      state->inputs_gpu.reset();
      state->last_out.reset();
    }
    const bool whole = compare && (state->params.changed({params, rect}) || !state->last_out ||
                                   state->last_out->width != out->width || state->last_out->height != out->height);
    const GstFlowReturn ret = p3d::gst::run_gpu(base, "filtering depth", [&]() -> p3d::CudaStatus {
      cudaStream_t stream = base->gpu->stream();
      p3d::TileFlags dirty;
      p3d::DepthGrid<const float> kept;
      if (compare) {
        P3D_CUDA_TRY_STATUS(state->inputs_gpu.compare(guide, p3d::gst::frame_depth_plane(buf), adaptive.tolerance,
                                                      stream));
        if (!whole) {
          const int reach = p3d::bilateral_reach(params, rect.width(), rect.height());
          P3D_CUDA_TRY_STATUS(p3d::dilate_gpu(state->inputs_gpu.changes(), reach, reach, state->dirty_gpu, stream));
          P3D_CUDA_TRY_STATUS(state->dirty_gpu.summarize(stream));
          dirty = state->dirty_gpu.flags().offset(rect.x0, rect.y0);
          kept = p3d::sub_grid(p3d::as_const(state->last_out->grid()), rect);
        }
      }
      return state->gpu.run(params, active, p3d::sub_grid(p3d::as_const(depth->grid()), rect),
                            p3d::sub_grid(out->grid(), rect), stream, dirty, kept);
    });
    if (ret != GST_FLOW_OK) {
      state->forget();  // the inputs and parameters kept may have moved on without the output
      return ret;
    }
    if (compare) state->last_out = out;
    if (compare && !whole && state->inputs_gpu.compared())
      state->backoff_gpu.observe(state->dirty_gpu.last_share() > 0);
  } else
#endif
  {
    p3d::bilateral_filter_cpu(params, active, p3d::sub_image(p3d::as_const(depth->view()), rect),
                              p3d::sub_image(out->view(), rect));
  }
  pseudo3d_buffer_set_depth(buf, std::move(out));
  return GST_FLOW_OK;
}

static void release(GstPseudo3DBase *base) {
  FilterState *state = GST_PSEUDO3D_FILTER(base)->state;
  state->forget();
#if HAVE_CUDA
  state->gpu = p3d::BilateralFilterGpu();
  state->inputs_gpu = p3d::gst::InputHistoryGpu();
  state->dirty_gpu = p3d::ChangeMapGpu();
#endif
  state->pool.clear();
}

// radius 0 is the identity: buffers pass untouched. Switched at the frame
// boundary in the streaming thread, never between a frame's output buffer
// and its transform (radius 0 within a frame copies the depth: the same).
static gboolean frame_boundary(GstPseudo3DBase *base) {
  GstPseudo3DFilter *self = GST_PSEUDO3D_FILTER(base);
  GST_OBJECT_LOCK(self);
  const bool identity = self->params.radius == 0;
  GST_OBJECT_UNLOCK(self);
  gst_base_transform_set_passthrough(GST_BASE_TRANSFORM(self), identity);
  return FALSE;  // the caps never change
}

static void gst_pseudo3d_filter_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DFilter *self = GST_PSEUDO3D_FILTER(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_RADIUS: self->params.radius = g_value_get_int(value); break;
    case PROP_SIGMA_SPACE: self->params.sigma_space = g_value_get_float(value); break;
    case PROP_SIGMA_RANGE: self->params.sigma_range = g_value_get_float(value); break;
    case PROP_MODE: self->params.mode = static_cast<p3d::BilateralMode>(g_value_get_enum(value)); break;
    case PROP_SCALE: self->params.scale = g_value_get_int(value); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_filter_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DFilter *self = GST_PSEUDO3D_FILTER(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_RADIUS: g_value_set_int(value, self->params.radius); break;
    case PROP_SIGMA_SPACE: g_value_set_float(value, self->params.sigma_space); break;
    case PROP_SIGMA_RANGE: g_value_set_float(value, self->params.sigma_range); break;
    case PROP_MODE: g_value_set_enum(value, static_cast<gint>(self->params.mode)); break;
    case PROP_SCALE: g_value_set_int(value, self->params.scale); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_filter_finalize(GObject *object) {
  delete GST_PSEUDO3D_FILTER(object)->state;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_filter_class_init(GstPseudo3DFilterClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstPseudo3DBaseClass *base_class = GST_PSEUDO3D_BASE_CLASS(klass);
  const p3d::BilateralParams d = p3d::default_filter_params();
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);

  gobject_class->set_property = gst_pseudo3d_filter_set_property;
  gobject_class->get_property = gst_pseudo3d_filter_get_property;
  gobject_class->finalize = gst_pseudo3d_filter_finalize;

  g_object_class_install_property(
      gobject_class, PROP_RADIUS,
      g_param_spec_int("radius", "Radius",
                       "Half width of the filter window in pixels (0 = off: buffers pass through)", 0,
                       p3d::kMaxBilateralRadius, d.radius, flags));
  g_object_class_install_property(
      gobject_class, PROP_SIGMA_SPACE,
      g_param_spec_float("sigma-space", "Spatial sigma",
                         "Standard deviation of the spatial Gaussian, in pixels", 0.1f, 100.f, d.sigma_space, flags));
  g_object_class_install_property(
      gobject_class, PROP_SIGMA_RANGE,
      g_param_spec_float("sigma-range", "Range sigma",
                         "Standard deviation of the guide-luma Gaussian, in 8-bit levels: smaller keeps depth edges "
                         "sharper at image edges; 0 averages only over pixels of identical luma",
                         0.f, 1000.f, d.sigma_range, flags));
  g_object_class_install_property(
      gobject_class, PROP_MODE,
      g_param_spec_enum("mode", "Filter mode",
                        "A row pass then a column pass (the default: 2 (2r+1) taps a pixel instead of (2r+1)^2, "
                        "near the whole window's quality: docs/quality.md), or the whole window",
                        GST_TYPE_PSEUDO3D_FILTER_MODE, static_cast<gint>(d.mode), flags));
  g_object_class_install_property(
      gobject_class, PROP_SCALE,
      g_param_spec_int("scale", "Grid step",
                       "Filter on a grid this many times coarser than the picture in each direction, each result "
                       "spread over its cell (the mean luma of a cell guides it): 1 = every pixel; 0 = automatic: "
                       "1 up to 2159 rows, 4 from there (4K and 8K: speed and quality against the step in "
                       "docs/benchmarks.md and docs/quality.md). radius and sigma-space stay in pixels of the "
                       "picture",
                       0, p3d::kMaxBilateralScale, d.scale, flags));

  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_FILTER_MODE, (GstPluginAPIFlags)0);
  gst_element_class_set_static_metadata(element_class, "pseudo3d depth filter", "Filter/Effect/Video",
                                        "Cross-bilateral filtering of a frame's depth map guided by the frame",
                                        "pseudo3d developers");
  GstCaps *caps = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, p3d::kMaxFrameSide);
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, caps));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, caps));
  gst_caps_unref(caps);

  base_class->frame_boundary = frame_boundary;
  base_class->process_ip = process_ip;
  base_class->release = release;
  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_filter_debug, "pseudo3dfilter", 0, "pseudo3d depth filter");
}

static void gst_pseudo3d_filter_init(GstPseudo3DFilter *self) {
  self->params = p3d::default_filter_params();
  self->state = new FilterState();
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), TRUE);
}
