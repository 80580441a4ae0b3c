#include "pack.h"

#include <stdexcept>

#include <opencv2/core.hpp>

namespace p3d {

namespace {

constexpr float kLuma[3] = {0.299f, 0.587f, 0.114f};  // rgb_luma's weights

void set_row(float *m, int row, float r, float g, float b) {
  m[3 * row] = r;
  m[3 * row + 1] = g;
  m[3 * row + 2] = b;
}
void pass_channel(float *m, int c) { m[3 * c + c] = 1.f; }
void luma_to_channel(float *m, int c) { set_row(m, c, kLuma[0], kLuma[1], kLuma[2]); }

// Dubois' least-squares projections (E. Dubois, "A projection method to
// generate anaglyph stereo images", ICASSP 2001, and his published
// matrices for the three glasses), applied to 0..255 R'G'B'.
void dubois(AnaglyphGlasses g, float *l, float *r) {
  static const float kRedCyan[2][9] = {
      {0.437f, 0.449f, 0.164f, -0.062f, -0.062f, -0.024f, -0.048f, -0.050f, -0.017f},
      {-0.011f, -0.032f, -0.007f, 0.377f, 0.761f, 0.009f, -0.026f, -0.093f, 1.234f}};
  static const float kGreenMagenta[2][9] = {
      {-0.062f, -0.158f, -0.039f, 0.284f, 0.668f, 0.143f, -0.015f, -0.027f, 0.021f},
      {0.529f, 0.705f, 0.024f, -0.016f, -0.015f, -0.065f, 0.009f, 0.075f, 0.937f}};
  static const float kAmberBlue[2][9] = {
      {1.062f, -0.205f, 0.299f, -0.026f, 0.908f, 0.068f, -0.038f, -0.173f, 0.022f},
      {-0.016f, -0.123f, -0.017f, 0.006f, 0.062f, -0.017f, 0.094f, 0.185f, 0.911f}};
  const float(*m)[9] = g == AnaglyphGlasses::GreenMagenta ? kGreenMagenta
                       : g == AnaglyphGlasses::AmberBlue  ? kAmberBlue
                                                          : kRedCyan;
  for (int i = 0; i < 9; ++i) {
    l[i] = m[0][i];
    r[i] = m[1][i];
  }
}

// Channels each eye's filter passes (0 = R, 1 = G, 2 = B).
struct Filters {
  bool left[3];
  bool right[3];
  bool single_colour_left;  // which eye looks through the one-channel filter
};
Filters filters(AnaglyphGlasses g) {
  switch (g) {
    case AnaglyphGlasses::GreenMagenta: return {{false, true, false}, {true, false, true}, true};
    case AnaglyphGlasses::AmberBlue: return {{true, true, false}, {false, false, true}, false};
    case AnaglyphGlasses::RedCyan:
    default: return {{true, false, false}, {false, true, true}, true};
  }
}

// An eye's matrix built from its filter: each passed channel gets either the
// same channel (colour) or the luma.
void filter_matrix(const bool *passed, bool as_luma, float *m) {
  for (int c = 0; c < 3; ++c) {
    if (!passed[c]) continue;
    if (as_luma)
      luma_to_channel(m, c);
    else
      pass_channel(m, c);
  }
}

bool packed_rgb_valid(const FrameView &f) {
  return is_packed_rgb(f.format) && f.plane[0] != nullptr && f.width > 0 && f.height > 0 &&
         f.stride[0] >= 4 * f.width;
}

}  // namespace

AnaglyphMatrices anaglyph_matrices(AnaglyphGlasses g, AnaglyphMethod m) {
  AnaglyphMatrices am{};
  if (m == AnaglyphMethod::Dubois) {
    dubois(g, am.left, am.right);
    return am;
  }
  const Filters f = filters(g);
  const bool luma_left = m == AnaglyphMethod::Gray || (m == AnaglyphMethod::HalfColor && f.single_colour_left);
  const bool luma_right = m == AnaglyphMethod::Gray || (m == AnaglyphMethod::HalfColor && !f.single_colour_left);
  filter_matrix(f.left, luma_left, am.left);
  filter_matrix(f.right, luma_right, am.right);
  return am;
}

void pack_size(PackLayout layout, int view_width, int view_height, int *out_width, int *out_height) {
  *out_width = layout == PackLayout::SideBySide ? 2 * view_width : view_width;
  *out_height = layout == PackLayout::TopBottom ? 2 * view_height : view_height;
}

bool pack_args_valid(const PackParams &params, const FrameView &in, const FrameView &out) {
  const int layout = static_cast<int>(params.layout), glasses = static_cast<int>(params.glasses),
            method = static_cast<int>(params.method);
  if (layout < 0 || layout > static_cast<int>(PackLayout::Right)) return false;
  if (glasses < 0 || glasses > static_cast<int>(AnaglyphGlasses::AmberBlue)) return false;
  if (method < 0 || method > static_cast<int>(AnaglyphMethod::Gray)) return false;
  if (!packed_rgb_valid(in) || !packed_rgb_valid(out) || in.format != out.format) return false;
  if (in.width % 2 != 0) return false;
  int w = 0, h = 0;
  pack_size(params.layout, in.width / 2, in.height, &w, &h);
  return out.width == w && out.height == h;
}

void pack_cpu(const PackParams &params, const FrameView &in, const FrameView &out) {
  if (!pack_args_valid(params, in, out))
    throw std::invalid_argument("pack_cpu: frames do not match the layout (see pack_args_valid)");
  const AnaglyphMatrices am = anaglyph_matrices(params.glasses, params.method);
  cv::parallel_for_(cv::Range(0, out.height), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < out.width; ++x) store_rgba(out, x, y, pack_pixel(params, am, in, x, y));
  });
}

}  // namespace p3d
