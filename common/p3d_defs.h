// Basic shared definitions: host/device qualifiers and a pitched 2-D view.
// Everything in common/ that a CUDA kernel also calls is marked P3D_HD, so the
// CPU reference and the kernel run literally the same per-pixel code.
#pragma once

#include <cstddef>
#include <cmath>
#include <cstdint>
#include <type_traits>

#if defined(__CUDACC__)
#define P3D_HD __host__ __device__ __forceinline__
#else
#define P3D_HD inline
#endif

namespace p3d {

// A 2-D array of T with a row pitch in bytes (pitch >= width * sizeof(T)).
// The pointer may be host or device memory; the view never owns it.
template <typename T>
struct ImageView {
  T *data = nullptr;
  int width = 0;
  int height = 0;
  size_t pitch = 0;  // bytes between the starts of two rows

  P3D_HD T *row(int y) const {
    return reinterpret_cast<T *>(reinterpret_cast<unsigned char *>(
        const_cast<typename std::remove_const<T>::type *>(data)) + static_cast<size_t>(y) * pitch);
  }
  P3D_HD T &at(int x, int y) const { return row(y)[x]; }
  P3D_HD bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
};

template <typename T>
P3D_HD ImageView<const T> as_const(const ImageView<T> &v) {
  return ImageView<const T>{v.data, v.width, v.height, v.pitch};
}

// A depth map of a width x height picture held on a grid of cells of
// 2^shift x 2^shift pixels, one value a cell: pixel (x, y) has
// cells.at(x >> shift, y >> shift); shift 0 is the full-size map. The
// estimator's block depths and the filter's coarse-grid results are
// constant over such cells, so the GPU stages hand them on as they are,
// not copied out to every pixel (docs/architecture.md, "Depth between the
// stages").
template <typename T>
struct DepthGrid {
  ImageView<T> cells;  // grid_cells(width, shift) x grid_cells(height, shift)
  int width = 0;
  int height = 0;
  int shift = 0;

  // The cells of pixel row y.
  P3D_HD T *cell_row(int y) const { return cells.row(y >> shift); }
  P3D_HD T &at(int x, int y) const { return cell_row(y)[x >> shift]; }
  P3D_HD bool empty() const { return cells.empty() || width <= 0 || height <= 0; }
};

// A rectangle of pixels [x0, x1) x [y0, y1).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  P3D_HD bool empty() const { return x1 <= x0 || y1 <= y0; }
  P3D_HD int width() const { return x1 - x0; }
  P3D_HD int height() const { return y1 - y0; }
};
P3D_HD PixelRect whole_picture(int width, int height) { return PixelRect{0, 0, width, height}; }
// r grown by `by` pixels on every side, clipped to a width x height picture.
P3D_HD PixelRect grown(const PixelRect &r, int by, int width, int height) {
  return PixelRect{r.x0 - by > 0 ? r.x0 - by : 0, r.y0 - by > 0 ? r.y0 - by : 0,
                   r.x1 + by < width ? r.x1 + by : width, r.y1 + by < height ? r.y1 + by : height};
}
P3D_HD bool operator==(const PixelRect &a, const PixelRect &b) {
  return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1;
}
P3D_HD bool operator!=(const PixelRect &a, const PixelRect &b) { return !(a == b); }

// The part of a view inside r (r lies within the view).
template <typename T>
P3D_HD ImageView<T> sub_image(const ImageView<T> &v, PixelRect r) {
  return ImageView<T>{v.row(r.y0) + r.x0, r.width(), r.height(), v.pitch};
}

// Cells along an axis of `pixels` at a shift.
P3D_HD int grid_cells(int pixels, int shift) {
  return static_cast<int>((static_cast<long long>(pixels) + (1LL << shift) - 1) >> shift);
}

// A full-size map as a grid (shift 0).
template <typename T>
P3D_HD DepthGrid<T> full_grid(const ImageView<T> &v) {
  return DepthGrid<T>{v, v.width, v.height, 0};
}
template <typename T>
P3D_HD DepthGrid<const T> as_const(const DepthGrid<T> &g) {
  return DepthGrid<const T>{as_const(g.cells), g.width, g.height, g.shift};
}
// The part of a grid's picture inside r, whose corner (x0, y0) must lie
// on a cell corner (multiples of 2^shift; sub_grid_fits).
template <typename T>
P3D_HD bool sub_grid_fits(const DepthGrid<T> &g, PixelRect r) {
  const int cell = 1 << g.shift;
  return r.x0 % cell == 0 && r.y0 % cell == 0;
}
template <typename T>
P3D_HD DepthGrid<T> sub_grid(const DepthGrid<T> &g, PixelRect r) {
  const PixelRect cells{r.x0 >> g.shift, r.y0 >> g.shift, (r.x0 >> g.shift) + grid_cells(r.width(), g.shift),
                        (r.y0 >> g.shift) + grid_cells(r.height(), g.shift)};
  return DepthGrid<T>{sub_image(g.cells, cells), r.width(), r.height(), g.shift};
}
// Whether g's cells have the size its picture and shift call for.
template <typename T>
P3D_HD bool grid_fits(const DepthGrid<T> &g) {
  return g.shift >= 0 && g.shift < 16 && g.cells.width == grid_cells(g.width, g.shift) &&
         g.cells.height == grid_cells(g.height, g.shift);
}
// A grid copied out to every pixel of a full-size map of its picture's
// size (host code: pseudo3ddepthout's read-back, the tests).
template <typename T>
inline void expand_grid(const DepthGrid<const T> &g, const ImageView<T> &out) {
  for (int y = 0; y < g.height; ++y) {
    const T *cells = g.cell_row(y);
    T *row = out.row(y);
    for (int x = 0; x < g.width; ++x) row[x] = cells[x >> g.shift];
  }
}

// log2(step) for a power-of-two step >= 1, else -1: the grids a stage can
// hand on at its step.
P3D_HD int step_shift(int step) {
  int s = 0;
  while (step > 1 && (step & 1) == 0) {
    step >>= 1;
    ++s;
  }
  return step == 1 ? s : -1;
}

template <typename T>
P3D_HD T clamp_value(T v, T lo, T hi) {
  return v < lo ? lo : (v > hi ? hi : v);
}

// ceilf(v) as an int, for |v| < 2^31 (the caller's range; exact there).
// The device has an instruction for it. The host code is built for plain
// x86-64, which has no rounding instruction before SSE4.1, and there ceilf
// is a branchy sequence of about 18 instructions; truncating and adding one
// where that fell below v gives the same integer for a few.
P3D_HD int ceil_to_int(float v) {
#ifdef __CUDA_ARCH__
  return static_cast<int>(ceilf(v));
#else
  const int i = static_cast<int>(v);  // toward zero: v's ceiling, or one below it for positive non-integers
  return static_cast<float>(i) < v ? i + 1 : i;
#endif
}

// Round a float to the nearest 8-bit level, saturating. floorf(x + 0.5f) is
// used on both sides (instead of lrintf/__float2int_rn) so that host and
// device round halves the same way.
P3D_HD uint8_t to_u8(float v) {
  v = v < 0.f ? 0.f : (v > 255.f ? 255.f : v);
  return static_cast<uint8_t>(static_cast<int>(v + 0.5f));
}

// The same to an integer level 0..top (16-bit samples: 65535, 10-bit
// codes: 1023).
P3D_HD int to_level(float v, int top) {
  const float t = static_cast<float>(top);
  v = v < 0.f ? 0.f : (v > t ? t : v);
  return static_cast<int>(v + 0.5f);
}

}  // namespace p3d
