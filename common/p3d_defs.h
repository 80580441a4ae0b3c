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

}  // namespace p3d
