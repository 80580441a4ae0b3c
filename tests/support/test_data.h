// Test data helpers: real images (Middlebury Aloe from opencv-doc, see
// scripts/get-test-data.sh) and comparison helpers shared by the suites.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "frame.h"
#include "host_frame.h"
#include "bilateral.h"
#include "pack.h"
#include "warp.h"

namespace p3d::test {

// Folder holding aloeL.jpg, aloeR.jpg, aloeGT.png, vtest.avi. Env
// P3D_DATA_DIR overrides the build-time default.
std::string data_dir();
// Loads a file from data_dir() (as cv::IMREAD_UNCHANGED would); fails the
// test (ADD_FAILURE) and returns an empty Mat when missing. A raw dump
// "<name>.p3draw" (write_raw_image) is read first when present: the GPU
// suites read only those, so they need no image codecs (Debian's
// libopencv-imgcodecs pulls in GDAL, too big to carry to a GPU machine).
cv::Mat load_data_image(const std::string &name);

// Decodes an image file; empty on failure. Two implementations: OpenCV's
// imread (CPU suites) and none (GPU suites, raw dumps only).
cv::Mat read_image_file(const std::string &path);
// Raw dump: a text line "P3DRAW <cols> <rows> <cv type>\n", then the rows.
bool write_raw_image(const std::string &path, const cv::Mat &m);
cv::Mat read_raw_image(const std::string &path);

// Largest |a - b| over all pixels and channels of two 8-bit images and the
// number of samples that differ by more than `tolerance`.
struct DiffStats {
  int max_abs = 0;
  long long over_tolerance = 0;
  long long samples = 0;
};
DiffStats compare_u8(const cv::Mat &a, const cv::Mat &b, int tolerance);
// Same for two float images.
struct FloatDiff {
  double max_abs = 0;
  long long nonfinite = 0;
};
FloatDiff compare_f32(const cv::Mat &a, const cv::Mat &b);

// A 16-bit BGR picture (CV_16UC3) whose samples use their low bits: ramps
// with noise in the low bits and four flat boxes (depth edges, holes), for
// the deep formats (HostFrame::from_bgr16).
cv::Mat deep_picture(int w, int h, uint32_t seed);

// The six 8-bit input formats, for parameterised tests (the CPU and the
// GPU take them); the deep ones (16-bit samples) the CPU path takes.
inline constexpr PixelFormat kAllFormats[] = {PixelFormat::NV12, PixelFormat::I420, PixelFormat::RGBA,
                                              PixelFormat::BGRA, PixelFormat::RGBx, PixelFormat::BGRx};
inline constexpr PixelFormat kDeepFormats[] = {PixelFormat::P010, PixelFormat::I420_10, PixelFormat::RGBA64};
inline constexpr PixelFormat kPackedFormats[] = {PixelFormat::RGBA, PixelFormat::BGRA, PixelFormat::RGBx,
                                                 PixelFormat::BGRx};
const char *format_name(PixelFormat f);

// Parameter structs from their fields, for compact test tables.
inline WarpParams warp_params(float max_disparity, float convergence, StereoView view, HoleFill fill) {
  WarpParams p;
  p.max_disparity = max_disparity;
  p.convergence = convergence;
  p.view = view;
  p.fill = fill;
  return p;
}
inline BilateralParams bilateral_params(int radius, float sigma_space, float sigma_range) {
  BilateralParams p;
  p.radius = radius;
  p.sigma_space = sigma_space;
  p.sigma_range = sigma_range;
  return p;
}

inline PackParams pack_params(PackLayout l, AnaglyphGlasses g = AnaglyphGlasses::RedCyan,
                              AnaglyphMethod m = AnaglyphMethod::Dubois, bool swap = false) {
  PackParams p;
  p.layout = l;
  p.glasses = g;
  p.method = m;
  p.swap_eyes = swap;
  return p;
}

// Every value of the stage enums, for exhaustive CPU and GPU tests.
inline constexpr PackLayout kAllLayouts[] = {
    PackLayout::Anaglyph,      PackLayout::SideBySide,     PackLayout::SideBySideHalf,    PackLayout::TopBottom,
    PackLayout::TopBottomHalf, PackLayout::RowInterleaved, PackLayout::ColumnInterleaved, PackLayout::Checkerboard,
    PackLayout::Left,          PackLayout::Right};
inline constexpr AnaglyphGlasses kAllGlasses[] = {AnaglyphGlasses::RedCyan, AnaglyphGlasses::GreenMagenta,
                                                  AnaglyphGlasses::AmberBlue};
inline constexpr AnaglyphMethod kAllMethods[] = {AnaglyphMethod::Dubois,       AnaglyphMethod::Color,
                                                 AnaglyphMethod::HalfColor,    AnaglyphMethod::Gray,
                                                 AnaglyphMethod::DuboisFfmpeg, AnaglyphMethod::DuboisLinear};
inline constexpr StereoInput kAllInputs[] = {StereoInput::SideBySide,     StereoInput::SideBySideHalf,
                                             StereoInput::TopBottom,      StereoInput::TopBottomHalf,
                                             StereoInput::RowInterleaved, StereoInput::ColumnInterleaved,
                                             StereoInput::Checkerboard};
inline constexpr HoleFill kAllFills[] = {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::NeighborAverage,
                                          HoleFill::None};
inline constexpr StereoView kAllViews[] = {StereoView::Both, StereoView::Left, StereoView::Right};

}  // namespace p3d::test
