// Depth as grey pictures, in and out.
//
// In (pseudo3ddepthmux): external depth (a depth camera, a depth file, an ML
// model's output) turned into the plugin's depth: float, 0 = far, 1 = near,
// the frame's size.
//
// Samples are 8- or 16-bit grey. The conventions met in the wild:
//   NearWhite  larger = nearer (Depth-Anything and most "depth map" images;
//              really inverse depth or disparity): d = s / smax;
//   NearDark   larger = farther (a Z-buffer rendered as grey): d = 1 - s / smax;
//   Metric     s is a distance (for example millimetres from a depth camera),
//              between `near` (d = 1) and `far` (d = 0) in the same unit; what
//              lies between is mapped linearly in 1/s, as disparity is
//              (d = (1/s - 1/far) / (1/near - 1/far)), clamped to [0, 1].
//              s = 0, which depth cameras write where they saw nothing, is
//              taken as far.
// A map of another size than the frame takes, for each pixel, the sample
// whose area holds the pixel's centre (OpenCV's INTER_NEAREST_EXACT). Not
// bilinear: depth between a near and a far object is no depth of either,
// and the warp would scatter such pixels between the two ("flying pixels").
// On Aloe from a half-size ground truth: nearest 24.31 dB, bilinear 23.87
// dB, either followed by pseudo3dfilter's defaults about 23.6 dB.
#pragma once

#include <cstdint>

#include "p3d_defs.h"
#include "enum_name.h"

namespace p3d {

enum class DepthConvention : int { NearWhite = 0, NearDark = 1, Metric = 2 };

inline constexpr EnumName<DepthConvention> kDepthConventionNames[] = {
    {DepthConvention::NearWhite, "near-white",
     "Larger is nearer (white = near: most depth maps, Depth-Anything)"},
    {DepthConvention::NearDark, "near-dark", "Larger is farther (dark = near: a Z-buffer)"},
    {DepthConvention::Metric, "metric",
     "Distance in any unit (a depth camera's millimetres), near..far mapped linearly in 1/distance; 0 = not seen, "
     "taken as far"},
};
P3D_CHECK_ENUM_NAMES(kDepthConventionNames);

struct DepthImportParams {
  DepthConvention convention = DepthConvention::NearWhite;
  float near = 500.f;   // Metric: distance of the nearest depth (d = 1), > 0
  float far = 10000.f;  // Metric: distance of the farthest depth (d = 0), > near
};

// One sample's depth; smax is 255 or 65535.
float import_depth_sample(const DepthImportParams &p, uint32_t s, uint32_t smax);

// `src` (8-bit when bits == 8, else 16-bit, any size) into `out` (its own size).
void import_depth_cpu(const DepthImportParams &p, const ImageView<const uint8_t> &src, int bits,
                      ImageView<float> out);

// Out (pseudo3ddepthout): depth as grey, white = near:
// s = round(clamp(d, 0, 1) * smax), smax 255 (bits 8) or 65535 (bits 16),
// NaN as 0 (far). `out` has `depth`'s size; 16-bit rows are uint16_t.
// import_depth_cpu (near-white) of the result gives d to within 0.5 / smax.
uint32_t export_depth_sample(float d, uint32_t smax);
void export_depth_cpu(const ImageView<const float> &depth, int bits, ImageView<uint8_t> out);

}  // namespace p3d
