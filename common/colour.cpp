// Colour conversion parameters and plane geometry of the supported formats.
#include "frame.h"

namespace p3d {

// From Kr/Kb (BT.601: 0.299/0.114, BT.709: 0.2126/0.0722, ...):
//   R = Y + 2(1-Kr) Cr,  B = Y + 2(1-Kb) Cb,  G = (Y - Kr R - Kb B) / Kg
//   => G = Y - 2Kb(1-Kb)/Kg Cb - 2Kr(1-Kr)/Kg Cr,  Kg = 1 - Kr - Kb.
// Limited range: Y in 16..235 (219 levels), Cb/Cr in 16..240 (224 levels);
// 10 bits: 64..940 (876) and 64..960 (896), full range 0..1023, the
// result in 16-bit units.
YuvToRgb yuv_to_rgb_params(double kr, double kb, bool full_range, int bits) {
  YuvToRgb m;
  const double kg = 1.0 - kr - kb;
  m.rv = static_cast<float>(2.0 * (1.0 - kr));
  m.bu = static_cast<float>(2.0 * (1.0 - kb));
  m.gu = static_cast<float>(-2.0 * kb * (1.0 - kb) / kg);
  m.gv = static_cast<float>(-2.0 * kr * (1.0 - kr) / kg);
  if (bits > 8) {
    m.top = 65535;
    m.c_offset = 512.f;
    m.y_offset = full_range ? 0.f : 64.f;
    m.y_scale = static_cast<float>(65535.0 / (full_range ? 1023.0 : 876.0));
    m.c_scale = static_cast<float>(65535.0 / (full_range ? 1023.0 : 896.0));
  } else if (full_range) {
    m.y_offset = 0.f;
    m.y_scale = 1.f;
    m.c_scale = 1.f;
  } else {
    m.y_offset = 16.f;
    m.y_scale = static_cast<float>(255.0 / 219.0);
    m.c_scale = static_cast<float>(255.0 / 224.0);
  }
  return m;
}

RgbToYuv rgb_to_yuv_params(double kr, double kb, bool full_range, int bits) {
  RgbToYuv m;
  m.kr = static_cast<float>(kr);
  m.kb = static_cast<float>(kb);
  m.kg = static_cast<float>(1.0 - kr - kb);
  m.cb = static_cast<float>(1.0 / (2.0 * (1.0 - kb)));
  m.cr = static_cast<float>(1.0 / (2.0 * (1.0 - kr)));
  if (bits > 8) {
    m.top = 1023;
    m.c_offset = 512.f;
    m.y_offset = full_range ? 0.f : 64.f;
    m.y_scale = static_cast<float>((full_range ? 1023.0 : 876.0) / 65535.0);
    m.c_scale = static_cast<float>((full_range ? 1023.0 : 896.0) / 65535.0);
  } else if (full_range) {
    m.y_offset = 0.f;
    m.y_scale = 1.f;
    m.c_scale = 1.f;
  } else {
    m.y_offset = 16.f;
    m.y_scale = static_cast<float>(219.0 / 255.0);
    m.c_scale = static_cast<float>(224.0 / 255.0);
  }
  return m;
}

int frame_plane_count(PixelFormat f) {
  switch (f) {
    case PixelFormat::NV12:
    case PixelFormat::P010: return 2;
    case PixelFormat::I420:
    case PixelFormat::I420_10: return 3;
    default: return 1;
  }
}

void frame_plane_size(PixelFormat f, int width, int height, int plane, int *bytes_per_row, int *rows) {
  const int cw = (width + 1) / 2, ch = (height + 1) / 2, sb = sample_bytes(f);
  if (is_packed_rgb(f)) {
    *bytes_per_row = packed_pixel_bytes(f) * width;
    *rows = height;
    return;
  }
  *bytes_per_row = sb * (plane == 0 ? width : (is_semi_planar(f) ? 2 * cw : cw));
  *rows = plane == 0 ? height : ch;
}

void high_byte_copy_cpu(const FrameView &src, const FrameView &out) {
  for (int p = 0; p < frame_plane_count(src.format); ++p) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(src.format, src.width, src.height, p, &row_bytes, &rows);
    for (int y = 0; y < rows; ++y) {
      const uint8_t *in = src.plane[p] + static_cast<size_t>(y) * src.stride[p];
      uint8_t *to = out.plane[p] + static_cast<size_t>(y) * out.stride[p];
      for (int i = 0; i < row_bytes / 2; ++i) to[i] = high_byte(src.format, load_u16(in, i));
    }
  }
}

}  // namespace p3d
