// CPU reference of the DIBR warp (common/warp.h). Rows are independent for
// the warp and the Background fill, so each row is scattered, resolved and
// filled by one cv::parallel_for_ task with its own key array; the
// NeighborAverage fill is an image-wide Jacobi iteration. BackgroundSmooth
// finds its anchors in the row tasks and sums them afterwards in bands of
// rows (smooth_band).
#include "warp.h"

#include <algorithm>
#include <cmath>
#include <atomic>
#include <cstring>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "row_convert.h"

namespace p3d {
namespace {

// The CPU's z-buffer holds 64-bit keys for every row: the same order, so
// the same function, as the GPU's NarrowKeys where those fit.
using Keys = WideKeys;

struct WarpJob {
  WarpParams params;  // sanitised
  FrameView src;
  YuvToRgb m;
  ImageView<const float> depth;
  FrameView out;
  float D;
  int width, height;
};

// One eye of the output: its shift factor and first output column.
struct Eye {
  float shift;
  int col0;
};

// The pixels of the views: Rgba, or Rgba16 for deep frames (RGBA64 out),
// held as rgba_word() words.
template <class Px>
using WordOf = decltype(rgba_word(Px{}));

// The source row y converted once to R'G'B'A (load_rgba, load_rgba16), as
// rgba_word() words, as the GPU holds it in shared memory: both eyes sample
// it (sample_word), so a pixel is converted once instead of twice per eye.
// A pair at a time, as the GPU does: a 4:2:0 pair shares its chroma.
template <class Px>
struct SourceRow {
  std::vector<WordOf<Px>> words;
  explicit SourceRow(int width) : words(static_cast<size_t>(width)) {}
  // The words of the pixels [x0, x1) (whole pairs; rgba_words_of_row()).
  void load(const WarpJob &j, int y, int x0, int x1) {
    if constexpr (std::is_same_v<Px, Rgba>) {
      rgba_words_of_row(j.src, y, j.m, words.data(), x0, x1);
    } else {
      for (int x = x0 & ~1; x < x1; x += 2) load_rgba_pair_words(j.src, x, y, j.m, words.data() + x);
    }
  }
};

// Where one eye's row y goes in the output (packed RGB, warp_frames_fit):
// store_rgba() of a word, as one 4-byte copy with r and b swapped for the
// BGR orders (RGBA64: one 8-byte copy). The row pointer and the order are fixed per row, where
// store_rgba() would read them again for every pixel (its byte stores may
// alias the frame description).
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "rgba_word() words are stored in memory order");
template <class Px>
struct OutputRow {
  static constexpr size_t kBytes = sizeof(WordOf<Px>);
  uint8_t *p;
  bool bgr;
  OutputRow(const FrameView &out, int col0, int y)
      : p(out.plane[0] + static_cast<size_t>(y) * out.stride[0] + kBytes * static_cast<size_t>(col0)),
        bgr(is_bgr_order(out.format)) {}
  void put(int x, WordOf<Px> w) const {
    if constexpr (kBytes == 4) {
      if (bgr) w = swap_rb_word(w);
    }
    std::memcpy(p + kBytes * static_cast<size_t>(x), &w, kBytes);
  }
};

// Every source pixel's span of targets in one eye's row (warp_span()) and
// the hits (warp_hit_at()) it offers the span's first two targets: a pixel
// covers one or two targets but where the surface stretches.
struct SpanKeys {
  std::vector<int> first, count;
  std::vector<unsigned int> depth0, u0, depth1, u1;
  explicit SpanKeys(int width)
      : first(width), count(width), depth0(width), u0(width), depth1(width), u1(width) {}
};

// SpanKeys of the source pixels [x0, end) of a row `width` wide from their
// read depths d and targets t (indexed by x), several pixels at a time
// with OpenCV's universal intrinsics; end <= x1, where the caller takes
// over with the scalar helpers (the last pixel, which has no neighbour,
// and the remainder).
// Each lane computes what warp_link(), warp_span() and warp_hit_at()
// compute, in their operation order: IEEE single precision, no fused
// multiply-add, so the same bits (tests/common/test_warp.cpp compares the
// renders of rows of every width). v_ceil() equals ceil_to_int() for
// every target of a row. The clamps are written as min and max, which
// give clamp_value()'s result for every operand but NaN and -0, and
// neither reaches them: the read depths and targets are finite, and
// 1 / gap is infinite only for a subnormal gap, which only t(x+1) = 0
// beside a subnormal t(x) < 0 makes (t(x+1) = (x+1) + s p(x+1) is 0 or at
// least 2^-25 in size), a span that holds no integer target; and a sum
// x + (X - t) * inv_gap that is 0 is +0.
int span_keys_vector(const float *d, const float *t, int x0, int x1, int width, SpanKeys &k) {
  int x = x0;
#if P3D_CPU_VECTORS
  using namespace cv;
  constexpr int kLanes = v_float32::nlanes;
  const v_float32 zero = vx_setall_f32(0.f), one = vx_setall_f32(1.f), half = vx_setall_f32(0.5f);
  const v_float32 max_gap = vx_setall_f32(1.f + kMaxStretch), hi = vx_setall_f32(static_cast<float>(width - 1));
  const v_float32 depth_scale = vx_setall_f32(65535.f), u_scale = vx_setall_f32(256.f);
  const v_int32 last_column = vx_setall_s32(width - 1), int_one = vx_setall_s32(1);
  int lane_index[kLanes];
  for (int i = 0; i < kLanes; ++i) lane_index[i] = i;
  const v_int32 lanes = vx_load(lane_index);
  // Every lane has a right neighbour (x + kLanes < width) and is asked for.
  for (; x + kLanes <= x1 && x + kLanes < width; x += kLanes) {
    const v_float32 d0 = vx_load(d + x), t0 = vx_load(t + x), d1 = vx_load(d + x + 1), t1 = vx_load(t + x + 1);
    const v_float32 xs = v_cvt_f32(vx_setall_s32(x) + lanes);
    // warp_link
    const v_float32 gap = t1 - t0;
    const v_float32 connected = (gap > zero) & (gap <= max_gap);
    const v_float32 inv_gap = v_select(connected, one / gap, zero);
    const v_int32 linked = v_reinterpret_as_s32(connected);
    // warp_span
    const v_int32 X0 = v_ceil(t0 - half), end = v_ceil(t1) - int_one;
    const v_int32 last = v_min(v_select(linked & (end > X0), end, X0), last_column);
    const v_int32 first = v_max(X0, vx_setzero_s32());
    v_store(k.first.data() + x, first);
    v_store(k.count.data() + x, last - first + int_one);
    // warp_hit_at of targets first and first + 1
    for (int i = 0; i < 2; ++i) {
      const v_float32 xf = v_cvt_f32(first + vx_setall_s32(i));
      const v_float32 on_span = connected & (xf >= t0) & (xf < t1);
      const v_float32 u_span = v_min(v_max(xs + (xf - t0) * inv_gap, zero), hi);
      const v_float32 u_own = v_min(v_max(xs + (xf - t0), zero), hi);
      const v_float32 u = v_select(on_span, u_span, u_own);
      const v_float32 depth = v_select(on_span, d0 + (u - xs) * (d1 - d0), d0);
      const v_int32 depth_code = v_trunc(v_min(v_max(depth, zero), one) * depth_scale + half);
      const v_int32 u_code = v_trunc(u * u_scale + half) + int_one;
      v_store(reinterpret_cast<int *>((i ? k.depth1 : k.depth0).data() + x), depth_code);
      v_store(reinterpret_cast<int *>((i ? k.u1 : k.u0).data() + x), u_code);
    }
  }
  vx_cleanup();
#else
  (void)d, (void)t, (void)x1, (void)width, (void)k;
#endif
  return x;
}

// Each source pixel's read depth d[x] = warp_depth(depth[x]) and target
// t[x] = warp_target(x, d[x], ...) for x in [x0, end), several pixels at
// a time; end <= x1, where the caller's scalar loop takes over. Same
// bits: warp_depth() is 0 where d >= 0 fails (NaN, negative) and else
// min(d, 1) (which keeps -0, as the scalar code does), and the target is
// the scalar operations in their order, without fused multiply-add.
int depth_targets_vector(const float *depth, float shift, float D, float convergence, int x0, int x1, float *d,
                         float *t) {
  int x = x0;
#if P3D_CPU_VECTORS
  using namespace cv;
  constexpr int kLanes = v_float32::nlanes;
  const v_float32 zero = vx_setzero_f32(), one = vx_setall_f32(1.f);
  const v_float32 vshift = vx_setall_f32(shift), vD = vx_setall_f32(D), conv = vx_setall_f32(convergence);
  int lane_index[kLanes];
  for (int i = 0; i < kLanes; ++i) lane_index[i] = i;
  const v_int32 lanes = vx_load(lane_index);
  for (; x + kLanes <= x1; x += kLanes) {
    const v_float32 raw = vx_load(depth + x);
    const v_float32 dv = v_select(raw >= zero, v_min(raw, one), zero);
    const v_float32 xs = v_cvt_f32(vx_setall_s32(x) + lanes);
    v_store(d + x, dv);
    v_store(t + x, xs + vshift * (vD * (dv - conv)));
  }
  vx_cleanup();
#else
  (void)depth, (void)shift, (void)D, (void)convergence, (void)x1, (void)d, (void)t;
#endif
  return x;
}

// Per-row scratch of a row task: the converted source row, every pixel's
// read depth, target and span keys for the eye being scattered, the
// z-buffer keys, the Background fill's nearest-right index and the
// BackgroundSmooth anchors' runs of holes.
template <class Px>
struct RowScratch {
  SourceRow<Px> src;
  std::vector<float> depth, target;
  std::vector<Keys::Word> keys;
  SpanKeys spans;
  std::vector<int> right;                // Background only
  std::vector<std::pair<int, int>> runs;  // BackgroundSmooth only: the row's runs of holes
  std::vector<int> right_clean;           // and each run's nearest clean pixel on the right
  RowScratch(int width, bool smooth)
      : src(width), depth(width), target(width), keys(width), spans(width), right(width), right_clean(smooth ? width : 0) {}
};

// The part of one eye's row a call renders: the targets [a, b) get their
// keys, colours and (BackgroundSmooth, Background) fill anchors; the
// sources [sa, sb) are every pixel whose span can reach them, and the keys
// of [ka, kb), every target those sources reach, are cleared first. A
// whole row is all three [0, W).
struct RowWindow {
  int a, b, sa, sb, ka, kb;
};
RowWindow whole_row(int width) { return RowWindow{0, width, 0, width, 0, width}; }

// How far a source pixel's span reaches from it, in whole pixels: its
// target t(x) is within |s| D of x, its footprint half a pixel around it
// and a connected span ends before t(x+1) < t(x) + 1 + kMaxStretch.
int span_reach(const Eye &eye, float D) {
  const float w = (eye.shift < 0.f ? -eye.shift : eye.shift) * D;
  return static_cast<int>(std::ceil(w)) + 2 + static_cast<int>(kMaxStretch);
}

// The window of targets [a, b) of a row `width` wide, for an eye whose
// spans reach `reach` pixels.
RowWindow row_window(int a, int b, int reach, int width) {
  const int sa = std::max(0, a - reach), sb = std::min(width, b + reach);
  return RowWindow{a, b, sa, sb, std::max(0, sa - reach), std::min(width, sb + reach)};
}

// Z-buffer of the targets w.a..w.b of row y: keys[X] = the largest key any
// source pixel offers X (keys outside [w.ka, w.kb) are not touched).
// Each pixel's depth and target are computed once (warp_source would
// compute them for x and again for x + 1) and linked with warp_link.
template <class Px>
void scatter_row(const WarpJob &j, const Eye &eye, int y, const RowWindow &w, RowScratch<Px> &r) {
  std::vector<Keys::Word> &keys = r.keys;
  std::fill(keys.begin() + w.ka, keys.begin() + w.kb, Keys::Word{0});
  const float *drow = j.depth.row(y);
  float *d = r.depth.data(), *t = r.target.data();
  const int read_end = std::min(w.sb + 1, j.width);  // a source links with its right neighbour
  for (int x = depth_targets_vector(drow, eye.shift, j.D, j.params.convergence, w.sa, read_end, d, t); x < read_end;
       ++x) {
    d[x] = warp_depth(drow[x]);
    t[x] = warp_target(x, d[x], eye.shift, j.D, j.params.convergence);
  }
  auto source = [&](int x) {
    const bool has_next = x + 1 < j.width;
    return warp_link(x, d[x], t[x], has_next ? d[x + 1] : d[x], has_next ? t[x + 1] : t[x], has_next);
  };
  SpanKeys &k = r.spans;
  const int vector_end = span_keys_vector(d, t, w.sa, w.sb, j.width, k);
  for (int x = vector_end; x < w.sb; ++x) {
    const WarpSource s = source(x);
    const WarpSpan span = warp_span(s, j.width);
    k.first[x] = span.first;
    k.count[x] = span.last - span.first + 1;
    const WarpHit h0 = warp_hit_at(s, span.first, j.width), h1 = warp_hit_at(s, span.first + 1, j.width);
    k.depth0[x] = h0.depth;
    k.u0[x] = h0.u;
    k.depth1[x] = h1.depth;
    k.u1[x] = h1.u;
  }
  // The z-buffer's max; the rare longer spans take their further targets here.
  for (int x = w.sa; x < w.sb; ++x) {
    const int X = k.first[x], n = k.count[x];
    if (n <= 0) continue;
    keys[X] = std::max(keys[X], Keys::key(WarpHit{k.depth0[x], k.u0[x]}, X));
    if (n == 1) continue;
    keys[X + 1] = std::max(keys[X + 1], Keys::key(WarpHit{k.depth1[x], k.u1[x]}, X + 1));
    if (n == 2) continue;
    const WarpSource s = source(x);
    for (int i = 2; i < n; ++i) keys[X + i] = std::max(keys[X + i], Keys::key(warp_hit_at(s, X + i, j.width), X + i));
  }
}

// Colours of the covered targets, sampled from the converted source row;
// holes get kHoleColour for fill=None and are left for the fill otherwise.
// Returns the row's hole count.
template <class Px>
long long resolve_row(const WarpJob &j, const Eye &eye, int y, const RowWindow &w, const SourceRow<Px> &src,
                      const std::vector<Keys::Word> &keys) {
  const OutputRow<Px> out(j.out, eye.col0, y);
  const WordOf<Px> *row = src.words.data();
  const bool paint = j.params.fill == HoleFill::None;
  const int W = j.width;  // read once: the output's byte stores may alias j
  const Keys::Word *key = keys.data();
  long long holes = 0;
  for (int X = w.a; X < w.b; ++X) {
    if (key[X] != 0) {
      out.put(X, sample_word(row, W, Keys::u(key[X], X)));
    } else {
      ++holes;
      if (paint) out.put(X, rgba_word(colour_as<Px>(kHoleColour)));
    }
  }
  return holes;
}

// Background fill of row y: right[X] = nearest non-hole right of X, then a
// left-to-right pass that knows the nearest non-hole to the left.
template <class Px>
void background_fill_row(const WarpJob &j, const Eye &eye, int y, const std::vector<Keys::Word> &keys,
                         std::vector<int> &right) {
  int next = -1;
  for (int X = j.width - 1; X >= 0; --X) {
    right[X] = next;
    if (keys[X] != 0) next = X;
  }
  int prev = -1;
  for (int X = 0; X < j.width; ++X) {
    if (keys[X] != 0) {
      prev = X;
      continue;
    }
    const int xr = right[X];
    const int pick = background_source(X, prev, key_depth_at<Keys>(keys.data(), prev), xr,
                                       key_depth_at<Keys>(keys.data(), xr));
    Px c = colour_as<Px>(kFillBlack);
    if (pick >= 0) load_pixel(j.out, eye.col0 + pick, y, &c);
    store_pixel(j.out, eye.col0 + X, y, c);
  }
}

// What the image-wide fills keep of the warp (W x H each): NeighborAverage
// the hole mask (1 = hole); BackgroundSmooth every pixel's state (0: not a
// hole, kSmoothHole: a hole without an anchor, kSmoothAnchor: a hole with
// anchor[i]) and the holes' anchors.
constexpr uint8_t kSmoothHole = 1, kSmoothAnchor = 2;
template <class Px>
struct EyeScratch {
  std::vector<uint8_t> mask;
  uint8_t *state = nullptr;  // in WarpCpuScratch
  Px *anchor = nullptr;
};

// BackgroundSmooth, row part: the state and anchor of every pixel of row y,
// whose keys are final and whose non-holes are rendered, from the row's
// runs of holes. Clean pixels (smooth_is_clean) are those of the gaps
// between runs, kSmoothClean pixels in from each hole (the row's ends
// count as no hole), so a hole's nearest clean pixel on either side is an
// end of the nearest gap on that side that has any; its nearest non-hole
// is the pixel beside its run. The work follows the holes, not the row.
// Only the pixels [w.a, w.b) are written, as if they were the whole row:
// the same states and anchors as the whole row's where w.a is 0 or a
// clean pixel and w.b is the width or follows one (warp_eyes).
template <class Px>
void smooth_anchor_row(const WarpJob &j, const Eye &eye, int y, const RowWindow &w, RowScratch<Px> &r,
                       EyeScratch<Px> &s) {
  const int W = w.b, K = kSmoothClean;
  const std::vector<Keys::Word> &keys = r.keys;
  const size_t base = static_cast<size_t>(y) * j.width;
  uint8_t *state = s.state + base;
  Px *anchor = s.anchor + base;
  std::memset(state + w.a, 0, static_cast<size_t>(w.b - w.a));
  std::vector<std::pair<int, int>> &runs = r.runs;  // [first, last] hole of each run
  runs.clear();
  // The loop's index never has its address taken (emplace_back takes its
  // arguments by reference), so it stays in a register.
  const Keys::Word *key = keys.data();
  for (int X = w.a; X < W; ++X) {
    if (key[X] != 0) continue;
    const int first = X;
    while (X + 1 < W && key[X + 1] == 0) ++X;
    const int last = X;
    runs.emplace_back(first, last);
  }
  const int n = static_cast<int>(runs.size());
  // Gap g lies before run g (gap n after the last run); its clean pixels
  // are [clean_lo(g), clean_hi(g)], empty when lo > hi.
  auto clean_lo = [&](int g) { return g == 0 ? w.a : runs[g - 1].second + 1 + K; };
  auto clean_hi = [&](int g) { return g == n ? W - 1 : runs[g].first - 1 - K; };
  std::vector<int> &right_clean = r.right_clean;  // per run: the nearest clean pixel right of it, -1: none
  for (int g = n, next = -1; g >= 1; --g) {
    if (clean_lo(g) <= clean_hi(g)) next = clean_lo(g);
    right_clean[g - 1] = next;
  }
  int left_clean = -1;
  for (int i = 0; i < n; ++i) {
    if (clean_lo(i) <= clean_hi(i)) left_clean = clean_hi(i);
    const int a = runs[i].first, b = runs[i].second;
    const int xl = smooth_side(left_clean, a > w.a ? a - 1 : -1), xr = smooth_side(right_clean[i], b + 1 < W ? b + 1 : -1);
    const unsigned int depth_l = key_depth_at<Keys>(keys.data(), xl), depth_r = key_depth_at<Keys>(keys.data(), xr);
    for (int X = a; X <= b; ++X) {
      const int pick = background_source(X, xl, depth_l, xr, depth_r);
      if (pick < 0) {
        state[X] = kSmoothHole;
        continue;
      }
      state[X] = kSmoothAnchor;
      load_pixel(j.out, eye.col0 + pick, y, &anchor[X]);
    }
  }
}

// The nearest clean pixel (smooth_is_clean of the states' hole mask) at or
// left of `from`, -1: none; at or right of `from`, -1: none.
int clean_at_or_left(const uint8_t *state, int from, int width) {
  for (int X = std::min(from, width - 1); X >= 0; --X)
    if (smooth_is_clean(state, X, width)) return X;
  return -1;
}
int clean_at_or_right(const uint8_t *state, int from, int width) {
  for (int X = std::max(from, 0); X < width; ++X)
    if (smooth_is_clean(state, X, width)) return X;
  return -1;
}

// The window of eye e's row y that a change of the source columns
// [c.x0, c.x1) (its pixels or its depth) makes the warp render again.
// Sources [c.x0 - 2, c.x1 + 1) can change their hits (a pixel's span reads
// its right neighbour's depth, a hit's colour the words around its u), and
// those reach the targets T within span_reach() of them. BackgroundSmooth's
// anchors of a hole come from the row's runs of holes and clean pixels on
// either side, so the window grows to a clean pixel left and right of T
// that T cannot touch (kSmoothClean away from it, read from the states of
// the previous frame, which are this frame's outside T): the holes between
// find their anchors inside, the others keep theirs. Background's nearest
// non-holes are found along the whole row, NeighborAverage fills across
// rows: both take whole rows.
template <class Px>
RowWindow changed_window(const WarpJob &j, const Eye &eye, const EyeScratch<Px> &s, int y, ColumnSpan c) {
  const int W = j.width, reach = span_reach(eye, j.D);
  const HoleFill fill = j.params.fill;
  if (fill == HoleFill::Background || fill == HoleFill::NeighborAverage) return whole_row(W);
  int a = std::max(0, c.x0 - 2 - reach), b = std::min(W, c.x1 + 1 + reach);
  if (fill == HoleFill::BackgroundSmooth) {
    const uint8_t *state = s.state + static_cast<size_t>(y) * W;
    const int left = clean_at_or_left(state, a - kSmoothClean - 1, W);
    const int right = clean_at_or_right(state, b + kSmoothClean, W);
    a = left < 0 ? 0 : left;
    b = right < 0 ? W : right + 1;
  }
  return row_window(a, b, reach, W);
}

// Warps both eyes row by row (a row task converts its source row once);
// an eye with shift 0 is the source row copied. scratch[e] receives eye e's
// hole mask when its mask is sized, and its BackgroundSmooth states and
// anchors for that fill (sized W x H by the caller).
// holes[e]: eye e's hole count (of the windows rendered).
// changed: each row's changed columns, null: every row whole. windows[e]
// (H entries, when changed is given) receives the targets of eye e each
// row rendered again (empty: none).
template <class Px>
void warp_eyes(const WarpJob &j, const Eye eyes[2], EyeScratch<Px> *scratch, long long holes[2],
               const std::vector<ColumnSpan> *changed, std::vector<ColumnSpan> *windows) {
  std::atomic<long long> total[2] = {{0}, {0}};
  cv::parallel_for_(cv::Range(0, j.height), [&](const cv::Range &rows) {
    // Made at the task's first rendered row: a task of unchanged rows
    // allocates nothing.
    std::optional<RowScratch<Px>> scratch_row;
    long long local[2] = {0, 0};
    for (int y = rows.start; y < rows.end; ++y) {
      if (changed && (*changed)[y].empty()) continue;
      RowScratch<Px> &row =
          scratch_row ? *scratch_row : scratch_row.emplace(j.width, j.params.fill == HoleFill::BackgroundSmooth);
      const SourceRow<Px> &src = row.src;
      const std::vector<Keys::Word> &keys = row.keys;
      RowWindow w[2];
      int load0 = 0, load1 = j.width;  // the source words the windows read
      if (changed) {
        const ColumnSpan c = (*changed)[y];
        load0 = j.width, load1 = 0;
        for (int e = 0; e < 2; ++e) {
          // A copied eye is the changed columns themselves.
          w[e] = eyes[e].shift == 0.f ? RowWindow{c.x0, c.x1, c.x0, c.x1, c.x0, c.x1}
                                      : changed_window(j, eyes[e], scratch[e], y, c);
          load0 = std::min(load0, std::max(0, w[e].sa - 1));
          load1 = std::max(load1, std::min(j.width, w[e].sb + 2));
          windows[e][y] = ColumnSpan{w[e].a, w[e].b};
        }
      } else {
        w[0] = w[1] = whole_row(j.width);
      }
      row.src.load(j, y, load0, load1);
      for (int e = 0; e < 2; ++e) {
        const Eye &eye = eyes[e];
        if (eye.shift == 0.f) {
          const OutputRow<Px> out(j.out, eye.col0, y);
          for (int x = w[e].a; x < w[e].b; ++x) out.put(x, src.words[x]);
          continue;
        }
        scatter_row(j, eye, y, w[e], row);
        const long long h = resolve_row(j, eye, y, w[e], src, keys);
        local[e] += h;
        if (h > 0 && j.params.fill == HoleFill::Background) background_fill_row<Px>(j, eye, y, keys, row.right);
        EyeScratch<Px> &s = scratch[e];
        if (j.params.fill == HoleFill::BackgroundSmooth) smooth_anchor_row(j, eye, y, w[e], row, s);
        if (s.mask.empty()) continue;
        const size_t base = static_cast<size_t>(y) * j.width;
        for (int X = 0; X < j.width; ++X) s.mask[base + X] = keys[X] == 0;
      }
    }
    total[0] += local[0];
    total[1] += local[1];
  });
  holes[0] = total[0].load();
  holes[1] = total[1].load();
}

// BackgroundSmooth sums, after the row pass (smooth_anchor_row) wrote every
// row's states and anchors. Bands of rows run in parallel; a band sweeps
// its rows top-down and keeps, per column, the window of its current run of
// holes (rows lo..hi with their anchors' sum s), sliding it as y moves on,
// so V(X, y) comes in row order and each row is filled as soon as its V
// row is complete. Integer sums: the same result as any other order.
template <class Px>
struct ColumnWindow {
  using Sum = typename SmoothSumFor<Px>::Type;
  int lo, hi;
  Sum s;
  int row = -2;  // the row V was last taken at: a column left out of a row starts afresh
};

// The first column at or after X whose state is a hole (W: none), eight
// states at a time where they are all 0: most of a row is no hole.
inline int next_hole(const uint8_t *row, int X, int W) {
  for (; X + 8 <= W; X += 8) {
    uint64_t eight;
    std::memcpy(&eight, row + X, sizeof eight);
    if (eight != 0) break;
  }
  while (X < W && !row[X]) ++X;
  return X;
}

// The holes of the columns fill[y] of rows y0..y1 (fill: null, every
// column) get their fill. V is needed within Rx of them, and a run of holes
// is cut at the edges of those columns: the mean at t reads only V within
// Rx of t, which lies inside.
template <class Px>
void smooth_band(const WarpJob &j, const Eye &eye, const EyeScratch<Px> &es, int R, int Rx, int y0, int y1,
                 const std::vector<ColumnSpan> *fill, std::vector<ColumnWindow<Px>> &win,
                 std::vector<typename ColumnWindow<Px>::Sum> &V, std::vector<typename ColumnWindow<Px>::Sum> &prefix) {
  using Sum = typename ColumnWindow<Px>::Sum;
  const int W = j.width, H = j.height;
  const uint8_t *state = es.state;
  const Px *anchor = es.anchor;
  auto at = [W](int y, int X) { return static_cast<size_t>(y) * W + X; };
  for (auto &w : win) w.row = -2;
  for (int y = y0; y < y1; ++y) {
    const ColumnSpan out = fill ? (*fill)[y] : ColumnSpan{0, W};
    if (out.empty()) continue;
    const int v0 = std::max(0, out.x0 - Rx), v1 = std::min(W, out.x1 + Rx);  // the columns of V
    const uint8_t *row = state + at(y, 0);
    bool any = false;
    for (int X = next_hole(row, v0, v1); X < v1; X = next_hole(row, X + 1, v1)) {
      any = true;
      ColumnWindow<Px> &w = win[X];
      if (w.row != y - 1 || !state[at(y - 1, X)]) {  // a new run, or new to the sweep: lo = the run's start
        w.lo = y;
        while (w.lo > 0 && w.lo > y - R && state[at(w.lo - 1, X)]) --w.lo;
        w.hi = w.lo - 1;
        w.s = Sum{0, 0, 0, 0, 0};
      }
      w.row = y;
      while (w.hi < y + R && w.hi + 1 < H && state[at(w.hi + 1, X)]) {
        ++w.hi;
        if (state[at(w.hi, X)] == kSmoothAnchor) smooth_add(w.s, anchor[at(w.hi, X)]);
      }
      for (; w.lo < y - R; ++w.lo)
        if (state[at(w.lo, X)] == kSmoothAnchor) {
          const Px c = anchor[at(w.lo, X)];
          w.s = smooth_window(w.s, Sum{c.r, c.g, c.b, c.a, 1u});
        }
      V[X] = w.s;
    }
    if (!any) continue;
    // Every hole of the columns asked for becomes the mean of V over its
    // row run within +-Rx.
    for (int X = next_hole(row, v0, v1); X < v1; X = next_hole(row, X, v1)) {
      const int a = X;  // the run is columns a..b (cut at v0 and v1)
      prefix[0] = Sum{0, 0, 0, 0, 0};
      for (; X < v1 && row[X]; ++X) {
        prefix[X - a + 1] = prefix[X - a];
        smooth_add(prefix[X - a + 1], V[X]);
      }
      const int b = X - 1;
      for (int t = std::max(a, out.x0); t <= std::min(b, out.x1 - 1); ++t) {
        const Sum &hi = prefix[std::min(b, t + Rx) - a + 1], &lo = prefix[std::max(a, t - Rx) - a];
        store_pixel(j.out, eye.col0 + t, y, smooth_mean(smooth_window(hi, lo)));
      }
    }
  }
}

// The columns each row's fill must redo when the rows' windows of targets
// (warp_eyes) were rendered again: a hole's fill reads the anchors of its
// column within R rows and the sums of its row run within Rx columns.
std::vector<ColumnSpan> smooth_fill_spans(const std::vector<ColumnSpan> &windows, int R, int Rx, int width) {
  const int H = static_cast<int>(windows.size());
  std::vector<ColumnSpan> fill(windows.size(), ColumnSpan{width, 0});
  for (int y = 0; y < H; ++y) {
    const ColumnSpan w = windows[y];
    if (w.empty()) continue;
    const int x0 = std::max(0, w.x0 - Rx), x1 = std::min(width, w.x1 + Rx);
    for (int q = std::max(0, y - R); q <= std::min(H - 1, y + R); ++q) {
      fill[q].x0 = std::min(fill[q].x0, x0);
      fill[q].x1 = std::max(fill[q].x1, x1);
    }
  }
  return fill;
}

// fill: the columns of each row to fill (smooth_fill_spans), null: all.
template <class Px>
void background_smooth_fill(const WarpJob &j, const Eye &eye, const EyeScratch<Px> &s,
                            const std::vector<ColumnSpan> *fill) {
  const int R = smooth_fill_radius(eye.shift, j.D), Rx = smooth_fill_radius_x(R);
  // Bands of at least 2R rows, so that finding a run's start at a band's
  // first row (up to R rows up, holes only) stays a small share of the
  // sweep, and short enough that 8 or 16 threads get several bands each
  // (1080p: 34 bands, 4K: 38). A band starts anywhere, so the rows asked
  // for are cut into bands run by run.
  const int band = std::max(32, 2 * R);
  std::vector<std::pair<int, int>> bands;
  for (int y = 0; y < j.height;) {
    if (fill && (*fill)[y].empty()) {
      ++y;
      continue;
    }
    int end = y;
    while (end < j.height && (!fill || !(*fill)[end].empty())) ++end;
    for (; y < end; y += band) bands.emplace_back(y, std::min(end, y + band));
    y = end;
  }
  cv::parallel_for_(cv::Range(0, static_cast<int>(bands.size())), [&](const cv::Range &r) {
    std::vector<ColumnWindow<Px>> win(j.width);
    std::vector<typename ColumnWindow<Px>::Sum> V(j.width), prefix(static_cast<size_t>(j.width) + 1);
    for (int b = r.start; b < r.end; ++b)
      smooth_band(j, eye, s, R, Rx, bands[b].first, bands[b].second, fill, win, V, prefix);
  });
}

// NeighborAverage: Jacobi steps ping-ponging between two hole masks (reads
// from `cur` only, so rows can run in parallel), until no hole is left or a
// step fills nothing; what is left becomes kFillBlack.
template <class Px>
void neighbour_average_fill(const WarpJob &j, const Eye &eye, std::vector<uint8_t> &mask, long long holes) {
  std::vector<uint8_t> next(mask.size());
  std::vector<uint8_t> *cur = &mask, *nxt = &next;
  const size_t W = static_cast<size_t>(j.width);
  while (holes > 0) {
    std::atomic<long long> filled{0};
    cv::parallel_for_(cv::Range(0, j.height), [&](const cv::Range &rows) {
      long long local = 0;
      for (int y = rows.start; y < rows.end; ++y)
        for (int X = 0; X < j.width; ++X) {
          const size_t i = y * W + X;
          uint8_t still = 0;
          Px c;
          if ((*cur)[i]) {
            if (neighbour_average(j.out, eye.col0, cur->data(), W, j.width, j.height, X, y, &c)) {
              store_pixel(j.out, eye.col0 + X, y, c);
              ++local;
            } else {
              still = 1;
            }
          }
          (*nxt)[i] = still;
        }
      filled += local;
    });
    std::swap(cur, nxt);
    if (filled.load() == 0) break;
    holes -= filled.load();
  }
  if (holes <= 0) return;
  for (int y = 0; y < j.height; ++y)
    for (int X = 0; X < j.width; ++X)
      if ((*cur)[y * W + X]) store_pixel(j.out, eye.col0 + X, y, colour_as<Px>(kFillBlack));
}

}  // namespace

long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out) {
  WarpCpuScratch scratch;
  return warp_render_cpu(params, src, m, depth, out, scratch);
}

int warp_rows_reach(const WarpParams &params, int width, int height) {
  const WarpParams p = warp_sanitize(params);
  if (p.fill == HoleFill::NeighborAverage) return std::max(height, 0);
  if (p.fill != HoleFill::BackgroundSmooth) return 0;
  // A hole's fill sums the anchors of its column's run within R rows.
  const float D = disparity_scale(p, width);
  int R = 0;
  for (int e = 0; e < 2; ++e) {
    const float shift = warp_eye_shift(p, D, e);
    if (shift != 0.f) R = std::max(R, smooth_fill_radius(shift, D));
  }
  return R;
}

std::vector<uint8_t> warp_rows_written(const WarpParams &params, int width, const std::vector<ColumnSpan> &changed) {
  const int H = static_cast<int>(changed.size()), R = warp_rows_reach(params, width, H);
  std::vector<uint8_t> out(changed.size(), 0);
  for (int y = 0; y < H; ++y)
    if (!changed[y].empty()) std::fill(out.begin() + std::max(0, y - R), out.begin() + std::min(H, y + R + 1), 1);
  return out;
}

long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out, WarpCpuScratch &planes) {
  return warp_render_cpu(params, src, m, depth, out, planes, nullptr);
}

namespace {

// The anchor plane of eye e for the views' pixel type.
std::vector<Rgba> &anchor_plane(WarpCpuScratch &planes, int e, const Rgba *) { return planes.smooth_anchor[e]; }
std::vector<Rgba16> &anchor_plane(WarpCpuScratch &planes, int e, const Rgba16 *) { return planes.smooth_anchor16[e]; }

template <class Px>
long long render(WarpJob &j, WarpCpuScratch &planes, const std::vector<ColumnSpan> *changed) {
  const Eye eyes[2] = {{warp_eye_shift(j.params, j.D, 0), 0}, {warp_eye_shift(j.params, j.D, 1), j.width}};
  const bool average = j.params.fill == HoleFill::NeighborAverage;
  const bool smooth = j.params.fill == HoleFill::BackgroundSmooth;
  // A whole frame writes every smooth state, an adaptive one the states of
  // its windows (the planes hold the previous call's elsewhere, which
  // changed_window reads), and anchors are read only where a state names
  // one, so reused planes need no clearing.
  EyeScratch<Px> scratch[2];
  const size_t n = static_cast<size_t>(j.width) * j.height;
  for (int e = 0; e < 2; ++e) {
    if (eyes[e].shift == 0.f) continue;
    if (average) scratch[e].mask.resize(n);
    if (smooth) {
      std::vector<Px> &anchors = anchor_plane(planes, e, static_cast<const Px *>(nullptr));
      planes.smooth_state[e].resize(n);
      anchors.resize(n);
      scratch[e].state = planes.smooth_state[e].data();
      scratch[e].anchor = anchors.data();
    }
  }
  // NeighborAverage reaches across the picture: a change warps all.
  if (changed && average &&
      std::any_of(changed->begin(), changed->end(), [](const ColumnSpan &c) { return !c.empty(); }))
    changed = nullptr;
  long long holes[2] = {0, 0};
  std::vector<ColumnSpan> windows[2];
  if (changed)
    for (auto &w : windows) w.assign(changed->size(), ColumnSpan{});
  warp_eyes<Px>(j, eyes, scratch, holes, changed, windows);
  for (int e = 0; e < 2; ++e) {
    if (average && holes[e] > 0) neighbour_average_fill<Px>(j, eyes[e], scratch[e].mask, holes[e]);
    if (!smooth || eyes[e].shift == 0.f) continue;
    if (!changed) {
      if (holes[e] > 0) background_smooth_fill<Px>(j, eyes[e], scratch[e], nullptr);
      continue;
    }
    // The fill of a hole reads the anchors within R rows and Rx columns: it
    // runs where the windows reach, whatever their own hole counts.
    const int R = smooth_fill_radius(eyes[e].shift, j.D);
    const std::vector<ColumnSpan> fill = smooth_fill_spans(windows[e], R, smooth_fill_radius_x(R), j.width);
    background_smooth_fill<Px>(j, eyes[e], scratch[e], &fill);
  }
  return holes[0] + holes[1];
}

}  // namespace

long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out, WarpCpuScratch &planes,
                          const std::vector<ColumnSpan> *changed) {
  if (!warp_frames_fit(src, depth, out) || !params_fit(src.format, m)) return -1;
  if (changed && static_cast<int>(changed->size()) != src.height) return -1;
  if (changed)
    for (const ColumnSpan &c : *changed)
      if (!c.empty() && (c.x0 < 0 || c.x1 > src.width)) return -1;
  WarpJob j{warp_sanitize(params), src, m, depth, out, 0.f, src.width, src.height};
  j.D = disparity_scale(j.params, j.width);
  return is_deep(out.format) ? render<Rgba16>(j, planes, changed) : render<Rgba>(j, planes, changed);
}

}  // namespace p3d
