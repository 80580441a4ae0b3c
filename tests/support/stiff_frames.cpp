#include "stiff_frames.h"

namespace p3d::test {

const char *pattern_name(Pattern p) {
  switch (p) {
    case Pattern::Black: return "black";
    case Pattern::White: return "white";
    case Pattern::Colour: return "colour";
    case Pattern::VStripes: return "1px vertical stripes";
    case Pattern::HStripes: return "1px horizontal stripes";
    case Pattern::Checker1: return "1px checkerboard";
    case Pattern::Checker8: return "8px checkerboard";
    default: return "noise";
  }
}

int pattern_level(Pattern p, int x, int y) {
  switch (p) {
    case Pattern::Black: return 0;
    case Pattern::VStripes: return (x & 1) * 255;
    case Pattern::HStripes: return (y & 1) * 255;
    case Pattern::Checker1: return ((x + y) & 1) * 255;
    case Pattern::Checker8: return (((x / 8) + (y / 8)) & 1) * 255;
    default: return 255;
  }
}

HostFrame make_frame(Pattern p, PixelFormat f, int w, int h, uint32_t seed) {
  HostFrame fr(f, w, h, 3);
  if (p == Pattern::Noise) {
    fr.fill_random(seed);
    return fr;
  }
  const FrameView v = fr.view();
  if (p == Pattern::Colour) {
    if (is_packed_rgb(f)) {
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) store_rgba(v, x, y, Rgba{90, 220, 40, 255});
      return fr;
    }
    fr.fill(60);  // Y' 60, Cb = Cr = 60: a saturated green, constant
    return fr;
  }
  fr.fill(128);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int level = pattern_level(p, x, y);
      if (is_packed_rgb(f)) {
        const uint8_t l = static_cast<uint8_t>(level);
        store_rgba(v, x, y, Rgba{l, l, l, 255});
      } else {
        v.plane[0][static_cast<size_t>(y) * v.stride[0] + x] = static_cast<uint8_t>(16 + (level * 219 + 127) / 255);
      }
    }
  return fr;
}

}  // namespace p3d::test
