// The warp's row kernel and its launch, templates on the pixel type of the
// converted source row (Rgba for 8-bit pictures, Rgba16 for 16-bit ones):
// cuda/warp_rows.cu builds the 8-bit kernels, cuda/kernels_deep.cu the
// 16-bit ones. cuda/warp.cu describes a frame's passes, cuda/warp_plan.h
// chooses the instance a frame runs, and every per-pixel decision calls
// the P3D_HD helpers of common/warp.h.
//
// Rows are independent for everything but NeighborAverage, so one block
// renders one output row, both eyes, from start to end: the source row is
// converted to RGBA once into shared memory, the z-buffer lives in shared
// memory (global memory only for rows too wide for it), scatter, resolve and
// the Background fill follow each other behind __syncthreads, and nothing
// but the depth row, the source row and the output row touches DRAM.
#pragma once

#include <vector>

#include "chained_launch.cuh"
#include "launch_bounds.cuh"
#include "warp_device.cuh"
#include "warp_internal.h"

namespace p3d {
namespace warp_detail {
namespace {

// Pixels of chunk c that are in the row: the low W - 32 c bits of the last.
__device__ unsigned chunk_valid_bits(int c, int W) {
  const int n = W - c * 32;
  return n >= 32 ? ~0u : (1u << n) - 1u;
}

// Chunk k's word of a per-chunk bit array; `invert`: its clear bits within
// the row of W pixels instead (the non-holes, from the hole bits).
__device__ unsigned chunk_word(const unsigned *bits, bool invert, int W, int k) {
  return invert ? chunk_valid_bits(k, W) & ~bits[k] : bits[k];
}

// The nearest pixel left / right of pixel 32 c + bit whose bit is set in
// chunk_word(bits, invert, ...), or -1. Holes are narrow, so the search
// rarely leaves the chunk or its neighbour; it needs no row-wide scan and
// no barrier.
__device__ int nearest_left(const unsigned *bits, bool invert, int W, int c, int bit) {
  unsigned m = chunk_word(bits, invert, W, c) & ((1u << bit) - 1u);
  while (!m) {
    if (--c < 0) return -1;
    m = chunk_word(bits, invert, W, c);
  }
  return c * 32 + 31 - __clz(m);
}
__device__ int nearest_right(const unsigned *bits, bool invert, int W, int chunks, int c, int bit) {
  unsigned m = chunk_word(bits, invert, W, c) & ~((2u << bit) - 1u);
  while (!m) {
    if (++c >= chunks) return -1;
    m = chunk_word(bits, invert, W, c);
  }
  return c * 32 + __ffs(m) - 1;
}

// The colour a covered pixel with u code `u` has in the output, as
// load_pixel would read it back: sampled again from the converted source
// row in shared memory instead of read from global memory; RGBx/BGRx read
// back alpha 255.
template <class Px>
__device__ Px rendered_colour(const FrameView &out, const Px *src_row, int W, unsigned u) {
  Px c = sample_row(src_row, W, u);
  if (!has_alpha(out.format)) c.a = colour_as<Px>(kFillBlack).a;
  return c;
}

// A pixel of type Px as a word (rgba_word): 32 bits for Rgba, 64 for Rgba16.
template <class Px>
using WordOf = decltype(rgba_word(Px{}));

// ---- Pixels as words ---------------------------------------------------------
// The source row in shared memory holds rgba_word() of each load_pixel()
// value, and covered pixels are resolved with sample_word() (common/warp.h)
// and stored with one store a pixel (measured: docs/benchmarks.md, Design
// measurements, "Warp: resident rows, words, both eyes").

// Word w stored as one pixel of a frame whose rows are aligned to words:
// store_pixel()'s bytes (r and b swapped for the BGR orders, which are
// 8-bit).
__device__ inline void store_pixel_word(uint32_t *p, uint32_t w, bool bgr) { *p = bgr ? swap_rb_word(w) : w; }
__device__ inline void store_pixel_word(uint64_t *p, uint64_t w, bool) { *p = w; }

// One eye's part of output row y, which starts at column col0 of `out`:
// store() is store_pixel() of a word, one store when the frame's rows are
// aligned to the word (`words`, checked once by the launcher). The row's
// address is taken once, not per pixel (64-bit arithmetic).
template <class Px>
struct OutRow {
  using Word = WordOf<Px>;
  const FrameView *out;
  Word *words;  // the eye's first pixel in the row; null: rows not aligned to words
  int col0, y;
  bool bgr;
  __device__ OutRow(const FrameView &frame, int col0_, int y_, bool aligned)
      : out(&frame),
        words(aligned ? reinterpret_cast<Word *>(frame.plane[0] + static_cast<size_t>(y_) * frame.stride[0]) + col0_
                      : nullptr),
        col0(col0_),
        y(y_),
        bgr(is_bgr_order(frame.format)) {}
  __device__ void store(int X, Word w) const {
    if (!words) {
      store_pixel(*out, col0 + X, y, word_rgba(w));
      return;
    }
    store_pixel_word(words + X, w, bgr);
  }
};

// Background fill of one row whose keys are final and whose chunks' hole
// bits are in hole_bits: each hole's nearest non-holes by bit search.
template <class Keys, class Px>
__device__ void background_fill_row(const FrameView &out, const Px *src_row, int col0, int y,
                                    const typename Keys::Word *keys, int W, int chunks, const unsigned *hole_bits) {
  for (int X = threadIdx.x; X < W; X += blockDim.x) {
    const int c = X >> 5, bit = X & 31;
    if (!((hole_bits[c] >> bit) & 1u)) continue;
    const int xl = nearest_left(hole_bits, true, W, c, bit), xr = nearest_right(hole_bits, true, W, chunks, c, bit);
    const int pick = background_source(X, xl, key_depth_at<Keys>(keys, xl), xr, key_depth_at<Keys>(keys, xr));
    store_pixel(out, col0 + X, y,
                pick >= 0 ? rendered_colour(out, src_row, W, Keys::u(keys[pick], pick)) : colour_as<Px>(kFillBlack));
  }
}

// memory, its z-buffers, the chunk arrays of the fills. Indexed by eye: a
// kernel that renders the eyes one after the other points both entries at
// one array; one that renders them together (kBothEyes) has one for each.
template <class Keys, class Px>
struct RowJob {
  using Word = WordOf<Px>;
  FrameView out;
  FrameView row;  // the source row as Px words in shared memory (y = 0)
  EyeShifts eyes;
  float D, convergence;
  const float *depth_row;  // the cells of row y: pixel x's depth is depth_row[x >> depth_shift]
  int depth_shift;
  typename Keys::Word *keys[2];
  unsigned *hole_bits[2];   // per chunk (kFillBits)
  unsigned *clean_bits[2];  // per chunk (BackgroundSmooth)
  uint8_t *mask;  // NeighborAverage masks (2 eyes x H x W)
  SmoothScratch smooth;  // BackgroundSmooth
  unsigned long long *total;
  int y, W, H, chunks;
  bool words;  // out's rows are aligned to words: OutRow stores words
};

// ---- BackgroundSmooth (common/warp.h) ----------------------------------------
// The row kernel finds every hole's anchor (the clean and non-hole pixels
// are row-local, and the keys are in shared memory), then one kernel
// (smooth_tile_kernel) sums the anchors down the column runs and along the
// row runs of holes. Scratch per eye (W x H each): state (uint8 flags
// below), anchor (Px). Integer sums throughout, so every reduction order
// gives the CPU's result.

// State flags of a pixel: a hole (0: not one, so not summed), has an anchor.
static_assert(kSmoothClean >= 1 && kSmoothClean < 32, "the clean test reads the chunks on either side");

// Lists the tile of chunk c of row y of an eye, once per frame.
__device__ void list_smooth_tile(const SmoothScratch &sc, int eye, int y, int c) {
  const unsigned t = (static_cast<unsigned>(eye) * sc.tiles_y + y / sc.tile_rows) * sc.tiles_x + c;
  if (atomicExch(sc.tile_mark + t, 1u) == 0u) sc.tile_list[atomicAdd(sc.tile_count, 1u)] = t;
}

// Every chunk's flag (has it a hole) of one rendered eye row, from the
// hole bits the resolve loop took by ballot, and the tiles of the chunks
// with holes listed for the sums kernel. Every row of a rendered eye (shift
// not 0) writes its flags every frame (the sums kernel reads no state of a
// chunk without one).
template <class Keys, class Px>
__device__ void smooth_chunk_flags(const RowJob<Keys, Px> &j, int eye) {
  uint8_t *flags = j.smooth.chunk_holes + (static_cast<size_t>(eye) * j.H + j.y) * j.chunks;
  const unsigned *hole_bits = j.hole_bits[eye];
  for (int c = threadIdx.x; c < j.chunks; c += blockDim.x) {
    const bool holes = hole_bits[c] != 0u;
    flags[c] = holes;
    if (holes) list_smooth_tile(j.smooth, eye, j.y, c);
  }
}

// The clean bits of one rendered eye row (no hole within kSmoothClean),
// per chunk from the chunk's and its neighbours' hole bits. Read by
// smooth_anchor_row after a barrier.
template <class Keys, class Px>
__device__ void smooth_clean_bits(const RowJob<Keys, Px> &j, int eye) {
  const unsigned *hole_bits = j.hole_bits[eye];
  for (int c = threadIdx.x; c < j.chunks; c += blockDim.x) {
    const unsigned h = hole_bits[c], prev = c > 0 ? hole_bits[c - 1] : 0u,
                   next = c + 1 < j.chunks ? hole_bits[c + 1] : 0u;
    unsigned near = h;  // bit i: a hole within kSmoothClean of pixel 32 c + i
    for (int d = 1; d <= kSmoothClean; ++d) near |= (h << d) | (prev >> (32 - d)) | (h >> d) | (next << (32 - d));
    j.clean_bits[eye][c] = chunk_valid_bits(c, j.W) & ~near;
  }
}

// The states and anchors of one rendered eye row whose keys are final, whose
// chunks' hole bits the resolve loop took by ballot and whose clean bits
// smooth_clean_bits wrote, for the chunks with holes (the sums kernel reads
// no others): each hole takes its nearest clean (else non-hole) pixel on
// either side by bit search, and background_source() picks the anchor.
// States: 0 for a non-hole, kStateHole, plus kStateAnchor where it has one.
template <class Keys, class Px>
__device__ void smooth_anchor_row(const RowJob<Keys, Px> &j, int eye) {
  const unsigned *hole_bits = j.hole_bits[eye], *clean_bits = j.clean_bits[eye];
  const typename Keys::Word *keys = j.keys[eye];
  const size_t row = (static_cast<size_t>(eye) * j.H + j.y) * j.W;
  for (int X = threadIdx.x; X < j.W; X += blockDim.x) {
    const int c = X >> 5, bit = X & 31;
    const unsigned chunk = hole_bits[c];
    if (!chunk) continue;
    if (!((chunk >> bit) & 1u)) {
      j.smooth.state[row + X] = 0;
      continue;
    }
    const int l_any = nearest_left(hole_bits, true, j.W, c, bit);
    const int r_any = nearest_right(hole_bits, true, j.W, j.chunks, c, bit);
    const int l_clean = l_any < 0 ? -1 : nearest_left(clean_bits, false, j.W, c, bit);
    const int r_clean = r_any < 0 ? -1 : nearest_right(clean_bits, false, j.W, j.chunks, c, bit);
    const int xl = smooth_side(l_clean, l_any), xr = smooth_side(r_clean, r_any);
    const int pick = background_source(X, xl, key_depth_at<Keys>(keys, xl), xr, key_depth_at<Keys>(keys, xr));
    if (pick < 0) {
      j.smooth.state[row + X] = kStateHole;
      continue;
    }
    j.smooth.state[row + X] = kStateHole | kStateAnchor;
    static_cast<Px *>(j.smooth.anchor)[row + X] =
        rendered_colour(j.out, reinterpret_cast<const Px *>(j.row.plane[0]), j.W, Keys::u(keys[pick], pick));
  }
}

// Clears n key words before a scatter. In shared memory (kShared: 16-byte
// aligned) 16 bytes a store, where a word a store costs five instructions a
// pixel and eye; a row's keys in global memory (rows too wide for shared
// memory) are not always 16-byte aligned.
template <bool kShared, class Word>
__device__ void zero_keys(Word *keys, int n) {
  int done = 0;
  if (kShared) {
    constexpr int kPerStore = static_cast<int>(sizeof(uint4) / sizeof(Word));
    const int stores = n / kPerStore;
    for (int i = threadIdx.x; i < stores; i += blockDim.x) reinterpret_cast<uint4 *>(keys)[i] = make_uint4(0, 0, 0, 0);
    done = stores * kPerStore;
  }
  for (int X = done + threadIdx.x; X < n; X += blockDim.x) keys[X] = 0;
}

// Whether a fill needs each chunk's hole bits (its nearest-pixel searches).
template <HoleFill kFill>
constexpr bool kFillBits = kFill == HoleFill::Background || kFill == HoleFill::BackgroundSmooth;

// Source pixel s's hits on the targets it covers (warp_span).
template <class Keys>
__device__ void scatter_source(typename Keys::Word *keys, const WarpSource &s, int W) {
  const WarpSpan span = warp_span(s, W);
  // Not unrolled: a span is one target for most pixels, and the unrolled
  // loop's set-up costs more than the loop.
#pragma unroll 1
  for (int X = span.first; X <= span.last; ++X) atomicMax(keys + X, Keys::key(warp_hit_at(s, X, W), X));
}

// Source pixel x's depth as the warp reads it (warp_depth), from the
// row's cells.
template <class Keys, class Px>
__device__ float source_depth(const RowJob<Keys, Px> &j, int x) {
  return warp_depth(j.depth_row[x >> j.depth_shift]);
}

// Source pixel x placed in an eye with shift factor `shift`: warp_source()
// on the row's cells.
template <class Keys, class Px>
__device__ WarpSource place_source(const RowJob<Keys, Px> &j, int x, float shift) {
  const bool has_next = x + 1 < j.W;
  const float d0 = source_depth(j, x);
  return warp_place(x, d0, has_next ? source_depth(j, x + 1) : d0, has_next, shift, j.D, j.convergence);
}

// One eye's target X = base + lane of the row, from its final key: the
// colour sampled at the key's u (sample_word on j.row, the load_rgba()
// values of the source row, as the CPU's SourceRow), or a hole (counted in
// *holes; kHoleColour for fill=None). Called warp-uniformly (a warp covers
// one 32-pixel chunk) so that the fills take each chunk's hole bits by
// ballot. All else the fills need per chunk (BackgroundSmooth's chunk
// flags, tile list and states) is written after the loop, from the hole
// bits: in the loop it would cost about 18 instructions a pixel and eye,
// mostly for chunks without a hole (measured: docs/benchmarks.md, Design
// measurements, "Warp: resident rows, words, both eyes").
template <class Keys, HoleFill kFill, class Px>
__device__ void resolve_target(const RowJob<Keys, Px> &j, int eye, const OutRow<Px> &out_row, uint8_t *mask_row,
                               int base, int lane, int *holes) {
  const int X = base + lane;
  const bool in = X < j.W;
  const typename Keys::Word key = in ? j.keys[eye][X] : 1u;  // past the row: not a hole
  if (in) {
    if (key != 0) {
      out_row.store(X, sample_word(reinterpret_cast<const WordOf<Px> *>(j.row.plane[0]), j.W, Keys::u(key, X)));
    } else {
      ++*holes;
      if (kFill == HoleFill::None) out_row.store(X, rgba_word(colour_as<Px>(kHoleColour)));
    }
    if (kFill == HoleFill::NeighborAverage) mask_row[X] = key == 0 ? 1 : 0;
  }
  if (kFillBits<kFill>) {
    const unsigned chunk_holes = __ballot_sync(kFullMask, key == 0);
    if (lane == 0) j.hole_bits[eye][base >> 5] = chunk_holes;
  }
}

// An eye's NeighborAverage masks row (null for the other fills).
template <class Keys, HoleFill kFill, class Px>
__device__ uint8_t *mask_row_of(const RowJob<Keys, Px> &j, int eye) {
  return kFill == HoleFill::NeighborAverage ? j.mask + (static_cast<size_t>(eye) * j.H + j.y) * j.W : nullptr;
}

// The row fills of an eye whose resolve loop is done (behind a barrier):
// Background's nearest-pixel fill, or BackgroundSmooth's anchors (its
// clean bits are written before the barrier that precedes this).
template <class Keys, HoleFill kFill, class Px>
__device__ void fill_row(const RowJob<Keys, Px> &j, int eye) {
  if (kFill == HoleFill::BackgroundSmooth) smooth_anchor_row(j, eye);
  if (kFill == HoleFill::Background)
    background_fill_row<Keys>(j.out, reinterpret_cast<const Px *>(j.row.plane[0]), eye * j.W, j.y, j.keys[eye], j.W,
                              j.chunks, j.hole_bits[eye]);
}

// Renders one eye of the row; every thread of the block calls it. The fill
// is a template parameter, so that the per-pixel loops carry no test of the
// fills they do not serve (the row kernel is instruction bound).
template <class Keys, bool kSharedKeys, HoleFill kFill, class Px>
__device__ void render_eye(const RowJob<Keys, Px> &j, int eye, int *row_holes) {
  const float shift = j.eyes.shift[eye];
  uint8_t *mask_row = mask_row_of<Keys, kFill>(j, eye);
  const OutRow<Px> out_row(j.out, eye * j.W, j.y, j.words);
  if (shift == 0.f) {  // this eye is the source
    for (int x = threadIdx.x; x < j.W; x += blockDim.x) {
      out_row.store(x, reinterpret_cast<const WordOf<Px> *>(j.row.plane[0])[x]);
      if (kFill == HoleFill::NeighborAverage) mask_row[x] = 0;
    }
    return;
  }
  __syncthreads();  // the previous eye is done with keys and row_holes
  if (threadIdx.x == 0) *row_holes = 0;
  zero_keys<kSharedKeys>(j.keys[eye], j.W);
  __syncthreads();
  for (int x = threadIdx.x; x < j.W; x += blockDim.x)
    scatter_source<Keys>(j.keys[eye], place_source(j, x, shift), j.W);
  __syncthreads();

  int holes = 0;
  const int lane = threadIdx.x & 31;
  for (int base = threadIdx.x - lane; base < j.W; base += blockDim.x)
    resolve_target<Keys, kFill>(j, eye, out_row, mask_row, base, lane, &holes);
  if (holes) atomicAdd(row_holes, holes);
  __syncthreads();  // also publishes this row's colours to the fill below
  if (kFill == HoleFill::BackgroundSmooth) smooth_chunk_flags(j, eye);
  const int row_total = *row_holes;
  if (row_total == 0) return;  // block-uniform
  if (threadIdx.x == 0) atomicAdd(j.total, static_cast<unsigned long long>(row_total));
  if (kFill == HoleFill::BackgroundSmooth) {
    smooth_clean_bits(j, eye);
    __syncthreads();
  }
  fill_row<Keys, kFill>(j, eye);
}

// Both eyes rendered together (both shifts not 0, keys in shared memory,
// one z-buffer an eye): a source pixel's depths, read and clamped once,
// place it in both views (warp_source's arithmetic, so the same targets),
// and a target resolves both eyes in one pass. The z-buffers hold no
// colour, only where each target's hit comes from (depth and u codes), so
// they serve every row that reads the same cells: render_row_group() fills
// them once for all of its rows.

// Both eyes' z-buffers from the depth row j.depth_row (keys zeroed, behind
// a barrier). Every thread of the block calls it; the caller syncs after.
template <class Keys, class Px>
__device__ void scatter_both_eyes(const RowJob<Keys, Px> &j) {
  const float s0 = j.eyes.shift[0], s1 = j.eyes.shift[1];
  for (int x = threadIdx.x; x < j.W; x += blockDim.x) {
    const bool has_next = x + 1 < j.W;
    const float d0 = source_depth(j, x);
    const float d1 = has_next ? source_depth(j, x + 1) : d0;
    scatter_source<Keys>(j.keys[0], warp_place(x, d0, d1, has_next, s0, j.D, j.convergence), j.W);
    scatter_source<Keys>(j.keys[1], warp_place(x, d0, d1, has_next, s1, j.D, j.convergence), j.W);
  }
}

// Row j.y of both eyes from final z-buffers and the row's converted source
// (both behind a barrier), row_holes zeroed: the colours, the holes and
// their fills. Every thread of the block calls it; the row takes two
// barriers (three with BackgroundSmooth's clean bits).
template <class Keys, HoleFill kFill, class Px>
__device__ void resolve_both_eyes(const RowJob<Keys, Px> &j, int *row_holes) {
  int holes[2] = {0, 0};
  uint8_t *mask_rows[2] = {mask_row_of<Keys, kFill>(j, 0), mask_row_of<Keys, kFill>(j, 1)};
  const OutRow<Px> out_rows[2] = {OutRow<Px>(j.out, 0, j.y, j.words), OutRow<Px>(j.out, j.W, j.y, j.words)};
  const int lane = threadIdx.x & 31;
  for (int base = threadIdx.x - lane; base < j.W; base += blockDim.x) {
    resolve_target<Keys, kFill>(j, 0, out_rows[0], mask_rows[0], base, lane, &holes[0]);
    resolve_target<Keys, kFill>(j, 1, out_rows[1], mask_rows[1], base, lane, &holes[1]);
  }
  for (int eye = 0; eye < 2; ++eye)
    if (holes[eye]) atomicAdd(row_holes + eye, holes[eye]);
  __syncthreads();  // also publishes this row's colours to the fills below
  const bool any[2] = {row_holes[0] != 0, row_holes[1] != 0};  // block-uniform
  if (threadIdx.x == 0 && (any[0] || any[1]))
    atomicAdd(j.total, static_cast<unsigned long long>(row_holes[0]) + static_cast<unsigned long long>(row_holes[1]));
  if (kFill == HoleFill::BackgroundSmooth) {
    for (int eye = 0; eye < 2; ++eye) {
      smooth_chunk_flags(j, eye);
      if (any[eye]) smooth_clean_bits(j, eye);
    }
    if (!any[0] && !any[1]) return;
    __syncthreads();
  }
  for (int eye = 0; eye < 2; ++eye)
    if (any[eye]) fill_row<Keys, kFill>(j, eye);
}

// The source row y converted into j.row, a pixel pair a thread: a 4:2:0
// pair shares its chroma (load_rgba_pair_words, as the CPU's SourceRow).
template <class Keys, class Px>
__device__ void convert_source_row(const RowJob<Keys, Px> &j, const FrameView &src, const YuvToRgb &m, int y) {
  for (int x = 2 * threadIdx.x; x < j.W; x += 2 * blockDim.x)
    load_rgba_pair_words(src, x, y, m, reinterpret_cast<WordOf<Px> *>(j.row.plane[0]) + x);
}

// Rows y0 .. y0 + rows - 1, which all read the depth cells of row y0
// (j.depth_row), both eyes at once: the z-buffers are cleared and filled
// once (while the first source row converts), then each row is resolved
// from them with its own source row. Every thread of the block calls it.
// On a grid of 2 x 2 cells a row pair shares one scatter, on 4 x 4 cells
// (the automatic grid at 4K and 8K) four rows do; a row alone (full-size
// depth) takes three barriers, four with BackgroundSmooth's clean bits.
template <class Keys, HoleFill kFill, class Px>
__device__ void render_row_group(RowJob<Keys, Px> &j, const FrameView &src, const YuvToRgb &m, int y0, int rows,
                                 int *row_holes) {
  if (threadIdx.x < 2) row_holes[threadIdx.x] = 0;
  zero_keys<true>(j.keys[0], 2 * j.W);  // keys[1] follows keys[0]
  convert_source_row(j, src, m, y0);
  __syncthreads();
  scatter_both_eyes(j);
  __syncthreads();
  for (int r = 0;;) {
    j.y = y0 + r;
    resolve_both_eyes<Keys, kFill>(j, row_holes);
    if (++r >= rows) break;
    __syncthreads();  // this row's fills are done with the source row, its bits and row_holes
    if (threadIdx.x < 2) row_holes[threadIdx.x] = 0;
    convert_source_row(j, src, m, y0 + r);
    __syncthreads();
  }
}

// Output pixel (col, y) from a word: OutRow::store's bytes, with the
// row's address taken per store (a RowsTogether thread stores to several
// rows, and an OutRow for each would not fit its registers).
template <class Keys, class Px>
__device__ void store_word(const RowJob<Keys, Px> &j, int col, int y, WordOf<Px> w) {
  if (!j.words) {
    store_pixel(j.out, col, y, word_rgba(w));
    return;
  }
  store_pixel_word(reinterpret_cast<WordOf<Px> *>(j.out.plane[0] + static_cast<size_t>(y) * j.out.stride[0]) + col, w,
                   is_bgr_order(j.out.format));
}

// Target X of both eyes in the rows of a RowsTogether block with the pack
// fused (keys k0, k1; 0 is a hole): the anaglyph pixel where neither eye
// has a hole, else each covered eye's colour into the pair, for the sums
// kernel's fill and the patch kernel's mix.
template <class Keys, class Px>
__device__ void resolve_fused_target(const RowJob<Keys, Px> &j, const FusedAnaglyph &f, const uint32_t *rows0, int y0,
                                     int rows, int X, typename Keys::Word k0, typename Keys::Word k1) {
  const unsigned u0 = Keys::u(k0, X), u1 = Keys::u(k1, X);
  const bool pair_alpha = has_alpha(j.out.format);
  for (int r = 0; r < rows; ++r) {
    const uint32_t *row = rows0 + static_cast<size_t>(r) * j.W;
    if (k0 != 0 && k1 != 0) {
      store_aligned_word(f.out, X, y0 + r,
                         fused_anaglyph_word(f, sample_word(row, j.W, u0), sample_word(row, j.W, u1), pair_alpha));
      continue;
    }
    if (k0 != 0) store_word(j, X, y0 + r, sample_word(row, j.W, u0));
    if (k1 != 0) store_word(j, j.W + X, y0 + r, sample_word(row, j.W, u1));
  }
}

// The same rows resolved side by side (RowBlock::RowsTogether): every
// row's source converted at once into a buffer of its own (j.row holds
// row 0's, each next row's follows, W words apart), so that a target's key
// is read and decoded once for all the rows, its hole bit taken once (the
// rows' holes are the same: their z-buffers are), and the rows take the
// barriers of one. The fills then run row by row, as render_row_group's.
// kFused: the pack fused (resolve_fused_target; BackgroundSmooth only).
template <class Keys, HoleFill kFill, bool kFused, class Px>
__device__ void render_rows_together(RowJob<Keys, Px> &j, const FrameView &src, const YuvToRgb &m, int y0, int rows,
                                     int *row_holes, const FusedAnaglyph &fused) {
  static_assert(!kFused || kFill == HoleFill::BackgroundSmooth, "the fused pack's holes are filled by the sums kernel");
  WordOf<Px> *rows0 = reinterpret_cast<WordOf<Px> *>(j.row.plane[0]);
  if (threadIdx.x < 2) row_holes[threadIdx.x] = 0;
  zero_keys<true>(j.keys[0], 2 * j.W);  // keys[1] follows keys[0]
  for (int r = 0; r < rows; ++r) {
    j.row.plane[0] = reinterpret_cast<uint8_t *>(rows0 + static_cast<size_t>(r) * j.W);
    convert_source_row(j, src, m, y0 + r);
  }
  __syncthreads();
  scatter_both_eyes(j);
  __syncthreads();

  int holes[2] = {0, 0};
  const int lane = threadIdx.x & 31;
  for (int base = threadIdx.x - lane; base < j.W; base += blockDim.x) {
    const int X = base + lane;
    const bool in = X < j.W;
    if constexpr (kFused) {
      const typename Keys::Word k0 = in ? j.keys[0][X] : 1u, k1 = in ? j.keys[1][X] : 1u;  // past the row: no hole
      if (in) {
        holes[0] += k0 == 0;
        holes[1] += k1 == 0;
        resolve_fused_target(j, fused, rows0, y0, rows, X, k0, k1);
      }
      const unsigned chunk_holes0 = __ballot_sync(kFullMask, k0 == 0), chunk_holes1 = __ballot_sync(kFullMask, k1 == 0);
      if (lane == 0) {
        j.hole_bits[0][base >> 5] = chunk_holes0;
        j.hole_bits[1][base >> 5] = chunk_holes1;
      }
    } else {
#pragma unroll
      for (int eye = 0; eye < 2; ++eye) {
        const typename Keys::Word key = in ? j.keys[eye][X] : 1u;  // past the row: not a hole
        if (in) {
          if (key != 0) {
            const unsigned u = Keys::u(key, X);
            for (int r = 0; r < rows; ++r)
              store_word(j, eye * j.W + X, y0 + r, sample_word(rows0 + static_cast<size_t>(r) * j.W, j.W, u));
          } else {
            ++holes[eye];
            if (kFill == HoleFill::None)
              for (int r = 0; r < rows; ++r)
                store_word(j, eye * j.W + X, y0 + r, rgba_word(colour_as<Px>(kHoleColour)));
          }
          if (kFill == HoleFill::NeighborAverage)
            for (int r = 0; r < rows; ++r)
              j.mask[(static_cast<size_t>(eye) * j.H + y0 + r) * j.W + X] = key == 0 ? 1 : 0;
        }
        if (kFillBits<kFill>) {
          const unsigned chunk_holes = __ballot_sync(kFullMask, key == 0);
          if (lane == 0) j.hole_bits[eye][base >> 5] = chunk_holes;
        }
      }
    }
  }
  for (int eye = 0; eye < 2; ++eye)
    if (holes[eye]) atomicAdd(row_holes + eye, holes[eye]);
  __syncthreads();  // also publishes the rows' colours to the fills below
  const bool any[2] = {row_holes[0] != 0, row_holes[1] != 0};  // block-uniform
  if (threadIdx.x == 0 && (any[0] || any[1]))
    atomicAdd(j.total, static_cast<unsigned long long>(rows) * (static_cast<unsigned long long>(row_holes[0]) +
                                                               static_cast<unsigned long long>(row_holes[1])));
  if (kFill == HoleFill::BackgroundSmooth) {
    for (int r = 0; r < rows; ++r) {
      j.y = y0 + r;
      for (int eye = 0; eye < 2; ++eye) smooth_chunk_flags(j, eye);
    }
    for (int eye = 0; eye < 2; ++eye)
      if (any[eye]) smooth_clean_bits(j, eye);
    if (!any[0] && !any[1]) return;
    __syncthreads();
  }
  for (int r = 0; r < rows; ++r) {
    j.y = y0 + r;
    j.row.plane[0] = reinterpret_cast<uint8_t *>(rows0 + static_cast<size_t>(r) * j.W);
    for (int eye = 0; eye < 2; ++eye)
      if (any[eye]) fill_row<Keys, kFill>(j, eye);
  }
}

// One block = output rows y0 .. y0 + group_rows - 1 (y0 = blockIdx.x *
// group_rows, cut at the picture's end; past the tail's first row, one
// row or one eye of one row, below), both eyes, so each source row is
// converted once. Keys: the key word (NarrowKeys where they fit,
// common/warp.h). kSharedKeys: the z-buffer in shared memory, else in
// global_keys (one W-key row per block). kBothEyes: both eyes at once, a
// z-buffer each (render_row_group; shared keys only), else one after the
// other through one z-buffer (render_eye; one row a block). depth: the
// picture's depth on any grid (p3d_defs.h DepthGrid; the filter's coarse
// cells are read in place, one shift a read); a block's rows all read the
// same cells (group_rows divides 1 << depth.shift). The first group_blocks
// blocks take group_rows rows each from the top, every later one a single
// row, or in RowsTogether kernels one eye of one row (group_tail_y0: the
// rows that would leave a last wave of groups mostly idle).
// kBlock: the block's kind (RowBlock, cuda/warp_plan.h).
// A row's block: at most 512 threads, as many blocks per SM as it holds
// threads for (cuda/launch_bounds.cuh: 4 on sm_80, sm_90 and sm_100, at
// most 32 registers a thread; 3 on the other Ampere to Blackwell parts,
// 40; 2 on Turing); launch_rows asks for the largest shared-memory
// carveout. The kernel is instruction bound (Nsight Compute at 4K: three
// quarters of the issue slots, a fifth of DRAM's bandwidth), so every
// further resident row helps (the fourth fits with 32-bit keys: 32 KB of
// shared memory a row at 4K). Under the 32-register bound (sm_90) only the
// Group and WideGroup kernels with BackgroundSmooth (ptxas: 4 bytes) and
// RowsTogether with NeighborAverage (44) spill. Both eyes at once take a
// second z-buffer (15 KB at 4K, still four rows an SM) and save a scatter's
// depth reads and the eyes' barriers; from about 4600 pixels a row on
// Hopper it would cost a resident row, and the eyes go in turn (measured:
// docs/benchmarks.md, Design measurements, "Warp: resident rows, words,
// both eyes").
// A WideGroup or RowsTogether block: half the threads an SM holds.
constexpr int kWideGroupThreads = P3D_MAX_THREADS_PER_SM / 2;
template <class Keys, bool kSharedKeys, HoleFill kFill, bool kBothEyes, RowBlock kBlock, bool kFused, class Px>
__global__ void __launch_bounds__(kBlock == RowBlock::WideGroup || kBlock == RowBlock::RowsTogether ? kWideGroupThreads
                                                                                                  : kRowThreadsMax,
                                  kBlock == RowBlock::WideGroup || kBlock == RowBlock::RowsTogether
                                      ? 2
                                      : P3D_MAX_THREADS_PER_SM / kRowThreadsMax)
    warp_row_kernel(FrameView src, YuvToRgb m, DepthGrid<const float> depth, FrameView out, EyeShifts eyes, float D,
                    float convergence, typename Keys::Word *global_keys, uint8_t *mask, SmoothScratch smooth,
                    unsigned long long *total, bool words, int group_rows, int group_blocks, FusedAnaglyph fused,
                    StageGate gate) {
  chained_kernel_start();
  if (gate.closed()) return;  // the smooth fill then finds no tile listed (rows: below)
  static_assert(kSharedKeys || !kBothEyes, "both eyes at once keep their keys in shared memory");
  static_assert(!kFused || kBlock == RowBlock::RowsTogether, "the pack is fused in RowsTogether blocks");
  static_assert(kBothEyes || kBlock == RowBlock::Row, "row groups render both eyes at once");
  extern __shared__ __align__(16) unsigned long long smem[];  // 16: zero_keys() stores uint4
  __shared__ int row_holes[2];
  constexpr int kEyeArrays = kBothEyes ? 2 : 1;
  // group_blocks blocks of group_rows rows, then the tail (group_tail_y0):
  // a block for each eye of every later row in RowsTogether kernels
  // (kEyeTail), a block a row in the others.
  constexpr bool kEyeTail = tail_blocks_a_row(kBlock) == 2;
  const int b = static_cast<int>(blockIdx.x);
  const bool in_tail = kBlock != RowBlock::Row && b >= group_blocks;
  const int y0 = kBlock == RowBlock::Row ? b
                 : in_tail               ? group_blocks * group_rows + ((b - group_blocks) >> (kEyeTail ? 1 : 0))
                                         : b * group_rows;
  const int block_rows = min(kBlock == RowBlock::Row || in_tail ? 1 : group_rows, src.height - y0);
  if (gate.skips_rows(y0, block_rows)) return;  // the target keeps these rows, its fill's states and anchors
  RowJob<Keys, Px> j;
  j.y = y0;
  j.W = src.width;
  j.H = src.height;
  j.chunks = row_chunks(j.W);
  j.out = out;
  j.eyes = eyes;
  j.D = D;
  j.convergence = convergence;
  j.depth_row = depth.cell_row(y0);
  j.depth_shift = depth.shift;
  auto *shared_keys = reinterpret_cast<typename Keys::Word *>(smem);
  j.keys[0] = kSharedKeys ? shared_keys : global_keys + static_cast<size_t>(y0) * j.W;
  // The source row after the keys, aligned to its pixels (row_smem_bytes).
  const size_t key_bytes = kSharedKeys ? sizeof(typename Keys::Word) * kEyeArrays * j.W : 0;
  uint8_t *rgba = reinterpret_cast<uint8_t *>(smem) + (key_bytes + sizeof(Px) - 1) / sizeof(Px) * sizeof(Px);
  const int source_rows = kBlock == RowBlock::RowsTogether ? group_rows : 1;  // source row buffers
  j.hole_bits[0] = reinterpret_cast<unsigned *>(rgba + sizeof(Px) * static_cast<size_t>(j.W) * source_rows);
  j.clean_bits[0] = j.hole_bits[0] + kEyeArrays * j.chunks;
  j.keys[1] = j.keys[0] + (kBothEyes ? j.W : 0);
  j.hole_bits[1] = j.hole_bits[0] + (kBothEyes ? j.chunks : 0);
  j.clean_bits[1] = j.clean_bits[0] + (kBothEyes ? j.chunks : 0);
  j.mask = mask;
  j.smooth = smooth;
  j.total = total;
  j.words = words;
  j.row.format = sizeof(Px) == 8 ? PixelFormat::RGBA64 : PixelFormat::RGBA;
  j.row.width = j.W;
  j.row.height = 1;
  j.row.plane[0] = rgba;
  j.row.stride[0] = static_cast<int>(sizeof(Px)) * j.W;

  if (kEyeTail && in_tail) {  // one eye of one row
    convert_source_row(j, src, m, y0);
    __syncthreads();
    // Eye 1 takes eye 0's z-buffer, which is 16-byte aligned for
    // zero_keys' stores (keys[1] is W words further: not aligned where W
    // is not a multiple of 4); the block renders no other eye.
    j.keys[1] = j.keys[0];
    if ((b - group_blocks) & 1)  // constant eyes: j's arrays stay in registers
      render_eye<Keys, kSharedKeys, kFill>(j, 1, &row_holes[0]);
    else
      render_eye<Keys, kSharedKeys, kFill>(j, 0, &row_holes[0]);
  } else if (kBlock == RowBlock::RowsTogether) {
    render_rows_together<Keys, kFill, kFused>(j, src, m, y0, block_rows, row_holes, fused);
  } else if (kBothEyes) {  // a row's block has one row (a constant, so no loop is compiled in)
    render_row_group<Keys, kFill>(j, src, m, y0, kBlock == RowBlock::Row ? 1 : block_rows, row_holes);
  } else {
    convert_source_row(j, src, m, y0);
    __syncthreads();
    render_eye<Keys, kSharedKeys, kFill>(j, 0, &row_holes[0]);
    render_eye<Keys, kSharedKeys, kFill>(j, 1, &row_holes[0]);
  }
}

// The row kernel of a key word, key place, eye order, block kind, fill and
// pixel type; kFused: with the pack fused (BackgroundSmooth only, else null).
template <class Keys, bool kSharedKeys, bool kBothEyes, RowBlock kBlock, bool kFused = false, class Px = Rgba>
auto row_kernel_for(HoleFill fill)
    -> decltype(&warp_row_kernel<Keys, kSharedKeys, HoleFill::BackgroundSmooth, kBothEyes, kBlock, kFused, Px>) {
  if constexpr (kFused) {
    return fill == HoleFill::BackgroundSmooth
               ? warp_row_kernel<Keys, kSharedKeys, HoleFill::BackgroundSmooth, kBothEyes, kBlock, true, Px>
               : nullptr;
  } else {
    switch (fill) {
      case HoleFill::Background:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::Background, kBothEyes, kBlock, false, Px>;
      case HoleFill::NeighborAverage:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::NeighborAverage, kBothEyes, kBlock, false, Px>;
      case HoleFill::None:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::None, kBothEyes, kBlock, false, Px>;
      case HoleFill::BackgroundSmooth:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::BackgroundSmooth, kBothEyes, kBlock, false, Px>;
    }
    return nullptr;
  }
}

template <class Keys, bool kSharedKeys, bool kBothEyes, RowBlock kBlock, bool kFused = false, class Px = Rgba>
CudaStatus launch_rows(const RowLaunch &l) {
  const auto row_kernel = row_kernel_for<Keys, kSharedKeys, kBothEyes, kBlock, kFused, Px>(l.fill);
  if (!row_kernel) return CudaStatus{cudaErrorInvalidValue, "WarpParams::fill is a HoleFill", __FILE__, __LINE__};
  P3D_CUDA_TRY_STATUS(allow_shared_memory(reinterpret_cast<const void *>(row_kernel), l.smem_optin, l.attributes_set));
  static_assert(kSharedKeys || sizeof(typename Keys::Word) == sizeof(*l.global_keys), "global keys are wide");
  const int rows = kBlock == RowBlock::Row ? 1 : l.group_rows;
  const int tail_y0 = kBlock == RowBlock::Row ? l.src.height : l.tail_y0;
  const int group_blocks = tail_y0 / rows;
  const unsigned blocks =
      static_cast<unsigned>(group_blocks + tail_blocks_a_row(kBlock) * max(0, l.src.height - tail_y0));
  const int threads = kBlock == RowBlock::WideGroup || kBlock == RowBlock::RowsTogether ? l.wide_group_threads
                                                                                        : row_threads(l.src.width);
  P3D_CUDA_TRY(launch_chained(row_kernel, blocks, threads, l.smem, l.stream, l.src, l.m, l.depth, l.out, l.eyes, l.D,
                              l.convergence, reinterpret_cast<typename Keys::Word *>(l.global_keys), l.mask, l.smooth,
                              l.total, l.words, rows, group_blocks, l.fused, l.gate));
  return {};
}


// Threads an SM holds resident of a kernel with blocks of `threads` and
// `smem` bytes of dynamic shared memory (attributes set beforehand).
CudaStatus resident_threads(const void *kernel, int threads, size_t smem, int *resident) {
  int blocks = 0;
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&blocks, kernel, threads, smem));
  *resident = blocks * threads;
  return {};
}

// choose_row_kernels' residency of each candidate kernel of pixels Px,
// read from the device: every kernel's shared-memory attributes set
// first, then the threads an SM holds of each (RowsTogether only where its
// block fits).
template <class Px>
CudaStatus query_row_kernels_of(HoleFill fill, int W, int smem_optin, std::vector<const void *> *attributes_set,
                                RowKernelChoice *choice) {
  constexpr size_t kPx = sizeof(Px);
  if (!both_eyes_fit(W, smem_optin, kPx)) {
    *choice = choose_row_kernels(fill, W, smem_optin, RowKernelResidency{}, kPx);
    return {};
  }
  const size_t smem_both = row_smem_bytes(W, sizeof(NarrowKeys::Word), 2, kPx);
  const auto in_turn = row_kernel_for<NarrowKeys, true, false, RowBlock::Row, false, Px>(fill);
  const auto both = row_kernel_for<NarrowKeys, true, true, RowBlock::Row, false, Px>(fill);
  const auto group = row_kernel_for<NarrowKeys, true, true, RowBlock::Group, false, Px>(fill);
  const auto wide = row_kernel_for<NarrowKeys, true, true, RowBlock::WideGroup, false, Px>(fill);
  const auto together = row_kernel_for<NarrowKeys, true, true, RowBlock::RowsTogether, false, Px>(fill);
  if (!in_turn || !both || !group || !wide || !together)
    return CudaStatus{cudaErrorInvalidValue, "WarpParams::fill is a HoleFill", __FILE__, __LINE__};
  for (const void *k : {reinterpret_cast<const void *>(in_turn), reinterpret_cast<const void *>(both),
                        reinterpret_cast<const void *>(group), reinterpret_cast<const void *>(wide),
                        reinterpret_cast<const void *>(together)})
    P3D_CUDA_TRY_STATUS(allow_shared_memory(k, smem_optin, attributes_set));
  RowKernelResidency r;
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(in_turn), row_threads(W),
                                       row_smem_bytes(W, sizeof(NarrowKeys::Word), 1, kPx), &r.in_turn));
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(both), row_threads(W), smem_both, &r.both));
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(group), row_threads(W), smem_both, &r.group));
  // A wide block's size is its kernel's launch bound on this device's
  // architecture (kWideGroupThreads of the machine code it runs).
  cudaFuncAttributes wide_attr{}, together_attr{};
  P3D_CUDA_TRY(cudaFuncGetAttributes(&wide_attr, reinterpret_cast<const void *>(wide)));
  P3D_CUDA_TRY(cudaFuncGetAttributes(&together_attr, reinterpret_cast<const void *>(together)));
  r.wide_block = wide_attr.maxThreadsPerBlock;
  r.together_block = together_attr.maxThreadsPerBlock;
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(wide), r.wide_block, smem_both, &r.wide));
  if (rows_together_fit(W, smem_optin, kPx))
    P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(together), r.together_block,
                                         together_smem_bytes(W, 1 << kGroupShiftMax, kPx), &r.together));
  int dev = 0;
  P3D_CUDA_TRY(cudaGetDevice(&dev));
  P3D_CUDA_TRY(cudaDeviceGetAttribute(&r.sms, cudaDevAttrMultiProcessorCount, dev));
  *choice = choose_row_kernels(fill, W, smem_optin, r, kPx);
  return {};
}

}  // namespace
}  // namespace warp_detail
}  // namespace p3d
