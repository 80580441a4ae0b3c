#include "stereo_frames.h"

#include <algorithm>

namespace p3d::test {

namespace {

Rgba at(const HostFrame &f, int x, int y) { return load_rgba(f.view(), x, y, YuvToRgb()); }

Rgba weighted(Rgba a, int wa, Rgba b, int wb) {
  const int n = wa + wb;
  auto mix = [&](int u, int v) { return static_cast<uint8_t>((wa * u + wb * v + n / 2) / n); };
  return Rgba{mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b), mix(a.a, b.a)};
}

// Linear interpolation at display position X of the n squeezed samples
// sample(0..n-1) of one view: sample i = X/2 weighs 3, its neighbour on X's
// side 1; past the last sample, the last sample.
template <typename Sample>
Rgba unsqueezed(int X, int n, const Sample &sample) {
  if (n <= 0) return Rgba{};
  if (X / 2 >= n) return sample(n - 1);
  const int i = X / 2, j = std::clamp(X % 2 ? i + 1 : i - 1, 0, n - 1);
  return weighted(sample(i), 3, sample(j), 1);
}

}  // namespace

HostFrame arrange_pair(StereoInput input, bool right_first, const HostFrame &l, const HostFrame &r) {
  const int w = l.width(), h = l.height();
  const HostFrame &first = right_first ? r : l, &second = right_first ? l : r;
  const int fw = input == StereoInput::SideBySide ? 2 * w : w, fh = input == StereoInput::TopBottom ? 2 * h : h;
  const int split_w = (w + 1) / 2, split_h = (h + 1) / 2;
  HostFrame f(PixelFormat::RGBA, fw, fh);
  for (int y = 0; y < fh; ++y)
    for (int x = 0; x < fw; ++x) {
      Rgba c{};
      switch (input) {
        case StereoInput::SideBySide: c = x < w ? at(first, x, y) : at(second, x - w, y); break;
        case StereoInput::TopBottom: c = y < h ? at(first, x, y) : at(second, x, y - h); break;
        case StereoInput::SideBySideHalf: {
          const HostFrame &v = x < split_w ? first : second;
          const int i = 2 * (x < split_w ? x : x - split_w);
          c = weighted(at(v, i, y), 1, at(v, std::min(i + 1, w - 1), y), 1);
          break;
        }
        case StereoInput::TopBottomHalf: {
          const HostFrame &v = y < split_h ? first : second;
          const int i = 2 * (y < split_h ? y : y - split_h);
          c = weighted(at(v, x, i), 1, at(v, x, std::min(i + 1, h - 1)), 1);
          break;
        }
        case StereoInput::RowInterleaved: c = at(y % 2 == 0 ? first : second, x, y); break;
        case StereoInput::ColumnInterleaved: c = at(x % 2 == 0 ? first : second, x, y); break;
        case StereoInput::Checkerboard: c = at((x + y) % 2 == 0 ? first : second, x, y); break;
      }
      store_rgba(f.view(), x, y, c);
    }
  return f;
}

HostFrame reference_view(StereoInput input, bool right_first, const HostFrame &frame, int eye) {
  const int slot = eye ^ (right_first ? 1 : 0);  // 0: the first view in the frame
  const int W = frame.width(), H = frame.height();
  const int w = input == StereoInput::SideBySide ? W / 2 : W, h = input == StereoInput::TopBottom ? H / 2 : H;
  HostFrame v(PixelFormat::RGBA, w, h);
  const int split_w = (W + 1) / 2, split_h = (H + 1) / 2;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Rgba c{};
      switch (input) {
        case StereoInput::SideBySide: c = at(frame, x + slot * w, y); break;
        case StereoInput::TopBottom: c = at(frame, x, y + slot * h); break;
        case StereoInput::SideBySideHalf: {
          int start = slot ? split_w : 0, n = slot ? W - split_w : split_w;
          if (n == 0) start = 0, n = split_w;
          c = unsqueezed(x, n, [&](int i) { return at(frame, start + i, y); });
          break;
        }
        case StereoInput::TopBottomHalf: {
          int start = slot ? split_h : 0, n = slot ? H - split_h : split_h;
          if (n == 0) start = 0, n = split_h;
          c = unsqueezed(y, n, [&](int i) { return at(frame, x, start + i); });
          break;
        }
        case StereoInput::RowInterleaved:
        case StereoInput::ColumnInterleaved: {
          const bool rows = input == StereoInput::RowInterleaved;
          const int pos = rows ? y : x, n = rows ? H : W;
          auto sample = [&](int k) { return rows ? at(frame, x, k) : at(frame, k, y); };
          if (pos % 2 == slot || n == 1) {
            c = sample(pos);
          } else {
            const int a = pos - 1 >= 0 ? pos - 1 : pos + 1, b = pos + 1 < n ? pos + 1 : pos - 1;
            c = weighted(sample(a), 1, sample(b), 1);
          }
          break;
        }
        case StereoInput::Checkerboard: {
          if ((x + y) % 2 == slot) {
            c = at(frame, x, y);
            break;
          }
          int n = 0, sum[4] = {0, 0, 0, 0};
          const int d[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
          for (const auto &o : d) {
            const int xx = x + o[0], yy = y + o[1];
            if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
            const Rgba s = at(frame, xx, yy);
            sum[0] += s.r, sum[1] += s.g, sum[2] += s.b, sum[3] += s.a, ++n;
          }
          if (n == 0) {
            c = at(frame, x, y);
            break;
          }
          c = Rgba{uint8_t((sum[0] + n / 2) / n), uint8_t((sum[1] + n / 2) / n), uint8_t((sum[2] + n / 2) / n),
                   uint8_t((sum[3] + n / 2) / n)};
          break;
        }
      }
      store_rgba(v.view(), x, y, c);
    }
  return v;
}

}  // namespace p3d::test
