/**
 * SECTION:element-pseudo3ddepth
 * @title: pseudo3ddepth
 *
 * Estimates a depth map from each frame and attaches it to the buffer as a
 * Pseudo3DDepthMeta; the frame itself passes on unchanged. method=edges
 * groups blocks into regions along image edges and gives each region depth
 * from a depth-gradient hypothesis, smoothed over time (reused while the
 * scene is static, reset at scene cuts). method=rgbd takes frames holding
 * colour in the left half and depth as grey in the right half (white = near)
 * and outputs the colour half with that depth attached. A buffer that
 * already carries depth passes through untouched.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 videotestsrc ! pseudo3ddepth hypothesis=top-bottom ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack ! videoconvert ! autovideosink
 * ]|
 */
#include "gstpseudo3ddepth.h"

#include <cstring>
#include <memory>

#include "bars.h"
#include "caps_geometry.h"
#include "depth_estimate.h"
#include "depth_meta.h"
#include "depth_plane.h"
#include "enums.h"
#include "stage_adaptive.h"
#include "stage_depth.h"
#include "stage_gpu.h"
#include "staged_geometry.h"
#include "video_util.h"

#if HAVE_CUDA
#include "bars_gpu.h"
#include "depth_estimate_gpu.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_depth_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_depth_debug

enum {
  PROP_0,
  PROP_METHOD,
  PROP_HYPOTHESIS,
  PROP_BLOCK_SIZE,
  PROP_EDGE_THRESHOLD,
  PROP_REGION_WEIGHT,
  PROP_GROUND_CONTACT,
  PROP_TEMPORAL_SMOOTHING,
  PROP_FEATURE_SMOOTHING,
  PROP_STATIC_THRESHOLD,
  PROP_CUT_THRESHOLD,
  PROP_CROP_BARS,
};

#define DEFAULT_METHOD GST_PSEUDO3D_DEPTH_METHOD_EDGES
#define DEFAULT_CROP_BARS GST_PSEUDO3D_CROP_BARS_AUTO

struct DepthState {
  p3d::DepthEstimatorCpu cpu;
#if HAVE_CUDA
  p3d::DepthEstimatorGpu gpu;
#endif
  p3d::gst::DepthPlanePool pool;
  // adaptive (stage_adaptive.h): the frame's bytes and the plane of the
  // previous frame, which an unchanged depth reuses. Streaming thread.
  p3d::gst::InputHistory history;
  p3d::gst::DepthPlanePtr last_plane;
  // crop-bars (common/bars.h), streaming thread: the bars decided from
  // the frames before this one, and the rect the last frame's depth was
  // estimated in (the estimator's history is of that picture).
  p3d::BarTracker bars;
  p3d::BarCounts counts;
  bool counts_current = false;  // counts holds the last frame's, counted on the CPU
  p3d::PixelRect estimated_rect;
#if HAVE_CUDA
  p3d::BarCountsGpu bar_counts_gpu;
  // adaptive on CUDA memory: the frame's bytes kept on the device and the
  // tiles that changed (cuda/change_gpu.h). Streaming thread.
  p3d::FrameHistoryGpu history_gpu;
  p3d::ChangeMapGpu changes_gpu;
  p3d::ChangeBackOff backoff_gpu;
#endif
  // method decides the output width: it changes at a frame boundary (object lock).
  p3d::gst::StagedGeometry<GstPseudo3DDepthMethod> method{DEFAULT_METHOD};
};

struct _GstPseudo3DDepth {
  GstPseudo3DBase parent;
  p3d::DepthParams params;  // object lock
  GstPseudo3DCropBars crop_bars;  // object lock
  DepthState *state;
};

#define gst_pseudo3d_depth_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DDepth, gst_pseudo3d_depth, GST_TYPE_PSEUDO3D_BASE);
GST_ELEMENT_REGISTER_DEFINE(pseudo3ddepth, "pseudo3ddepth", GST_RANK_NONE, GST_TYPE_PSEUDO3D_DEPTH);

// method=rgbd outputs the colour half: half the input width.
static GstCaps *transform_geometry(GstPseudo3DBase *base, GstPadDirection from, const GstStructure *in) {
  GstPseudo3DDepth *self = GST_PSEUDO3D_DEPTH(base);
  GST_OBJECT_LOCK(self);
  const bool rgbd = self->state->method.negotiating() == GST_PSEUDO3D_DEPTH_METHOD_RGBD;
  GST_OBJECT_UNLOCK(self);
  if (!rgbd) return gst_pseudo3d_caps_of(gst_structure_copy(in));
  if (from == GST_PAD_SINK) return gst_pseudo3d_caps_of(gst_pseudo3d_sizes_forward(in, 1, 2, 1, 1));
  // Towards the sink: twice the width first, then every width whose half this is.
  return gst_caps_merge_structure(gst_pseudo3d_caps_of(gst_pseudo3d_sizes_back(in, 1, 2, 1, 1, FALSE)),
                                  gst_pseudo3d_sizes_back(in, 1, 2, 1, 1, TRUE));
}

static gboolean set_info(GstPseudo3DBase *base, GstCaps *, GstVideoInfo *in, GstCaps *, GstVideoInfo *out) {
  GstPseudo3DDepth *self = GST_PSEUDO3D_DEPTH(base);
  GST_OBJECT_LOCK(self);
  const GstPseudo3DDepthMethod method = self->state->method.commit();
  GST_OBJECT_UNLOCK(self);
  const int in_w = GST_VIDEO_INFO_WIDTH(in), out_w = GST_VIDEO_INFO_WIDTH(out);
  if (method == GST_PSEUDO3D_DEPTH_METHOD_RGBD) {
    // 4:2:0 halves must start on a chroma sample: the colour half's width must be even.
    if (out_w * 2 != in_w || (!GST_VIDEO_FORMAT_INFO_IS_RGB(in->finfo) && out_w % 2 != 0)) {
      // Name the rule the caps broke: an even YUV width whose half is odd
      // is twice as wide as its half, and said so before.
      const bool halves = out_w * 2 == in_w;
      return gst_pseudo3d_base_refuse_caps(
          base,
          halves ? "RGBD input in a YUV format needs a width that is a multiple of 4"
                 : "RGBD input must be twice as wide as its colour half",
          "input %dx%d %s; YUV formats need a width that is a multiple of 4 (the colour half must start on a "
          "chroma sample), RGB formats an even width",
          in_w, GST_VIDEO_INFO_HEIGHT(in), GST_VIDEO_INFO_NAME(in));
    }
  } else if (out_w != in_w) {
    return gst_pseudo3d_base_refuse_caps(base, "Output caps do not fit method=edges", "input width %d, output width %d",
                                         in_w, out_w);
  }
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), method == GST_PSEUDO3D_DEPTH_METHOD_EDGES);
  return TRUE;
}

static gboolean frame_boundary(GstPseudo3DBase *base) {
  GstPseudo3DDepth *self = GST_PSEUDO3D_DEPTH(base);
  GST_OBJECT_LOCK(self);
  const bool pending = self->state->method.pending();
  GST_OBJECT_UNLOCK(self);
  return pending;
}

// The parameters of this frame, read once; the temporal history is dropped
// first when the stream was flushed, restarted or interrupted.
static p3d::DepthParams frame_params(GstPseudo3DDepth *self) {
  if (gst_pseudo3d_base_take_history_reset(GST_PSEUDO3D_BASE(self))) {
    self->state->cpu.reset();
#if HAVE_CUDA
    self->state->gpu.reset();
    self->state->history_gpu.reset();
    self->state->backoff_gpu.reset();
#endif
    self->state->history.reset();
    self->state->last_plane.reset();
    self->state->bars.reset();
    self->state->counts_current = false;
  }
  GST_OBJECT_LOCK(self);
  const p3d::DepthParams p = self->params;
  GST_OBJECT_UNLOCK(self);
  return p;
}

// Whether crop-bars=auto (object lock taken here).
static bool crop_bars(GstPseudo3DDepth *self) {
  GST_OBJECT_LOCK(self);
  const bool crop = self->crop_bars == GST_PSEUDO3D_CROP_BARS_AUTO;
  GST_OBJECT_UNLOCK(self);
  return crop;
}

// With crop-bars=auto: the bar counts into the tracker in its order
// (common/bars.h, step 4): the previous frame's first, then this frame's
// counted for the next one. On the GPU a frame's counts are queued and read
// back at the next frame, which finds them done: no frame waits for its own
// but the first after a start, a reset or crop-bars coming back on, whose
// rect comes from its own counts. The counts run on a stream of their own
// beside the estimate (BarCountsGpu::join). changes: the tiles that
// changed since the previous frame (adaptive, system memory; null:
// unknown); when that frame was counted here too, only the changed bands
// are counted again, and an unchanged frame takes its counts again.
static GstFlowReturn observe_bars(GstPseudo3DDepth *self, GstPseudo3DPath path, const p3d::FrameView &view,
                                  const p3d::ChangeMap *changes) {
  GstPseudo3DBase *base = GST_PSEUDO3D_BASE(self);
  DepthState *state = self->state;
  const bool counted_last = state->counts_current;
  state->counts_current = false;
  const int luma_threshold = p3d::bar_luma_threshold(p3d::gst::yuv_params(&base->in_info));
#if HAVE_CUDA
  if (path == GST_PSEUDO3D_PATH_GPU) {
    p3d::CudaStatus st;
    if (state->bars.previous_due() && state->bar_counts_gpu.take(&state->counts, &st))
      state->bars.observe(state->counts);
    if (st.ok()) st = state->bar_counts_gpu.count(view, luma_threshold, base->gpu->stream());
    if (st.ok() && state->bars.counted() && state->bar_counts_gpu.take(&state->counts, &st))
      state->bars.observe(state->counts);
    return st.ok() ? GST_FLOW_OK : p3d::gst::post_cuda_error(base, st, "counting the bars");
  }
#else
  (void)path;
#endif
  if (state->bars.previous_due()) state->bars.observe(state->counts);
  if (!counted_last) changes = nullptr;
  const bool unchanged = changes && !changes->any() && state->counts.rows.size() == static_cast<size_t>(view.height) &&
                         state->counts.cols.size() == static_cast<size_t>(view.width);
  if (!unchanged) p3d::bar_counts_cpu(view, luma_threshold, &state->counts, changes);
  state->counts_current = true;
  if (state->bars.counted()) state->bars.observe(state->counts);
  return GST_FLOW_OK;
}

// The rect this frame's depth is estimated in: with crop-bars=auto the
// bars decided from the counts observed so far (the whole
// picture until a measure is adopted); the whole picture where the rect's
// corner is not on a cell of the GPU's block grid (block-size over
// kBarAlign). A new rect restarts the estimator's history, which belongs
// to the previous picture (*moved says so).
static p3d::PixelRect frame_rect(GstPseudo3DDepth *self, GstPseudo3DPath path, const p3d::DepthParams &params,
                                 const p3d::FrameView &view, bool crop, bool *moved) {
  DepthState *state = self->state;
  if (!crop) {
    // Counts kept from before would stand for a frame they were not taken
    // of when crop-bars comes back on.
    state->bars.reset();
    state->counts = p3d::BarCounts();
  }
  p3d::PixelRect rect = state->bars.active(view.width, view.height);
  const int shift = path == GST_PSEUDO3D_PATH_GPU ? p3d::block_grid_shift(params, rect.width(), rect.height()) : 0;
  rect = p3d::rect_on_cells(rect, shift, view.width, view.height);
  *moved = rect != state->estimated_rect;
  if (*moved) {
    if (!state->estimated_rect.empty())
      GST_DEBUG_OBJECT(self, "active picture %dx%d at %d,%d", rect.width(), rect.height(), rect.x0, rect.y0);
    state->cpu.reset();
#if HAVE_CUDA
    state->gpu.reset();
#endif
    state->last_plane.reset();
    state->estimated_rect = rect;
  }
  return rect;
}

// A new plane for this frame's depth, active rect set (the outside 0).
static p3d::gst::DepthPlanePtr new_plane(GstPseudo3DDepth *self, GstPseudo3DPath path, const p3d::FrameView &view,
                                         p3d::PixelRect rect, int shift) {
  GstPseudo3DBase *base = GST_PSEUDO3D_BASE(self);
  p3d::gst::DepthPlanePtr plane = p3d::gst::new_depth(base, self->state->pool, path, view.width, view.height, shift);
  if (plane && !p3d::gst::set_active(base, plane.get(), rect)) plane.reset();
  return plane;
}

// method=edges: frame unchanged, depth attached.
static GstFlowReturn process_ip(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *buf,
                                GstVideoFrame *frame) {
  GstPseudo3DDepth *self = GST_PSEUDO3D_DEPTH(base);
  const p3d::FrameView view = p3d::gst::frame_view(frame);
  // Depth supplied upstream for this very frame is kept; one that no longer
  // fits (another size or memory) is replaced by a fresh estimate.
  if (p3d::gst::depth_fits(base, pseudo3d_buffer_get_depth(buf), path, view.width, view.height))
    return GST_FLOW_OK;
  // Automatic block sizes are the frame's, inside bars too.
  const p3d::DepthParams params = p3d::frame_scaled(frame_params(self), view.width, view.height);
  const bool crop = crop_bars(self);
  const p3d::gst::AdaptiveSettings adaptive = p3d::gst::adaptive_settings(base);
  DepthState *state = self->state;
  // On the CPU, while frames keep changing, uncompared (ChangeBackOff).
  const bool adaptive_cpu = path == GST_PSEUDO3D_PATH_CPU && state->history.begin(adaptive.on);
  p3d::ChangeMap changes;
  if (adaptive_cpu) changes = state->history.compare(view, nullptr, adaptive.tolerance);
  if (!crop) state->counts_current = false;  // the counts fall behind the history
  if (crop && observe_bars(self, path, view, adaptive_cpu ? &changes : nullptr) != GST_FLOW_OK) return GST_FLOW_ERROR;
  bool moved = false;
  const p3d::PixelRect rect = frame_rect(self, path, params, view, crop, &moved);
  const p3d::FrameView active = p3d::sub_frame(view, rect);
  if (adaptive_cpu) {
    // Only the blocks of changed tiles are summed again; when no block
    // depth changed the frame gets the previous plane itself. A moved
    // rect starts over (frame_rect restarted the estimator): every tile.
    if (moved) changes.mark_all();
    const p3d::ChangeMap active_changes = changes.cropped(rect);
    const p3d::TemporalDecision d = state->cpu.estimate_blocks(params, active, &active_changes);
    GST_LOG_OBJECT(self, "temporal decision %d, %.0f%% of the tiles changed", static_cast<int>(d),
                   100.0 * changes.fraction());
    if (state->cpu.output_changed() || !p3d::gst::depth_fits(base, state->last_plane.get(), path, view.width, view.height)) {
      p3d::gst::DepthPlanePtr plane = new_plane(self, path, view, rect, 0);
      if (!plane) return GST_FLOW_ERROR;
      state->cpu.expand(p3d::sub_image(plane->view(), rect));
      state->last_plane = std::move(plane);
    }
    pseudo3d_buffer_set_depth(buf, state->last_plane);
    return GST_FLOW_OK;
  }
  // (On the CPU history.begin() dropped the history: backing off, it kept
  // the back-off; with adaptive=false it reset that too.)
  if (path != GST_PSEUDO3D_PATH_CPU) state->history.reset();
  state->last_plane.reset();
  // On CUDA memory the plane holds a value a block (no full-size copy;
  // depth_plane.h) where the block is a power of two.
  p3d::gst::DepthPlanePtr plane =
      new_plane(self, path, view, rect, p3d::block_grid_shift(params, rect.width(), rect.height()));
  if (!plane) {
#if HAVE_CUDA
    // The frame goes back upstream: the bar counts reading it end first.
    if (path == GST_PSEUDO3D_PATH_GPU) state->bar_counts_gpu.settle();
#endif
    return GST_FLOW_ERROR;
  }
#if HAVE_CUDA
  if (path == GST_PSEUDO3D_PATH_GPU) {
    // Adaptive: the frame compared on the device, and only the feature
    // blocks of changed tiles summed again (a moved rect restarted the
    // estimator, which then sums every block); while frames keep
    // changing, uncompared (ChangeBackOff).
    const bool compare = adaptive.on && state->backoff_gpu.compare_next();
    if (!compare) state->history_gpu.reset();
    const GstFlowReturn ret = p3d::gst::run_gpu(base, "estimating depth", [&]() -> p3d::CudaStatus {
      cudaStream_t stream = base->gpu->stream();
      auto estimate = [&]() -> p3d::CudaStatus {
        p3d::TileFlags changed;
        if (compare) {
          P3D_CUDA_TRY_STATUS(state->history_gpu.compare(view, adaptive.tolerance, state->changes_gpu, stream));
          P3D_CUDA_TRY_STATUS(state->changes_gpu.summarize(stream));
          changed = state->changes_gpu.flags().offset(rect.x0, rect.y0);
        }
        return state->gpu.estimate(params, active, p3d::sub_grid(plane->grid(), rect), stream,
                                   compare ? &changed : nullptr);
      };
      // The bar counts ran beside the estimate; what comes after the depth
      // (and the frame's release) waits for them.
      const p3d::CudaStatus st = estimate();
      const p3d::CudaStatus joined = state->bar_counts_gpu.join(stream);
      return st.ok() ? joined : st;
    });
    if (ret != GST_FLOW_OK) {
      // The frame's copy may be recorded while the estimator's features
      // are not: both start afresh.
      state->history_gpu.reset();
      state->gpu.reset();
      return ret;
    }
    if (compare && state->history_gpu.compared())
      state->backoff_gpu.observe(state->changes_gpu.last_share() > 0);
  } else
#endif
  {
    const p3d::TemporalDecision d = state->cpu.estimate(params, active, p3d::sub_image(plane->view(), rect));
    GST_LOG_OBJECT(self, "temporal decision %d", static_cast<int>(d));
  }
  pseudo3d_buffer_set_depth(buf, std::move(plane));
  return GST_FLOW_OK;
}

// method=rgbd: copy the colour half, attach the grey half as depth.
// RGBD is a copy and a grey conversion: on system memory it stays on the CPU.
static GstFlowReturn process(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *, GstVideoFrame *in,
                             GstVideoFrame *out) {
  GstPseudo3DDepth *self = GST_PSEUDO3D_DEPTH(base);
  const int half = GST_VIDEO_FRAME_WIDTH(out);
  // The grey half: set_info checked that it starts on a chroma sample.
  const p3d::FrameView grey =
      p3d::sub_frame(p3d::gst::frame_view(in), p3d::PixelRect{half, 0, 2 * half, GST_VIDEO_FRAME_HEIGHT(in)});
  const p3d::YuvToRgb yuv = p3d::gst::yuv_params(&base->in_info);
  p3d::gst::DepthPlanePtr plane =
      p3d::gst::new_depth(base, self->state->pool, path, half, GST_VIDEO_FRAME_HEIGHT(out));
  if (!plane) return GST_FLOW_ERROR;
#if HAVE_CUDA
  if (path == GST_PSEUDO3D_PATH_GPU) {
    const GstFlowReturn ret = p3d::gst::run_gpu(base, "reading RGBD depth", [&]() -> p3d::CudaStatus {
      for (guint i = 0; i < GST_VIDEO_FRAME_N_PLANES(out); ++i)
        P3D_CUDA_TRY(cudaMemcpy2DAsync(GST_VIDEO_FRAME_PLANE_DATA(out, i), GST_VIDEO_FRAME_PLANE_STRIDE(out, i),
                                       GST_VIDEO_FRAME_PLANE_DATA(in, i), GST_VIDEO_FRAME_PLANE_STRIDE(in, i),
                                       GST_VIDEO_FRAME_COMP_WIDTH(out, i) * GST_VIDEO_FRAME_COMP_PSTRIDE(out, i),
                                       GST_VIDEO_FRAME_COMP_HEIGHT(out, i), cudaMemcpyDeviceToDevice,
                                       base->gpu->stream()));
      return p3d::depth_from_grey_gpu(grey, yuv, plane->view(), base->gpu->stream());
    });
    if (ret != GST_FLOW_OK) return ret;
  } else
#endif
  {
    // The colour half is the left part of every plane: a plain copy.
    for (guint i = 0; i < GST_VIDEO_FRAME_N_PLANES(out); ++i) {
      const gsize row = GST_VIDEO_FRAME_COMP_WIDTH(out, i) * GST_VIDEO_FRAME_COMP_PSTRIDE(out, i);
      for (gint y = 0; y < GST_VIDEO_FRAME_COMP_HEIGHT(out, i); ++y)
        memcpy(static_cast<guint8 *>(GST_VIDEO_FRAME_PLANE_DATA(out, i)) + y * GST_VIDEO_FRAME_PLANE_STRIDE(out, i),
               static_cast<guint8 *>(GST_VIDEO_FRAME_PLANE_DATA(in, i)) + y * GST_VIDEO_FRAME_PLANE_STRIDE(in, i),
               row);
    }
    p3d::depth_from_grey_cpu(grey, yuv, plane->view());
  }
  if (!pseudo3d_buffer_set_depth(out->buffer, std::move(plane))) return GST_FLOW_ERROR;
  return GST_FLOW_OK;
}

static void release(GstPseudo3DBase *base) {
  DepthState *state = GST_PSEUDO3D_DEPTH(base)->state;
  state->history.reset();
  state->last_plane.reset();
  state->bars.reset();
  state->counts_current = false;
  state->estimated_rect = p3d::PixelRect();
  state->cpu = p3d::DepthEstimatorCpu();
#if HAVE_CUDA
  state->gpu = p3d::DepthEstimatorGpu();
  state->bar_counts_gpu.reset();
  state->history_gpu = p3d::FrameHistoryGpu();
  state->changes_gpu = p3d::ChangeMapGpu();
#endif
  state->pool.clear();
}

static void gst_pseudo3d_depth_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DDepth *self = GST_PSEUDO3D_DEPTH(object);
  gboolean reconfigure = FALSE;
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_METHOD:
      reconfigure = self->state->method.request(static_cast<GstPseudo3DDepthMethod>(g_value_get_enum(value)));
      break;
    case PROP_HYPOTHESIS: self->params.hypothesis = static_cast<p3d::Hypothesis>(g_value_get_enum(value)); break;
    case PROP_BLOCK_SIZE: self->params.block_size = g_value_get_int(value); break;
    case PROP_EDGE_THRESHOLD: self->params.edge_threshold = g_value_get_float(value); break;
    case PROP_REGION_WEIGHT: self->params.region_weight = g_value_get_float(value); break;
    case PROP_GROUND_CONTACT: self->params.ground_contact = g_value_get_float(value); break;
    case PROP_TEMPORAL_SMOOTHING: self->params.temporal_smoothing = g_value_get_float(value); break;
    case PROP_FEATURE_SMOOTHING: self->params.feature_smoothing = g_value_get_float(value); break;
    case PROP_STATIC_THRESHOLD: self->params.static_threshold = g_value_get_float(value); break;
    case PROP_CUT_THRESHOLD: self->params.cut_threshold = g_value_get_float(value); break;
    case PROP_CROP_BARS: self->crop_bars = static_cast<GstPseudo3DCropBars>(g_value_get_enum(value)); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
  if (reconfigure) gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));
}

static void gst_pseudo3d_depth_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DDepth *self = GST_PSEUDO3D_DEPTH(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_METHOD: g_value_set_enum(value, self->state->method.requested()); break;
    case PROP_HYPOTHESIS: g_value_set_enum(value, static_cast<gint>(self->params.hypothesis)); break;
    case PROP_BLOCK_SIZE: g_value_set_int(value, self->params.block_size); break;
    case PROP_EDGE_THRESHOLD: g_value_set_float(value, self->params.edge_threshold); break;
    case PROP_REGION_WEIGHT: g_value_set_float(value, self->params.region_weight); break;
    case PROP_GROUND_CONTACT: g_value_set_float(value, self->params.ground_contact); break;
    case PROP_TEMPORAL_SMOOTHING: g_value_set_float(value, self->params.temporal_smoothing); break;
    case PROP_FEATURE_SMOOTHING: g_value_set_float(value, self->params.feature_smoothing); break;
    case PROP_STATIC_THRESHOLD: g_value_set_float(value, self->params.static_threshold); break;
    case PROP_CUT_THRESHOLD: g_value_set_float(value, self->params.cut_threshold); break;
    case PROP_CROP_BARS: g_value_set_enum(value, self->crop_bars); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_depth_finalize(GObject *object) {
  delete GST_PSEUDO3D_DEPTH(object)->state;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_depth_class_init(GstPseudo3DDepthClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstPseudo3DBaseClass *base_class = GST_PSEUDO3D_BASE_CLASS(klass);
  const p3d::DepthParams d;
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);

  gobject_class->set_property = gst_pseudo3d_depth_set_property;
  gobject_class->get_property = gst_pseudo3d_depth_get_property;
  gobject_class->finalize = gst_pseudo3d_depth_finalize;

  g_object_class_install_property(
      gobject_class, PROP_METHOD,
      g_param_spec_enum("method", "Method",
                        "Where depth comes from: estimated from edges, or read from the right half of RGBD frames "
                        "(rgbd halves the output width: a change while playing renegotiates the caps before the "
                        "next frame; a stream whose width cannot be halved refuses rgbd with a warning and goes on)",
                        GST_TYPE_PSEUDO3D_DEPTH_METHOD, DEFAULT_METHOD, flags));
  g_object_class_install_property(
      gobject_class, PROP_HYPOTHESIS,
      g_param_spec_enum("hypothesis", "Depth-gradient hypothesis",
                        "Global depth layout assumed for the scene; each region takes its value where the region "
                        "comes nearest (see ground-contact)",
                        GST_TYPE_PSEUDO3D_HYPOTHESIS, static_cast<gint>(d.hypothesis), flags));
  g_object_class_install_property(
      gobject_class, PROP_BLOCK_SIZE,
      g_param_spec_int("block-size", "Block size",
                       "Side in pixels of the blocks that are grouped into regions (smaller: finer regions, slower); "
                       "0 = auto: one block per 540 pixels of the picture's shorter side, at least 2 (2 up to "
                       "1080p, 4 at 4K); 1 acts as 2",
                       0, 64, d.block_size, flags));
  g_object_class_install_property(
      gobject_class, PROP_EDGE_THRESHOLD,
      g_param_spec_float("edge-threshold", "Edge threshold",
                         "Colour difference (sum over R'G'B' of 8-bit block means; YUV input is converted, so it means "
                         "the same in every format) at which neighbouring blocks are split by an edge; 0 makes every "
                         "block its own region",
                         0.f, 765.f, d.edge_threshold, flags));
  g_object_class_install_property(
      gobject_class, PROP_REGION_WEIGHT,
      g_param_spec_float("region-weight", "Region weight",
                         "Share of the region's depth in a block's depth (the rest is the hypothesis at the "
                         "block): 1 = flat regions, 0 = pure hypothesis",
                         0.f, 1.f, d.region_weight, flags));
  g_object_class_install_property(
      gobject_class, PROP_GROUND_CONTACT,
      g_param_spec_float("ground-contact", "Ground contact",
                         "How a region's depth is taken from the hypothesis: 1 = at its nearest block (for "
                         "top-bottom its lowest, where an object stands on the ground), 0 = the mean over the "
                         "region, between = a blend",
                         0.f, 1.f, d.ground_contact, flags));
  g_object_class_install_property(
      gobject_class, PROP_TEMPORAL_SMOOTHING,
      g_param_spec_float("temporal-smoothing", "Temporal smoothing",
                         "Weight of the previous frame's depth in video (0 = none); reset at scene cuts",
                         0.f, 0.99f, d.temporal_smoothing, flags));
  g_object_class_install_property(
      gobject_class, PROP_FEATURE_SMOOTHING,
      g_param_spec_float("feature-smoothing", "Feature smoothing",
                         "Weight of the past frames in the block colours that edges compare (0 = this frame's "
                         "alone): averages out the noise that flips region edges on a static background; a "
                         "block whose colour moves by 8 levels or more starts afresh, as does every block at a "
                         "scene cut",
                         0.f, 0.99f, d.feature_smoothing, flags));
  g_object_class_install_property(
      gobject_class, PROP_STATIC_THRESHOLD,
      g_param_spec_float("static-threshold", "Static threshold",
                         "Mean absolute block difference (8-bit levels) up to which the scene counts as static "
                         "and the previous depth is reused without estimating",
                         0.f, 255.f, d.static_threshold, flags));
  g_object_class_install_property(
      gobject_class, PROP_CUT_THRESHOLD,
      g_param_spec_float("cut-threshold", "Scene-cut threshold",
                         "Mean absolute block difference (8-bit levels) from which a frame is a scene cut and the "
                         "depth history is dropped",
                         0.f, 255.f, d.cut_threshold, flags));

  g_object_class_install_property(
      gobject_class, PROP_CROP_BARS,
      g_param_spec_enum("crop-bars", "Crop bars",
                        "Letterbox and pillarbox bars: auto finds black bars on opposite sides over several frames "
                        "(a fade to black, a dark sky or a subtitle in a bar keeps the decision; a scene cut or new "
                        "caps decide afresh) and estimates depth on the picture between them only, so that no depth "
                        "edge comes from a bar; pseudo3dfilter and pseudo3dwarp then work on that picture too and "
                        "leave the bars as they are, unshifted in both views. off: the whole frame",
                        GST_TYPE_PSEUDO3D_CROP_BARS, DEFAULT_CROP_BARS, flags));

  gst_element_class_set_static_metadata(element_class, "pseudo3d depth estimation", "Filter/Effect/Video",
                                        "Estimates a depth map (or reads it from RGBD frames) and attaches it to "
                                        "each frame for pseudo-stereo rendering",
                                        "pseudo3d developers");
  GstCaps *caps = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, p3d::kMaxFrameSide);
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, caps));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, caps));
  gst_caps_unref(caps);

  base_class->transform_geometry = transform_geometry;
  base_class->set_info = set_info;
  base_class->frame_boundary = frame_boundary;
  base_class->process = process;
  base_class->process_ip = process_ip;
  base_class->release = release;

  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_depth_debug, "pseudo3ddepth", 0, "pseudo3d depth estimation");
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_DEPTH_METHOD, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_HYPOTHESIS, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_CROP_BARS, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_depth_init(GstPseudo3DDepth *self) {
  self->params = p3d::DepthParams();
  self->crop_bars = DEFAULT_CROP_BARS;
  self->state = new DepthState();
  GST_PSEUDO3D_BASE(self)->staged = &self->state->method;
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), DEFAULT_METHOD == GST_PSEUDO3D_DEPTH_METHOD_EDGES);
}
