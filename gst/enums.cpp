#include "enums.h"

#include "bilateral.h"
#include "depth_estimate.h"
#include "depth_grey.h"
#include "pack.h"
#include "warp.h"

// One registration helper for every enum: the tables below are the only
// per-type code.
#define P3D_DEFINE_ENUM(func, TypeName, ...)                              \
  GType func(void) {                                                      \
    static GType type = 0;                                                \
    if (g_once_init_enter(&type)) {                                       \
      static const GEnumValue values[] = {__VA_ARGS__, {0, NULL, NULL}};  \
      GType t = g_enum_register_static(TypeName, values);                 \
      g_once_init_leave(&type, t);                                        \
    }                                                                     \
    return type;                                                          \
  }

P3D_DEFINE_ENUM(gst_pseudo3d_hypothesis_get_type, "GstPseudo3DHypothesis",
                {(gint)p3d::Hypothesis::TopBottom, "Far at the top, near at the bottom", "top-bottom"},
                {(gint)p3d::Hypothesis::LeftRight, "Far at the left, near at the right", "left-right"},
                {(gint)p3d::Hypothesis::CenterNear, "Near in the centre, far at the edges", "center-near"},
                {(gint)p3d::Hypothesis::Flat, "No gradient (regions only)", "flat"})

P3D_DEFINE_ENUM(gst_pseudo3d_depth_method_get_type, "GstPseudo3DDepthMethod",
                {GST_PSEUDO3D_DEPTH_METHOD_EDGES, "Estimate from edges and a depth-gradient hypothesis", "edges"},
                {GST_PSEUDO3D_DEPTH_METHOD_RGBD,
                 "Input holds colour (left half) and depth as grey (right half, white = near)", "rgbd"})

P3D_DEFINE_ENUM(gst_pseudo3d_filter_mode_get_type, "GstPseudo3DFilterMode",
                {(gint)p3d::BilateralMode::Exact, "Every pixel of the (2r+1) x (2r+1) window", "exact"},
                {(gint)p3d::BilateralMode::Separable, "A row pass, then a column pass: 2 (2r+1) taps", "separable"})

P3D_DEFINE_ENUM(gst_pseudo3d_depth_convention_get_type, "GstPseudo3DDepthConvention",
                {(gint)p3d::DepthConvention::NearWhite, "Larger is nearer (white = near: most depth maps, "
                 "Depth-Anything)", "near-white"},
                {(gint)p3d::DepthConvention::NearDark, "Larger is farther (dark = near: a Z-buffer)", "near-dark"},
                {(gint)p3d::DepthConvention::Metric,
                 "Distance in any unit (a depth camera's millimetres), near..far mapped linearly in 1/distance; "
                 "0 = not seen, taken as far",
                 "metric"})

P3D_DEFINE_ENUM(gst_pseudo3d_view_get_type, "GstPseudo3DView",
                {(gint)p3d::StereoView::Both, "Synthesize both views, half the parallax each", "both"},
                {(gint)p3d::StereoView::Left, "Input is the right view; synthesize the left", "left"},
                {(gint)p3d::StereoView::Right, "Input is the left view; synthesize the right", "right"})

P3D_DEFINE_ENUM(gst_pseudo3d_fill_get_type, "GstPseudo3DFill",
                {(gint)p3d::HoleFill::Background, "Extend the background side of each row (depth-aware; cheapest, streaks along rows)", "background"},
                {(gint)p3d::HoleFill::BackgroundSmooth,
                 "Background side of each row, averaged across rows (depth-aware; best quality; costs more than "
                 "background: docs/benchmarks.md)",
                 "background-smooth"},
                {(gint)p3d::HoleFill::NeighborAverage, "Iterative neighbour-average inpainting", "neighbor-average"},
                {(gint)p3d::HoleFill::None, "Leave holes, painted magenta (diagnostics)", "none"})

P3D_DEFINE_ENUM(gst_pseudo3d_layout_get_type, "GstPseudo3DLayout",
                {(gint)p3d::PackLayout::Anaglyph, "Anaglyph (see glasses and anaglyph-method)", "anaglyph"},
                {(gint)p3d::PackLayout::SideBySide, "Side by side, full resolution (2W x H)", "side-by-side"},
                {(gint)p3d::PackLayout::SideBySideHalf, "Side by side, half width (anamorphic)", "side-by-side-half"},
                {(gint)p3d::PackLayout::TopBottom, "Top and bottom, full resolution (W x 2H)", "top-bottom"},
                {(gint)p3d::PackLayout::TopBottomHalf, "Top and bottom, half height (anamorphic)", "top-bottom-half"},
                {(gint)p3d::PackLayout::RowInterleaved, "Even rows left view, odd rows right view", "row-interleaved"},
                {(gint)p3d::PackLayout::ColumnInterleaved, "Even columns left, odd columns right",
                 "column-interleaved"},
                {(gint)p3d::PackLayout::Checkerboard, "Checkerboard of the two views", "checkerboard"},
                {(gint)p3d::PackLayout::Left, "Left view only", "left"},
                {(gint)p3d::PackLayout::Right, "Right view only", "right"})

P3D_DEFINE_ENUM(gst_pseudo3d_glasses_get_type, "GstPseudo3DGlasses",
                {(gint)p3d::AnaglyphGlasses::RedCyan, "Red (left) / cyan (right)", "red-cyan"},
                {(gint)p3d::AnaglyphGlasses::GreenMagenta, "Green (left) / magenta (right)", "green-magenta"},
                {(gint)p3d::AnaglyphGlasses::AmberBlue, "Amber (left) / blue (right)", "amber-blue"})

P3D_DEFINE_ENUM(gst_pseudo3d_anaglyph_method_get_type, "GstPseudo3DAnaglyphMethod",
                {(gint)p3d::AnaglyphMethod::Dubois,
                 "Dubois least squares, the first published matrices, on gamma-encoded values (least ghosting)",
                 "dubois"},
                {(gint)p3d::AnaglyphMethod::Color, "Full colour through the filters", "color"},
                {(gint)p3d::AnaglyphMethod::HalfColor, "Half colour (luma behind the single-colour filter)",
                 "half-color"},
                {(gint)p3d::AnaglyphMethod::Gray, "Grey (luma for both eyes)", "gray"},
                {(gint)p3d::AnaglyphMethod::DuboisFfmpeg,
                 "Dubois, the revised matrices of ffmpeg's and mpv's stereo3d (arcd, agmd, aybd)", "dubois-ffmpeg"},
                {(gint)p3d::AnaglyphMethod::DuboisLinear, "Dubois in linear light (sRGB decoded, mixed, clipped, encoded)",
                 "dubois-linear"})

#define P3D_INPUT(value, desc, nick) {static_cast<gint>(p3d::StereoInput::value) + 1, desc, nick}
P3D_DEFINE_ENUM(gst_pseudo3d_input_layout_get_type, "GstPseudo3DInputLayout",
                {GST_PSEUDO3D_INPUT_LAYOUT_FROM_CAPS, "From the caps' multiview-mode and multiview-flags",
                 "from-caps"},
                P3D_INPUT(SideBySide, "Side by side, full resolution", "side-by-side"),
                P3D_INPUT(SideBySideHalf, "Side by side, each view squeezed to half width", "side-by-side-half"),
                P3D_INPUT(TopBottom, "Top and bottom, full resolution", "top-bottom"),
                P3D_INPUT(TopBottomHalf, "Top and bottom, each view squeezed to half height", "top-bottom-half"),
                P3D_INPUT(RowInterleaved, "Rows alternate between the views", "row-interleaved"),
                P3D_INPUT(ColumnInterleaved, "Columns alternate between the views", "column-interleaved"),
                P3D_INPUT(Checkerboard, "Checkerboard of the two views", "checkerboard"))
#undef P3D_INPUT

P3D_DEFINE_ENUM(gst_pseudo3d_processing_get_type, "GstPseudo3DProcessing",
                {GST_PSEUDO3D_PROCESSING_AUTO, "GPU when a CUDA device and nvcodec are available, else CPU", "auto"},
                {GST_PSEUDO3D_PROCESSING_CPU, "CPU (CUDA-memory input still runs on the GPU)", "cpu"},
                {GST_PSEUDO3D_PROCESSING_GPU, "GPU; an error if none is available", "gpu"})
