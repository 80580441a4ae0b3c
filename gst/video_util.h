// The bridge between GStreamer video types and common/: formats, frame
// views of mapped GstVideoFrames, colorimetry, caps strings.
#pragma once

#include <gst/video/video.h>

#include "frame.h"

// Every format the stages take in system memory; CUDA memory carries all
// but RGBA64_LE (caps_all_domains, keep_cuda_formats).
#define P3D_ALL_FORMATS "{ NV12, I420, RGBA, BGRA, RGBx, BGRx, P010_10LE, I420_10LE, RGBA64_LE }"

namespace p3d::gst {

// Sample depths of formats: the 8-bit ones, and the deep ones (16-bit
// samples: P010_10LE, I420_10LE, RGBA64_LE), as bits of a mask.
enum FormatDepth : unsigned { kDepth8 = 1u, kDepth16 = 2u, kAnyDepth = 3u };
// Kinds of the formats a stage writes: packed RGB (a rendered pair, the
// pack's own input format), 4:2:0 Y'CbCr, or both.
enum class FormatKind { Packed, Yuv420, All };
// The formats of a kind at the depths of a mask, as a caps value string.
const char *formats_for(FormatKind kind, unsigned depths);
// The depths the format field of s names (kAnyDepth without one).
unsigned format_depths(const GstStructure *s);
// Leaves in the format field of s only the formats CUDA memory can hold
// (GStreamer 1.22's allocator aborts on any other, such as RGBA64_LE);
// false when none is left (s is then unusable).
bool keep_cuda_formats(GstStructure *s);
// Whether a negotiated format has deep samples.
inline bool is_deep_info(const GstVideoInfo *info) { return GST_VIDEO_INFO_COMP_DEPTH(info, 0) > 8; }

// FALSE for formats the plugin does not handle.
bool pixel_format_from_gst(GstVideoFormat f, PixelFormat *out);
// View of a mapped frame (host or device pointers, as mapped).
FrameView frame_view(const GstVideoFrame *frame);
// Y'CbCr -> R'G'B' of the info's colorimetry (BT.601 if unknown).
YuvToRgb yuv_params(const GstVideoInfo *info);
// R'G'B' -> Y'CbCr of the info's colorimetry (BT.601 if unknown).
RgbToYuv rgb_to_yuv(const GstVideoInfo *info);

// Raw video of `formats` up to max_side pixels wide and high, in both memory
// domains: CUDA memory first (preferred; keep_cuda_formats), then system
// memory.
GstCaps *caps_all_domains(const char *formats, int max_side, const char *extra_fields = nullptr);

}  // namespace p3d::gst
