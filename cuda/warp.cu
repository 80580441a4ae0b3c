// GPU DIBR warp (cuda/warp_gpu.h): kernels and the host launcher. Every
// per-pixel decision calls the P3D_HD helpers of common/warp.h.
//
// Rows are independent for everything but NeighborAverage, so one block
// renders one output row, both eyes, from start to end: the source row is
// converted to RGBA once into shared memory, the z-buffer lives in shared
// memory (global memory only for rows too wide for it), scatter, resolve and
// the Background fill follow each other behind __syncthreads, and nothing
// but the depth row, the source row and the output row touches DRAM.
#include "chained_launch.cuh"
#include "pack_gpu.h"
#include "warp_gpu.h"

#include <utility>
#include <vector>

#include "launch_bounds.cuh"

namespace p3d {

// The anaglyph output of a fused render (WarpRendererGpu::render_packed,
// below): `out` W x H, packed RGB in the pair's format with 4-byte aligned
// rows; the gamma mix's fixed-point matrices (anaglyph_mix_word,
// common/pack.h), kernel parameters so that the mix reads them as constant
// operands; `swap`: the right eye is shown as the left
// (PackParams::swap_eyes). out.plane[0] null: not fused.
struct FusedAnaglyph {
  FrameView out;
  int32_t left[9], right[9];  // AnaglyphMatrices::left_q, right_q
  bool swap;
};

namespace {

constexpr unsigned kFullMask = 0xffffffffu;
constexpr int kBlockX = 32;  // NeighborAverage kernels: one warp = one row segment
constexpr int kBlockY = 8;

// The eyes' shift factors (0: copy the source).
struct EyeShifts {
  float shift[2];
};

// Layout of counters_, zeroed every frame: total hole count, the per-step
// fill counts of one NeighborAverage batch, BackgroundSmooth's tile count,
// then its tile marks (one word a tile).
constexpr size_t kTotalOffset = 0;
constexpr size_t kFilledOffset = sizeof(unsigned long long);
constexpr size_t kTileCountOffset = kFilledOffset + sizeof(unsigned) * kWarpFillBatch;
constexpr size_t kTileMarksOffset = kTileCountOffset + sizeof(unsigned);

// Dynamic shared memory of the row kernel: [keys: W key words an eye when
// in shared memory] [the source row, W x RGBA] [per 32-pixel chunk and eye:
// its hole bits (bit i: pixel 32 c + i is a hole)] [the same for its clean
// bits (BackgroundSmooth)]. key_bytes: a key word's size, 0 for keys in
// global memory; eyes: the eyes that have arrays of their own (2 when the
// kernel renders them together, else 1).
__host__ __device__ int row_chunks(int W) { return (W + 31) / 32; }
size_t row_smem_bytes(int W, size_t key_bytes, int eyes) {
  return eyes * key_bytes * W + 4 * static_cast<size_t>(W) +
         eyes * 2 * sizeof(unsigned) * static_cast<size_t>(row_chunks(W));
}

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
// load_rgba would read it back: sampled again from the converted source row
// in shared memory instead of read from global memory; RGBx/BGRx read back
// alpha 255.
__device__ Rgba rendered_colour(const FrameView &out, const Rgba *src_row, int W, unsigned u) {
  Rgba c = sample_row(src_row, W, u);
  if (!has_alpha(out.format)) c.a = 255;
  return c;
}

// ---- Pixels as 32-bit words --------------------------------------------------
// The source row in shared memory holds rgba_word() of each load_rgba()
// value, and covered pixels are resolved with sample_word() (common/warp.h)
// and stored with one 32-bit store (measured: docs/benchmarks.md, Design
// measurements, "Warp: resident rows, words, both eyes").

// One eye's part of output row y, which starts at column col0 of `out`:
// store() is store_rgba() of a word, one 32-bit store when the frame's rows
// are 4-byte aligned (`words`, checked once by the launcher), r and b
// swapped for the BGR orders. The row's address is taken once, not per
// pixel (64-bit arithmetic).
struct OutRow {
  const FrameView *out;
  uint32_t *words;  // the eye's first pixel in the row; null: rows not 4-byte aligned
  int col0, y;
  bool bgr;
  __device__ OutRow(const FrameView &frame, int col0_, int y_, bool aligned)
      : out(&frame),
        words(aligned ? reinterpret_cast<uint32_t *>(frame.plane[0] + static_cast<size_t>(y_) * frame.stride[0]) + col0_
                      : nullptr),
        col0(col0_),
        y(y_),
        bgr(is_bgr_order(frame.format)) {}
  __device__ void store(int X, uint32_t w) const {
    if (!words) {
      store_rgba(*out, col0 + X, y, word_rgba(w));
      return;
    }
    words[X] = bgr ? swap_rb_word(w) : w;
  }
};

// Background fill of one row whose keys are final and whose chunks' hole
// bits are in hole_bits: each hole's nearest non-holes by bit search.
template <class Keys>
__device__ void background_fill_row(const FrameView &out, const Rgba *src_row, int col0, int y,
                                    const typename Keys::Word *keys, int W, int chunks, const unsigned *hole_bits) {
  for (int X = threadIdx.x; X < W; X += blockDim.x) {
    const int c = X >> 5, bit = X & 31;
    if (!((hole_bits[c] >> bit) & 1u)) continue;
    const int xl = nearest_left(hole_bits, true, W, c, bit), xr = nearest_right(hole_bits, true, W, chunks, c, bit);
    const int pick = background_source(X, xl, key_depth_at<Keys>(keys, xl), xr, key_depth_at<Keys>(keys, xr));
    store_rgba(out, col0 + X, y, pick >= 0 ? rendered_colour(out, src_row, W, Keys::u(keys[pick], pick)) : kFillBlack);
  }
}

// ---- Pack fused into the warp (WarpRendererGpu::render_packed) -------------
// An anaglyph pixel needs both eyes' colours at one target, which the
// RowsTogether kernel holds at once: where neither eye has a hole there it
// writes the anaglyph pixel itself, and the pair (render_packed's scratch)
// gets only the colours next to holes. The sums kernel then fills the
// holes in the pair, and a last kernel (fused_anaglyph_patch_kernel) mixes
// the pixels where either eye had a hole, and the tail rows, whose blocks
// render one eye each. The 4K pair (66 MB) is then neither written whole
// nor read back by a pack kernel.

// The anaglyph of the pair's words w0 (left eye) and w1 (rgba_word order)
// as pack's anaglyph() mixes them after load_rgba() reads them back from a
// pair of `pair_alpha` (alpha 255 in the formats without one), as a word.
__device__ uint32_t fused_anaglyph_word(const FusedAnaglyph &f, uint32_t w0, uint32_t w1, bool pair_alpha) {
  const uint32_t l = f.swap ? w1 : w0, r = f.swap ? w0 : w1;
  return pack_detail::anaglyph_mix_word(f.left, f.right, pair_alpha ? l : l | 0xff000000u, r);
}

// Pixel (col, y) of a frame with 4-byte aligned rows from a word in
// rgba_word order: store_rgba()'s bytes in one store.
__device__ void store_aligned_word(const FrameView &out, int col, int y, uint32_t w) {
  reinterpret_cast<uint32_t *>(out.plane[0] + static_cast<size_t>(y) * out.stride[0])[col] =
      is_bgr_order(out.format) ? swap_rb_word(w) : w;
}

// BackgroundSmooth's scratch (both eyes, W x H each) and its tiles. The
// sums kernel works on tiles of 32 columns (one chunk) x `tile_rows` rows
// of one eye; the row kernel lists the tiles that hold a hole (after each
// eye's resolve loop), so that the sums kernel visits those and no others
// (most tiles of a frame have none: launching a block for each would cost
// about as much as the sums themselves). Tile t = (eye * tiles_y + y /
// tile_rows) * tiles_x + chunk.
struct SmoothScratch {
  uint8_t *state;        // kState* flags of every pixel of the chunks with holes
  Rgba *anchor;          // every hole's anchor
  uint8_t *chunk_holes;  // whether each 32-pixel chunk of a row has a hole (2 eyes x H x chunks)
  unsigned *tile_mark;   // per tile: listed yet (zeroed every frame)
  unsigned *tile_list;   // the listed tiles, in no particular order
  unsigned *tile_count;  // how many are listed (zeroed every frame)
  int tile_rows, tiles_x, tiles_y;
};

// What one block works on: output row y, its converted source row in shared
// memory, its z-buffers, the chunk arrays of the fills. Indexed by eye: a
// kernel that renders the eyes one after the other points both entries at
// one array; one that renders them together (kBothEyes) has one for each.
template <class Keys>
struct RowJob {
  FrameView out;
  FrameView row;  // the source row as RGBA bytes in shared memory (y = 0)
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
  bool words;  // out's rows are 4-byte aligned: OutRow stores words
};

// ---- BackgroundSmooth (common/warp.h) ----------------------------------------
// The row kernel finds every hole's anchor (the clean and non-hole pixels
// are row-local, and the keys are in shared memory), then one kernel
// (smooth_tile_kernel) sums the anchors down the column runs and along the
// row runs of holes. Scratch per eye (W x H each): state (uint8 flags
// below), anchor (Rgba). Integer sums throughout, so every reduction order
// gives the CPU's result.

// State flags of a pixel: a hole (0: not one, so not summed), has an anchor.
constexpr uint8_t kStateHole = 1, kStateAnchor = 2;
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
template <class Keys>
__device__ void smooth_chunk_flags(const RowJob<Keys> &j, int eye) {
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
template <class Keys>
__device__ void smooth_clean_bits(const RowJob<Keys> &j, int eye) {
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
template <class Keys>
__device__ void smooth_anchor_row(const RowJob<Keys> &j, int eye) {
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
    j.smooth.anchor[row + X] =
        rendered_colour(j.out, reinterpret_cast<const Rgba *>(j.row.plane[0]), j.W, Keys::u(keys[pick], pick));
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
template <class Keys>
__device__ float source_depth(const RowJob<Keys> &j, int x) {
  return warp_depth(j.depth_row[x >> j.depth_shift]);
}

// Source pixel x placed in an eye with shift factor `shift`: warp_source()
// on the row's cells.
template <class Keys>
__device__ WarpSource place_source(const RowJob<Keys> &j, int x, float shift) {
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
template <class Keys, HoleFill kFill>
__device__ void resolve_target(const RowJob<Keys> &j, int eye, const OutRow &out_row, uint8_t *mask_row, int base,
                               int lane, int *holes) {
  const int X = base + lane;
  const bool in = X < j.W;
  const typename Keys::Word key = in ? j.keys[eye][X] : 1u;  // past the row: not a hole
  if (in) {
    if (key != 0) {
      out_row.store(X, sample_word(reinterpret_cast<const uint32_t *>(j.row.plane[0]), j.W, Keys::u(key, X)));
    } else {
      ++*holes;
      if (kFill == HoleFill::None) out_row.store(X, rgba_word(kHoleColour));
    }
    if (kFill == HoleFill::NeighborAverage) mask_row[X] = key == 0 ? 1 : 0;
  }
  if (kFillBits<kFill>) {
    const unsigned chunk_holes = __ballot_sync(kFullMask, key == 0);
    if (lane == 0) j.hole_bits[eye][base >> 5] = chunk_holes;
  }
}

// An eye's NeighborAverage masks row (null for the other fills).
template <class Keys, HoleFill kFill>
__device__ uint8_t *mask_row_of(const RowJob<Keys> &j, int eye) {
  return kFill == HoleFill::NeighborAverage ? j.mask + (static_cast<size_t>(eye) * j.H + j.y) * j.W : nullptr;
}

// The row fills of an eye whose resolve loop is done (behind a barrier):
// Background's nearest-pixel fill, or BackgroundSmooth's anchors (its
// clean bits are written before the barrier that precedes this).
template <class Keys, HoleFill kFill>
__device__ void fill_row(const RowJob<Keys> &j, int eye) {
  if (kFill == HoleFill::BackgroundSmooth) smooth_anchor_row(j, eye);
  if (kFill == HoleFill::Background)
    background_fill_row<Keys>(j.out, reinterpret_cast<const Rgba *>(j.row.plane[0]), eye * j.W, j.y, j.keys[eye], j.W,
                              j.chunks, j.hole_bits[eye]);
}

// Renders one eye of the row; every thread of the block calls it. The fill
// is a template parameter, so that the per-pixel loops carry no test of the
// fills they do not serve (the row kernel is instruction bound).
template <class Keys, bool kSharedKeys, HoleFill kFill>
__device__ void render_eye(const RowJob<Keys> &j, int eye, int *row_holes) {
  const float shift = j.eyes.shift[eye];
  uint8_t *mask_row = mask_row_of<Keys, kFill>(j, eye);
  const OutRow out_row(j.out, eye * j.W, j.y, j.words);
  if (shift == 0.f) {  // this eye is the source
    for (int x = threadIdx.x; x < j.W; x += blockDim.x) {
      out_row.store(x, reinterpret_cast<const uint32_t *>(j.row.plane[0])[x]);
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
template <class Keys>
__device__ void scatter_both_eyes(const RowJob<Keys> &j) {
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
template <class Keys, HoleFill kFill>
__device__ void resolve_both_eyes(const RowJob<Keys> &j, int *row_holes) {
  int holes[2] = {0, 0};
  uint8_t *mask_rows[2] = {mask_row_of<Keys, kFill>(j, 0), mask_row_of<Keys, kFill>(j, 1)};
  const OutRow out_rows[2] = {OutRow(j.out, 0, j.y, j.words), OutRow(j.out, j.W, j.y, j.words)};
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
template <class Keys>
__device__ void convert_source_row(const RowJob<Keys> &j, const FrameView &src, const YuvToRgb &m, int y) {
  for (int x = 2 * threadIdx.x; x < j.W; x += 2 * blockDim.x)
    load_rgba_pair_words(src, x, y, m, reinterpret_cast<uint32_t *>(j.row.plane[0]) + x);
}

// Rows y0 .. y0 + rows - 1, which all read the depth cells of row y0
// (j.depth_row), both eyes at once: the z-buffers are cleared and filled
// once (while the first source row converts), then each row is resolved
// from them with its own source row. Every thread of the block calls it.
// On a grid of 2 x 2 cells a row pair shares one scatter, on 4 x 4 cells
// (the automatic grid at 4K and 8K) four rows do; a row alone (full-size
// depth) takes three barriers, four with BackgroundSmooth's clean bits.
template <class Keys, HoleFill kFill>
__device__ void render_row_group(RowJob<Keys> &j, const FrameView &src, const YuvToRgb &m, int y0, int rows,
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
template <class Keys>
__device__ void store_word(const RowJob<Keys> &j, int col, int y, uint32_t w) {
  if (!j.words) {
    store_rgba(j.out, col, y, word_rgba(w));
    return;
  }
  store_aligned_word(j.out, col, y, w);
}

// Target X of both eyes in the rows of a RowsTogether block with the pack
// fused (keys k0, k1; 0 is a hole): the anaglyph pixel where neither eye
// has a hole, else each covered eye's colour into the pair, for the sums
// kernel's fill and the patch kernel's mix.
template <class Keys>
__device__ void resolve_fused_target(const RowJob<Keys> &j, const FusedAnaglyph &f, const uint32_t *rows0, int y0,
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
template <class Keys, HoleFill kFill, bool kFused>
__device__ void render_rows_together(RowJob<Keys> &j, const FrameView &src, const YuvToRgb &m, int y0, int rows,
                                     int *row_holes, const FusedAnaglyph &fused) {
  static_assert(!kFused || kFill == HoleFill::BackgroundSmooth, "the fused pack's holes are filled by the sums kernel");
  uint32_t *rows0 = reinterpret_cast<uint32_t *>(j.row.plane[0]);
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
    if (kFused) {
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
              for (int r = 0; r < rows; ++r) store_word(j, eye * j.W + X, y0 + r, rgba_word(kHoleColour));
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
// kBlock: one row a block (RowBlock::Row), or the rows of a group in a
// block of a row's size and launch bounds (Group) or in one of half the
// threads an SM holds, one row after another (WideGroup) or side by side
// with a source row buffer each (RowsTogether: render_rows_together).
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
// A WideGroup block: half the threads an SM holds (1024 on Hopper), two an
// SM, for rows whose both z-buffers would leave room for fewer row blocks
// (8K: 92 KB of shared memory a block, two still fit an SM, where a row's
// block of 512 threads would keep two, 1024 threads, resident). Where a
// row's block keeps as many threads resident (4K), Group blocks are faster
// than WideGroup ones, whose 1024 threads share 3840 pixels unevenly, one
// row at a time (measured: docs/benchmarks.md, Design measurements, "Warp:
// row groups"). A RowsTogether block has WideGroup's size and bounds, but
// its threads resolve all of the group's rows in one pass.
enum class RowBlock { Row, Group, WideGroup, RowsTogether };
// Blocks a row of the tail (group_tail_y0) takes: one an eye in
// RowsTogether kernels, where the shorter blocks pay (4K), one a row in
// the others, where the eyes' path would make the groups' code spill more
// (measured: docs/benchmarks.md, Design measurements, "Warp: row groups").
__host__ __device__ constexpr int tail_blocks_a_row(RowBlock b) { return b == RowBlock::RowsTogether ? 2 : 1; }
constexpr int kRowThreadsMax = 512;
constexpr int kWideGroupThreads = P3D_MAX_THREADS_PER_SM / 2;
// At most 1 << kGroupShiftMax rows a group (4: the 4K and 8K grids'
// cells). Even where that leaves few blocks for the GPU's slots (4K: 540
// Group blocks for 528 slots on a Hopper card of 132 SMs) the longer
// groups win over groups of 2 rows (measured: docs/benchmarks.md, Design
// measurements, "Warp: row groups").
constexpr int kGroupShiftMax = 2;
template <class Keys, bool kSharedKeys, HoleFill kFill, bool kBothEyes, RowBlock kBlock, bool kFused>
__global__ void __launch_bounds__(kBlock == RowBlock::WideGroup || kBlock == RowBlock::RowsTogether ? kWideGroupThreads
                                                                                                  : kRowThreadsMax,
                                  kBlock == RowBlock::WideGroup || kBlock == RowBlock::RowsTogether
                                      ? 2
                                      : P3D_MAX_THREADS_PER_SM / kRowThreadsMax)
    warp_row_kernel(FrameView src, YuvToRgb m, DepthGrid<const float> depth, FrameView out, EyeShifts eyes, float D,
                    float convergence, typename Keys::Word *global_keys, uint8_t *mask, SmoothScratch smooth,
                    unsigned long long *total, bool words, int group_rows, int group_blocks, FusedAnaglyph fused) {
  chained_kernel_start();
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
  RowJob<Keys> j;
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
  uint8_t *rgba = reinterpret_cast<uint8_t *>(kSharedKeys ? shared_keys + kEyeArrays * j.W : shared_keys);
  const int source_rows = kBlock == RowBlock::RowsTogether ? group_rows : 1;  // source row buffers
  j.hole_bits[0] = reinterpret_cast<unsigned *>(rgba + 4 * static_cast<size_t>(j.W) * source_rows);
  j.clean_bits[0] = j.hole_bits[0] + kEyeArrays * j.chunks;
  j.keys[1] = j.keys[0] + (kBothEyes ? j.W : 0);
  j.hole_bits[1] = j.hole_bits[0] + (kBothEyes ? j.chunks : 0);
  j.clean_bits[1] = j.clean_bits[0] + (kBothEyes ? j.chunks : 0);
  j.mask = mask;
  j.smooth = smooth;
  j.total = total;
  j.words = words;
  j.row.format = PixelFormat::RGBA;
  j.row.width = j.W;
  j.row.height = 1;
  j.row.plane[0] = rgba;
  j.row.stride[0] = 4 * j.W;

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

// One Jacobi step of NeighborAverage over both eyes: reads mask_in and the
// colours of pixels that mask_in says are filled (never written in this
// step), writes the new mask for every pixel.
__global__ void neighbour_average_kernel(FrameView out, int W, int H, const uint8_t *mask_in, uint8_t *mask_out,
                                         unsigned *filled) {
  chained_kernel_start();
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int eye = blockIdx.z;
  bool done = false;
  if (x < W && y < H) {
    const size_t plane = static_cast<size_t>(W) * H;
    const size_t i = eye * plane + static_cast<size_t>(y) * W + x;
    uint8_t still = 0;
    if (mask_in[i]) {
      Rgba c;
      if (neighbour_average(out, eye * W, mask_in + eye * plane, W, W, H, x, y, &c)) {
        store_rgba(out, eye * W + x, y, c);
        done = true;
      } else {
        still = 1;
      }
    }
    mask_out[i] = still;
  }
  const unsigned ballot = __ballot_sync(kFullMask, done);  // every lane gets here
  if ((threadIdx.x & 31) == 0 && ballot != 0) atomicAdd(filled, static_cast<unsigned>(__popc(ballot)));
}

// Column and row sums in one kernel: a block takes a tile of one eye,
// kSmoothTileW columns x S rows. It computes V of the tile's rows for the
// tile's columns and Rx more on either side into shared memory (sliding
// the +-R window down segments of kSmoothSub rows, as smooth_column_sums
// does on the CPU), then every hole of the tile sums V along its row run.
// The walks are serial, so they read a copy of the states and anchors of
// rows y0 - R .. y0 + S + R - 1 in shared memory when it fits (global
// memory otherwise: very wide windows only); a tile without a hole returns
// at once.
constexpr int kSmoothTileW = 32, kSmoothSub = 8, kSmoothTileThreads = 256, kSmoothTileRowsMax = 32;
// A tile's block has kSmoothTileThreads threads, or kSmoothTileThreadsMax
// where an SM holds as many tiles of that size (smooth_tile_threads).
constexpr int kSmoothTileThreadsMax = 512;
constexpr int kSmoothCopyBatch = 4;  // pixels a thread copies at once (smooth_tile)
constexpr int kSmoothTilesPerBlock = 8;  // the sums kernel's grid (smooth_tile_kernel)
// Windows of at most this many rows up and down take tiles of 16 rows (plan_smooth).
constexpr int kSmoothShortR = 32;
static_assert(kSmoothTileW == 32, "a tile's columns are one chunk of the row kernel's chunk flags");
static_assert(kSmoothTileThreads % 32 == 0 && kSmoothTileThreadsMax % 32 == 0,
              "whole warps: the row kernel's chunk loops and the copies");
__host__ __device__ size_t align16(size_t n) { return (n + 15) & ~static_cast<size_t>(15); }
__host__ __device__ int smooth_tile_columns(int Rx) { return kSmoothTileW + 2 * Rx; }

// V in shared memory. Wide: SmoothSum (20 bytes). Narrow, when a column
// window holds at most 257 anchors (R <= kSmoothNarrowRMax): each channel
// sum fits 16 bits (255 * 257 = 65535), so V takes 10 bytes, (r | g << 16,
// b | a << 16) and the count, which lets more tiles share an SM.
constexpr int kSmoothNarrowRMax = 128;
static_assert(255 * (2 * kSmoothNarrowRMax + 1) <= 65535, "a narrow V channel fits 16 bits");
template <bool kNarrow>
struct TileSums;
template <>
struct TileSums<false> {
  static constexpr size_t kPixelBytes = sizeof(SmoothSum);
  SmoothSum *v;
  static __host__ __device__ size_t bytes(size_t n) { return align16(n * sizeof(SmoothSum)); }
  __device__ TileSums(unsigned char *smem, size_t) : v(reinterpret_cast<SmoothSum *>(smem)) {}
  __device__ void put(size_t i, const SmoothSum &s) { v[i] = s; }
  __device__ SmoothSum get(size_t i) const { return v[i]; }
};
template <>
struct TileSums<true> {
  static constexpr size_t kPixelBytes = sizeof(uint2) + sizeof(unsigned short);
  uint2 *rgba;
  unsigned short *n;
  static __host__ __device__ size_t bytes(size_t count) { return align16(count * sizeof(uint2)) + align16(count * 2); }
  __device__ TileSums(unsigned char *smem, size_t count)
      : rgba(reinterpret_cast<uint2 *>(smem)),
        n(reinterpret_cast<unsigned short *>(smem + align16(count * sizeof(uint2)))) {}
  __device__ void put(size_t i, const SmoothSum &s) {
    rgba[i] = make_uint2(s.r | (s.g << 16), s.b | (s.a << 16));
    n[i] = static_cast<unsigned short>(s.n);
  }
  __device__ SmoothSum get(size_t i) const {
    const uint2 p = rgba[i];
    return SmoothSum{p.x & 0xffffu, p.x >> 16, p.y & 0xffffu, p.y >> 16, n[i]};
  }
};
__host__ __device__ size_t smooth_tile_v_bytes(bool narrow, int Rx, int S) {
  const size_t count = static_cast<size_t>(smooth_tile_columns(Rx)) * S;
  return narrow ? TileSums<true>::bytes(count) : TileSums<false>::bytes(count);
}
// The staged copy: anchors (Rgba), states (bytes), then the chunk flags of
// its rows (at most 2 + (columns - 1) / 32 chunks a row).
__host__ __device__ size_t smooth_tile_copy_pixels(int R, int Rx, int S) {
  return static_cast<size_t>(smooth_tile_columns(Rx)) * (S + 2 * R);
}
__host__ __device__ size_t smooth_tile_copy_bytes(int R, int Rx, int S) {
  const size_t flag_columns = 2 + (smooth_tile_columns(Rx) - 1) / 32;
  return smooth_tile_copy_pixels(R, Rx, S) * (sizeof(Rgba) + 1) + flag_columns * (S + 2 * R);
}
// One listed tile of one eye (tile column tx = chunk tx, tile row ty):
// every thread of the block calls it. kStaged: the walks read the copy in
// shared memory (a template parameter, so that they compile to
// shared-memory loads, not generic ones).
template <bool kNarrow, bool kStaged>
__device__ void smooth_tile(unsigned char *smem_bytes, const FrameView &out, int W, int H, int R,
                            const SmoothScratch &sc, int eye, int tx, int ty) {
  const int S = sc.tile_rows, Rx = smooth_fill_radius_x(R);
  const int x0 = tx * kSmoothTileW, y0 = ty * S;
  const size_t plane = static_cast<size_t>(W) * H;
  const uint8_t *st_eye = sc.state + eye * plane;
  const Rgba *an_eye = sc.anchor + eye * plane;
  const int chunks = row_chunks(W);
  const uint8_t *ch_eye = sc.chunk_holes + eye * static_cast<size_t>(H) * chunks;

  const int nc = smooth_tile_columns(Rx), cx0 = x0 - Rx;  // V columns cx0 .. cx0 + nc - 1
  TileSums<kNarrow> V(smem_bytes, static_cast<size_t>(nc) * S);  // row r of the tile: r * nc + column - cx0
  const uint8_t *st = st_eye;
  const Rgba *an = an_eye;
  size_t pitch = W;
  int sy0 = 0, sx0 = 0;
  if (kStaged) {
    Rgba *an_copy = reinterpret_cast<Rgba *>(smem_bytes + smooth_tile_v_bytes(kNarrow, Rx, S));
    uint8_t *st_copy = reinterpret_cast<uint8_t *>(an_copy + smooth_tile_copy_pixels(R, Rx, S));
    uint8_t *flags = st_copy + smooth_tile_copy_pixels(R, Rx, S);
    sy0 = max(0, y0 - R);
    sx0 = max(0, cx0);
    const int rows = min(H, y0 + S + R) - sy0, cols = min(W, cx0 + nc) - sx0;
    // The chunk flags of the copied rows, then the states and anchors of
    // the chunks with holes (zeros elsewhere, nothing read; an anchor is
    // loaded with its state and kept where the state names one): holes
    // are sparse, so most of the copy costs no load. The block works
    // through each copy as one flat range, kSmoothCopyBatch pixels a thread
    // at a time whose loads are all issued before any is used: a listed
    // tile's time is mostly these loads' latency, which a warp a row, each
    // row waiting for the last, would serialise (measured:
    // docs/benchmarks.md, Design measurements, "Warp: the smooth fill's
    // sums").
    const int fc0 = sx0 / 32, fcn = (sx0 + cols - 1) / 32 - fc0 + 1;
    for (int i = threadIdx.x; i < rows * fcn; i += blockDim.x) {
      const int r = i / fcn;
      flags[i] = ch_eye[static_cast<size_t>(sy0 + r) * chunks + fc0 + (i - r * fcn)];
    }
    __syncthreads();
    // Pixel i of the range is row i / cols, column i % cols; a thread's
    // pixels are blockDim.x apart, so it steps its row and column by the
    // block's quotient and remainder instead of dividing for each (a
    // division a pixel would be a third of the copy's instructions, which
    // are a third of the kernel's; measured: docs/benchmarks.md, Design
    // measurements, "Warp: the smooth fill's sums").
    const int count = rows * cols, step = static_cast<int>(blockDim.x);
    const int step_rows = step / cols, step_cols = step - step_rows * cols;
    int r = static_cast<int>(threadIdx.x) / cols, c = static_cast<int>(threadIdx.x) - r * cols;
    for (int i0 = threadIdx.x; i0 < count; i0 += kSmoothCopyBatch * step) {
      int at_copy[kSmoothCopyBatch];  // the pixel's place in the copy, -1: none
      uint8_t state[kSmoothCopyBatch];
      Rgba anchor[kSmoothCopyBatch];  // loaded with its state: stale (and dropped) where it has no anchor
#pragma unroll
      for (int k = 0; k < kSmoothCopyBatch; ++k) {
        const bool in = i0 + k * step < count;
        at_copy[k] = in ? r * nc + c : -1;
        state[k] = 0;
        if (in && flags[r * fcn + ((sx0 + c) >> 5) - fc0]) {
          const size_t g = static_cast<size_t>(sy0 + r) * W + sx0 + c;
          state[k] = st_eye[g];
          anchor[k] = an_eye[g];
        }
        r += step_rows;
        c += step_cols;
        if (c >= cols) {
          c -= cols;
          ++r;
        }
      }
#pragma unroll
      for (int k = 0; k < kSmoothCopyBatch; ++k) {
        if (at_copy[k] < 0) continue;
        st_copy[at_copy[k]] = state[k];
        if (state[k] & kStateAnchor) an_copy[at_copy[k]] = anchor[k];
      }
    }
    st = st_copy;
    an = an_copy;
    pitch = nc;
    __syncthreads();
  }
  auto at = [&](int y, int X) { return static_cast<size_t>(y - sy0) * pitch + (X - sx0); };
  // A pixel's state: the row kernel wrote the states of chunks with holes
  // only, so outside the copy a chunk without a flag reads as no hole.
  auto hole_state = [&](int y, int X) -> uint8_t {
    if (kStaged) return st[at(y, X)];
    return ch_eye[static_cast<size_t>(y) * chunks + (X >> 5)] ? st[at(y, X)] : 0;
  };

  const int subs = (S + kSmoothSub - 1) / kSmoothSub;
  for (int item = threadIdx.x; item < nc * subs; item += blockDim.x) {
    const int ci = item % nc, X = cx0 + ci;
    if (X < 0 || X >= W) continue;
    const int ya = y0 + (item / nc) * kSmoothSub, yb = min(min(H, y0 + S), ya + kSmoothSub);
    if (ya >= yb) continue;  // a segment past the picture's last row (its walk would read row H)
    int lo = ya;  // the first row of ya's window: its run's start, at most R rows up
    while (lo > 0 && lo > ya - R && hole_state(lo - 1, X)) --lo;
    int hi = lo - 1;  // the window holds the rows lo..hi of the current run
    SmoothSum s = SmoothSum{0, 0, 0, 0, 0};
    for (int y = ya; y < yb; ++y) {
      if (!hole_state(y, X)) {
        s = SmoothSum{0, 0, 0, 0, 0};
        lo = y + 1;
        hi = y;
        continue;
      }
      while (hi < y + R && hi + 1 < H && hole_state(hi + 1, X)) {
        ++hi;
        if (hole_state(hi, X) & kStateAnchor) smooth_add(s, an[at(hi, X)]);
      }
      while (lo < y - R) {
        if (hole_state(lo, X) & kStateAnchor) {
          const Rgba c = an[at(lo, X)];
          s = smooth_window(s, SmoothSum{c.r, c.g, c.b, c.a, 1u});
        }
        ++lo;
      }
      V.put(static_cast<size_t>(y - y0) * nc + ci, s);
    }
  }
  __syncthreads();

  for (int i = threadIdx.x; i < kSmoothTileW * S; i += blockDim.x) {
    const int X = x0 + i % kSmoothTileW, y = y0 + i / kSmoothTileW;
    if (X >= W || y >= H || !hole_state(y, X)) continue;
    const size_t v0 = static_cast<size_t>(y - y0) * nc - cx0;  // V of column t in row y: v0 + t
    SmoothSum s = V.get(v0 + X);
    for (int t = X - 1; t >= 0 && t >= X - Rx && hole_state(y, t); --t) smooth_add(s, V.get(v0 + t));
    for (int t = X + 1; t < W && t <= X + Rx && hole_state(y, t); ++t) smooth_add(s, V.get(v0 + t));
    store_rgba(out, eye * W + X, y, smooth_mean(s));
  }
}

// The sums kernel: block b sums listed tiles b, b + gridDim.x, ...; the
// grid has a block for every kSmoothTilesPerBlock tiles the frame may list
// (launch_smooth), so a frame whose every tile has a hole (noise depth,
// GpuWarp.AllModesRandomDepth) takes each block through several tiles.
// A 4K frame lists about 900 of its 32400 tiles. A block for every 8
// tiles beats a block for every tile (4 to 16 measure alike; 32 leave a
// 1080p frame's few tiles to too few blocks), and a grid of only as many
// blocks as the GPU holds is slower than either, chained or not: tiles
// differ in cost, and many short-lived blocks balance them better
// (measured: docs/benchmarks.md, Design measurements, "Warp: the smooth
// fill's sums").
// kTight: blocks of kSmoothTileThreads, as many as an SM holds threads for
// (at most 32 registers a thread on Hopper; ptxas: no spills in the
// staged narrow kernel, 12 to 24 bytes in the others), else
// kSmoothTileThreadsMax with no register bound; smooth_tile_threads()
// takes the one that keeps more threads resident.
template <bool kNarrow, bool kStaged, bool kTight>
__global__ void __launch_bounds__(kTight ? kSmoothTileThreads : kSmoothTileThreadsMax,
                                  kTight ? P3D_MAX_THREADS_PER_SM / kSmoothTileThreads : 1)
    smooth_tile_kernel(FrameView out, int W, int H, int2 radius, SmoothScratch sc) {
  chained_kernel_start();
  extern __shared__ unsigned char smem_bytes[];
  const unsigned count = *sc.tile_count;
  for (unsigned i = blockIdx.x; i < count; i += gridDim.x) {  // block-uniform
    if (i != blockIdx.x) __syncthreads();  // the last tile's row sums are done with shared memory
    const unsigned t = sc.tile_list[i];
    const int tx = static_cast<int>(t % sc.tiles_x), rest = static_cast<int>(t / sc.tiles_x);
    const int ty = rest % sc.tiles_y, eye = rest / sc.tiles_y;
    smooth_tile<kNarrow, kStaged>(smem_bytes, out, W, H, eye == 0 ? radius.x : radius.y, sc, eye, tx, ty);
  }
}

// The fused anaglyph's pixels that the row kernel left in the pair (pair:
// render_packed's scratch, 2W x H, both eyes' colours final): the holes of
// the listed tiles, either eye's (the sums kernel has filled them, and the
// other eye's colour is in the pair, written by the row kernel or filled
// too), then every pixel of the rows from tail_y0 on, whose blocks render
// one eye each. A pixel that both eyes' tiles (or a tile and its tail row)
// hold is written twice with the same bytes.
// Its time is load latency (the tile count, the list, the states, the
// pair): the work is kPatchPerThread pixels of one row an item (a quarter
// of a tile's row, or of a tail row), every item of the frame shared out
// over one wave of resident threads, each issuing the loads of all its
// pixels before it uses any, which beats a block a listed tile plus a
// block a tail row, and two waves of blocks a tile or a quarter of a tail
// row (measured: docs/benchmarks.md, Design measurements, "Fused pack").
constexpr int kPatchThreads = 256, kPatchPerThread = 4;
static_assert(kSmoothTileW % kPatchPerThread == 0, "a tile row is whole items");

__device__ uint32_t pair_word(const FrameView &pair, int col, int y) {
  const uint32_t w = reinterpret_cast<const uint32_t *>(pair.plane[0] + static_cast<size_t>(y) * pair.stride[0])[col];
  return is_bgr_order(pair.format) ? swap_rb_word(w) : w;  // store_rgba()'s bytes back in rgba_word order
}

__global__ void fused_anaglyph_patch_kernel(FrameView pair, FusedAnaglyph f, SmoothScratch sc, int tail_y0) {
  chained_kernel_start();
  const int W = pair.width / 2, H = pair.height, chunks = row_chunks(W);
  constexpr int kItemsARow = kSmoothTileW / kPatchPerThread;
  // 32-bit counts (a 64-bit division costs more than the rest of an item):
  // at most 2 x 256 x 8192 tile rows of 8 items (all listed at 8K), and
  // 8192 rows of 2048.
  const unsigned per_tile = static_cast<unsigned>(sc.tile_rows) * kItemsARow;
  const unsigned tile_items = *sc.tile_count * per_tile;
  const unsigned tail_row_items = static_cast<unsigned>(W + kPatchPerThread - 1) / kPatchPerThread;
  const unsigned items = tile_items + static_cast<unsigned>(H - tail_y0) * tail_row_items;
  const bool pair_alpha = has_alpha(pair.format);
  for (unsigned item = blockIdx.x * blockDim.x + threadIdx.x; item < items; item += gridDim.x * blockDim.x) {
    int x0, y;
    bool mix[kPatchPerThread];
    if (item < tile_items) {
      const int k = static_cast<int>(item % per_tile);
      const unsigned t = sc.tile_list[item / per_tile];
      const int tx = static_cast<int>(t % sc.tiles_x), rest = static_cast<int>(t / sc.tiles_x);
      const int ty = rest % sc.tiles_y, eye = rest / sc.tiles_y;
      y = ty * sc.tile_rows + k / kItemsARow;
      x0 = tx * kSmoothTileW + (k % kItemsARow) * kPatchPerThread;
      // The row kernel writes states only in chunks with holes; the others
      // hold a past frame's (initialised) bytes, loaded with the flag and
      // dropped.
      const bool in_rows = y < H;
      const size_t eye_row = static_cast<size_t>(eye) * H + (in_rows ? y : 0);  // of the eyes' planes' rows
      const bool flag = in_rows && sc.chunk_holes[eye_row * chunks + tx];
      uint8_t state[kPatchPerThread];
#pragma unroll
      for (int i = 0; i < kPatchPerThread; ++i) state[i] = x0 + i < W ? sc.state[eye_row * W + x0 + i] : 0;
#pragma unroll
      for (int i = 0; i < kPatchPerThread; ++i) mix[i] = flag && (state[i] & kStateHole);
    } else {
      const unsigned k = item - tile_items;
      y = tail_y0 + static_cast<int>(k / tail_row_items);
      x0 = static_cast<int>(k % tail_row_items) * kPatchPerThread;
#pragma unroll
      for (int i = 0; i < kPatchPerThread; ++i) mix[i] = x0 + i < W;
    }
    uint32_t w[kPatchPerThread][2];
#pragma unroll
    for (int i = 0; i < kPatchPerThread; ++i)
      if (mix[i]) {
        w[i][0] = pair_word(pair, x0 + i, y);
        w[i][1] = pair_word(pair, W + x0 + i, y);
      }
#pragma unroll
    for (int i = 0; i < kPatchPerThread; ++i)
      if (mix[i]) store_aligned_word(f.out, x0 + i, y, fused_anaglyph_word(f, w[i][0], w[i][1], pair_alpha));
  }
}

__global__ void paint_holes_kernel(FrameView out, int W, int H, const uint8_t *mask) {
  chained_kernel_start();
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int eye = blockIdx.z;
  if (x >= W || y >= H) return;
  if (mask[(static_cast<size_t>(eye) * H + y) * W + x]) store_rgba(out, eye * W + x, y, kFillBlack);
}

dim3 pixel_grid(int W, int H) { return dim3((W + kBlockX - 1) / kBlockX, (H + kBlockY - 1) / kBlockY, 2); }

// Lets `kernel` take as much dynamic shared memory as the device allows a
// block beside the kernel's static shared memory (past 48 KiB only by
// opting in), and asks for the largest carveout, so that as many blocks
// share an SM as their shared memory allows. Always the most, not a
// frame's size: the limit belongs to the kernel, shared by every renderer
// in the process, so a renderer that set a smaller one for its smaller
// rows would make another's launch fail; and the default 48 KiB count the
// static bytes too (a row of 5956 pixels with 32-bit keys takes 49144
// dynamic bytes, past it with the row kernel's 16 static ones). `done`
// lists the kernels this renderer has set up, so no frame after the first
// makes a call (a renderer serves one device).
CudaStatus allow_shared_memory(const void *kernel, int smem_optin, std::vector<const void *> *done) {
  for (const void *k : *done)
    if (k == kernel) return {};
  cudaFuncAttributes a{};
  P3D_CUDA_TRY(cudaFuncGetAttributes(&a, kernel));
  P3D_CUDA_TRY(cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                    smem_optin - static_cast<int>(a.sharedSizeBytes)));
  P3D_CUDA_TRY(cudaFuncSetAttribute(kernel, cudaFuncAttributePreferredSharedMemoryCarveout,
                                    static_cast<int>(cudaSharedmemCarveoutMaxShared)));
  done->push_back(kernel);
  return {};
}

// The z-buffer a frame's row kernel uses: NarrowKeys in shared memory where
// every hit is near its target (warp_narrow_keys_fit) and the row fits,
// else WideKeys in shared memory, else WideKeys in global memory (rows of
// about 19000 pixels and more on Hopper).
// NarrowSharedPerEye: NarrowKeys in shared memory, a z-buffer for each
// eye, both eyes rendered at once (both warped, and the second z-buffer
// costs no resident thread: choose_row_kernels).
enum class KeyPlace { NarrowSharedPerEye, NarrowShared, WideShared, WideGlobal };

struct RowLaunch {
  FrameView src;
  YuvToRgb m;
  DepthGrid<const float> depth;
  FrameView out;
  EyeShifts eyes;
  float D, convergence;
  HoleFill fill;
  KeyPlace keys;
  unsigned long long *global_keys;
  uint8_t *mask;
  SmoothScratch smooth;
  unsigned long long *total;
  bool words;
  size_t smem;
  cudaStream_t stream;
  int smem_optin;
  std::vector<const void *> *attributes_set;
  int group_rows;  // rows a block (NarrowSharedPerEye only; 1: a row's block)
  int tail_y0;     // row groups: from this row on, a block a row or eye (group_tail_y0)
  bool wide_groups;  // groups in WideGroup blocks, of wide_group_threads
  bool rows_together;  // groups in RowsTogether blocks, of wide_group_threads
  int wide_group_threads;
  FusedAnaglyph fused;  // out.plane[0] null: not fused
};

// The row kernel of a key word, key place, eye order, block kind and fill;
// kFused: with the pack fused (BackgroundSmooth only, else null).
template <class Keys, bool kSharedKeys, bool kBothEyes, RowBlock kBlock, bool kFused = false>
auto row_kernel_for(HoleFill fill)
    -> decltype(&warp_row_kernel<Keys, kSharedKeys, HoleFill::BackgroundSmooth, kBothEyes, kBlock, kFused>) {
  if constexpr (kFused) {
    return fill == HoleFill::BackgroundSmooth
               ? warp_row_kernel<Keys, kSharedKeys, HoleFill::BackgroundSmooth, kBothEyes, kBlock, true>
               : nullptr;
  } else {
    switch (fill) {
      case HoleFill::Background:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::Background, kBothEyes, kBlock, false>;
      case HoleFill::NeighborAverage:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::NeighborAverage, kBothEyes, kBlock, false>;
      case HoleFill::None:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::None, kBothEyes, kBlock, false>;
      case HoleFill::BackgroundSmooth:
        return warp_row_kernel<Keys, kSharedKeys, HoleFill::BackgroundSmooth, kBothEyes, kBlock, false>;
    }
    return nullptr;
  }
}

int row_threads(int W) { return W > 1024 ? kRowThreadsMax : 256; }

template <class Keys, bool kSharedKeys, bool kBothEyes, RowBlock kBlock, bool kFused = false>
CudaStatus launch_rows(const RowLaunch &l) {
  const auto row_kernel = row_kernel_for<Keys, kSharedKeys, kBothEyes, kBlock, kFused>(l.fill);
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
                              l.total, l.words, rows, group_blocks, l.fused));
  return {};
}

// The row kernel for the run's key place, row groups and fill.
CudaStatus launch_row_kernel(const RowLaunch &l) {
  switch (l.keys) {
    case KeyPlace::NarrowSharedPerEye:
      if (l.group_rows == 1) return launch_rows<NarrowKeys, true, true, RowBlock::Row>(l);
      if (l.rows_together)
        return l.fused.out.plane[0] ? launch_rows<NarrowKeys, true, true, RowBlock::RowsTogether, true>(l)
                                    : launch_rows<NarrowKeys, true, true, RowBlock::RowsTogether>(l);
      return l.wide_groups ? launch_rows<NarrowKeys, true, true, RowBlock::WideGroup>(l)
                           : launch_rows<NarrowKeys, true, true, RowBlock::Group>(l);
    case KeyPlace::NarrowShared:
      return launch_rows<NarrowKeys, true, false, RowBlock::Row>(l);
    case KeyPlace::WideShared:
      return launch_rows<WideKeys, true, false, RowBlock::Row>(l);
    case KeyPlace::WideGlobal:
      return launch_rows<WideKeys, false, false, RowBlock::Row>(l);
  }
  return CudaStatus{cudaErrorInvalidValue, "KeyPlace", __FILE__, __LINE__};
}

// Shared memory of a RowsTogether block of `rows` rows: a row's with both
// z-buffers, and a source row more for each further row.
size_t together_smem_bytes(int W, int rows) {
  return row_smem_bytes(W, sizeof(NarrowKeys::Word), 2) + 4 * static_cast<size_t>(W) * (rows - 1);
}

// Threads an SM holds resident of a kernel with blocks of `threads` and
// `smem` bytes of dynamic shared memory (attributes set beforehand).
CudaStatus resident_threads(const void *kernel, int threads, size_t smem, int *resident) {
  int blocks = 0;
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&blocks, kernel, threads, smem));
  *resident = blocks * threads;
  return {};
}

// Which row kernels serve rows of W pixels with both eyes warped and
// NarrowKeys, by the threads each keeps resident on an SM (this kernel is
// bound by instructions, so every resident thread counts):
//  * both eyes at once where that holds as many threads as the eyes in
//    turn: the second z-buffer costs 4 W bytes of shared memory, which
//    from about 4600 pixels (Hopper) leaves room for one row fewer;
//  * row groups, for depth on cells of 2 x 2 pixels and more: one scatter
//    serves the group's rows (render_row_group), so a block of G rows
//    does the scatter's work once where G rows' blocks did it G times.
//    RowsTogether blocks where they hold as many threads as the row
//    kernel chosen above (a source row each for up to 4 rows: 92 KB a
//    block at 4K), else Group blocks where those do, else WideGroup
//    blocks. At 4K, where all three hold 2048 threads an SM on Hopper,
//    RowsTogether blocks are the fastest, then Group, then WideGroup
//    (measured: docs/benchmarks.md, Design measurements, "Warp: row
//    groups").
CudaStatus choose_row_kernels(HoleFill fill, int W, int smem_optin, std::vector<const void *> *attributes_set,
                              RowKernelChoice *choice) {
  RowKernelChoice c;  // *choice is replaced only once every query succeeded
  c.width = W;
  c.fill = fill;
  const size_t smem_both = row_smem_bytes(W, sizeof(NarrowKeys::Word), 2);
  if (smem_both + 64 > static_cast<size_t>(smem_optin)) {
    *choice = c;
    return {};
  }
  const auto in_turn = row_kernel_for<NarrowKeys, true, false, RowBlock::Row>(fill);
  const auto both = row_kernel_for<NarrowKeys, true, true, RowBlock::Row>(fill);
  const auto group = row_kernel_for<NarrowKeys, true, true, RowBlock::Group>(fill);
  const auto wide = row_kernel_for<NarrowKeys, true, true, RowBlock::WideGroup>(fill);
  const auto together = row_kernel_for<NarrowKeys, true, true, RowBlock::RowsTogether>(fill);
  if (!in_turn || !both || !group || !wide || !together)
    return CudaStatus{cudaErrorInvalidValue, "WarpParams::fill is a HoleFill", __FILE__, __LINE__};
  for (const void *k : {reinterpret_cast<const void *>(in_turn), reinterpret_cast<const void *>(both),
                        reinterpret_cast<const void *>(group), reinterpret_cast<const void *>(wide),
                        reinterpret_cast<const void *>(together)})
    P3D_CUDA_TRY_STATUS(allow_shared_memory(k, smem_optin, attributes_set));
  int in_turn_threads = 0, both_threads = 0, group_threads = 0, wide_threads = 0, together_threads = 0;
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(in_turn), row_threads(W),
                                       row_smem_bytes(W, sizeof(NarrowKeys::Word), 1), &in_turn_threads));
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(both), row_threads(W), smem_both, &both_threads));
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(group), row_threads(W), smem_both, &group_threads));
  // A wide block's size is its kernel's launch bound on this device's
  // architecture (kWideGroupThreads of the machine code it runs).
  cudaFuncAttributes wide_attr{}, together_attr{};
  P3D_CUDA_TRY(cudaFuncGetAttributes(&wide_attr, reinterpret_cast<const void *>(wide)));
  P3D_CUDA_TRY(cudaFuncGetAttributes(&together_attr, reinterpret_cast<const void *>(together)));
  P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(wide), wide_attr.maxThreadsPerBlock, smem_both,
                                       &wide_threads));
  const size_t smem_together = together_smem_bytes(W, 1 << kGroupShiftMax);
  if (smem_together + 64 <= static_cast<size_t>(smem_optin))
    P3D_CUDA_TRY_STATUS(resident_threads(reinterpret_cast<const void *>(together), together_attr.maxThreadsPerBlock,
                                         smem_together, &together_threads));
  int dev = 0, sms = 0;
  P3D_CUDA_TRY(cudaGetDevice(&dev));
  P3D_CUDA_TRY(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
  c.both_eyes = both_threads >= in_turn_threads;
  const int row_best = c.both_eyes ? both_threads : in_turn_threads;
  if (together_threads > 0 && together_threads >= row_best) {
    c.groups = c.rows_together = true;
    c.wide_group_threads = together_attr.maxThreadsPerBlock;
    c.group_slots = sms * (together_threads / together_attr.maxThreadsPerBlock);
  } else if (group_threads > 0 && group_threads >= row_best) {
    c.groups = true;
    c.group_slots = sms * (group_threads / row_threads(W));
  } else if (wide_threads > 0 && wide_threads >= row_best) {
    c.groups = c.wide_groups = true;
    c.wide_group_threads = wide_attr.maxThreadsPerBlock;
    c.group_slots = sms * (wide_threads / wide_attr.maxThreadsPerBlock);
  }
  *choice = c;
  return {};
}

// BackgroundSmooth's sums for a frame: the eyes' radii, the tile rows, and
// the sums kernel's shared memory.
struct SmoothPlan {
  int2 radius;  // R of each eye
  bool narrow, staged;
  int tile_rows, tiles_x, tiles_y;
  size_t smem;
  size_t tiles() const { return 2 * static_cast<size_t>(tiles_x) * tiles_y; }
};

SmoothPlan plan_smooth(const EyeShifts &eyes, float D, int W, int H, int smem_optin) {
  SmoothPlan p;
  const int R0 = smooth_fill_radius(eyes.shift[0], D), R1 = smooth_fill_radius(eyes.shift[1], D);
  const int Rmax = max(eyes.shift[0] == 0.f ? 0 : R0, eyes.shift[1] == 0.f ? 0 : R1), Rx = smooth_fill_radius_x(Rmax);
  p.radius = make_int2(R0, R1);
  p.narrow = Rmax <= kSmoothNarrowRMax;
  // Tile rows: 16 for windows of up to kSmoothShortR rows, else
  // kSmoothTileRowsMax; fewer when V would pass 64 KB (wide Rx). A listed
  // tile sums all its rows and copies 2R more, and holes are sparse: short
  // tiles do less work on rows without holes, tall ones copy the 2R rows
  // fewer times: 16 rows win at R = 15 and 29 (1080p, 4K), 32 at R = 58
  // (8K) (measured: docs/benchmarks.md, Design measurements, "Warp: the
  // smooth fill's sums").
  const size_t v_pixel = p.narrow ? TileSums<true>::kPixelBytes : TileSums<false>::kPixelBytes;
  const int rows = Rmax <= kSmoothShortR ? 16 : kSmoothTileRowsMax;
  const int S = max(1, min(rows, static_cast<int>(65536 / (smooth_tile_columns(Rx) * v_pixel))));
  p.tile_rows = S;
  p.tiles_x = (W + kSmoothTileW - 1) / kSmoothTileW;
  p.tiles_y = (H + S - 1) / S;
  p.smem = smooth_tile_v_bytes(p.narrow, Rx, S);
  p.staged = p.smem + smooth_tile_copy_bytes(Rmax, Rx, S) + 64 <= static_cast<size_t>(smem_optin);
  if (p.staged) p.smem += smooth_tile_copy_bytes(Rmax, Rx, S);
  return p;
}

// The sums kernel's block size for a kernel and its shared memory:
// kSmoothTileThreadsMax where an SM holds as many tiles of that size as of
// kSmoothTileThreads, else kSmoothTileThreads. A tile's copy, walks and
// row sums all share its threads out, so more threads finish a tile
// sooner; but where registers, not shared memory, bound the tiles an SM
// holds, twice the threads hold half the tiles, and a frame's tiles take
// more waves: 512 threads pay at 8K (3 tiles an SM either way: 64 KB of
// shared memory a tile), not at 4K (6 tiles an SM with 256, 3 with 512);
// 1080p's tiles are bound by registers as at 4K, so the rule keeps 256
// there (measured: docs/benchmarks.md, Design measurements, "Warp: the
// smooth fill's sums"). Each of these kernels has a twin bound to
// kSmoothTileThreads threads and as many blocks as an SM holds threads
// for (32 registers a thread on Hopper, so 8 tiles an SM at 4K instead of
// 6); the twin runs where it keeps more threads resident, which it does
// where registers, not shared memory, bound the tiles: 4K and 1080p, not
// 8K. A 4K frame lists about a thousand tiles, which 8 tiles an SM take
// in one wave; 1080p's few hundred tiles fit either way, and gain nothing
// (measured: docs/benchmarks.md, Design measurements, "Warp: the smooth
// fill's sums").
CudaStatus smooth_tile_threads(const void *loose, const void *tight, size_t smem, SmoothSumsLaunch *cache) {
  if (cache->kernel == loose && cache->smem == smem) return {};
  int tiles = 0, tiles_max = 0, tiles_tight = 0;
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&tiles, loose, kSmoothTileThreads, smem));
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&tiles_max, loose, kSmoothTileThreadsMax, smem));
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&tiles_tight, tight, kSmoothTileThreads, smem));
  const int threads = tiles_max >= tiles ? kSmoothTileThreadsMax : kSmoothTileThreads;
  const bool use_tight = tiles_tight * kSmoothTileThreads > (tiles_max >= tiles ? tiles_max : tiles) * threads;
  cache->kernel = loose;
  cache->smem = smem;
  cache->launch = use_tight ? tight : loose;
  cache->threads = use_tight ? kSmoothTileThreads : threads;
  return {};
}

// The sums kernel of a plan's V width and staging, with or without the
// register bound (kTight).
template <bool kTight>
auto smooth_kernel_for(const SmoothPlan &plan) -> decltype(&smooth_tile_kernel<true, true, kTight>) {
  return plan.narrow ? (plan.staged ? smooth_tile_kernel<true, true, kTight> : smooth_tile_kernel<true, false, kTight>)
                     : (plan.staged ? smooth_tile_kernel<false, true, kTight> : smooth_tile_kernel<false, false, kTight>);
}

// BackgroundSmooth sums, after the row kernel wrote the states and anchors
// and listed the tiles with holes: one smooth_tile_kernel, a block for every
// kSmoothTilesPerBlock tiles the list may hold (the host does not read the
// count). No host sync.
CudaStatus launch_smooth(const SmoothPlan &plan, const SmoothScratch &sc, const FrameView &out, int W, int H,
                         cudaStream_t stream, int smem_optin, std::vector<const void *> *attributes_set,
                         SmoothSumsLaunch *threads_cache) {
  using Kernel = decltype(&smooth_tile_kernel<true, true, false>);
  const Kernel loose = smooth_kernel_for<false>(plan), tight = smooth_kernel_for<true>(plan);
  P3D_CUDA_TRY_STATUS(allow_shared_memory(reinterpret_cast<const void *>(loose), smem_optin, attributes_set));
  P3D_CUDA_TRY_STATUS(allow_shared_memory(reinterpret_cast<const void *>(tight), smem_optin, attributes_set));
  P3D_CUDA_TRY_STATUS(smooth_tile_threads(reinterpret_cast<const void *>(loose), reinterpret_cast<const void *>(tight),
                                          plan.smem, threads_cache));
  const Kernel kernel = reinterpret_cast<Kernel>(const_cast<void *>(threads_cache->launch));
  // Chained (cuda/chained_launch.cuh): its blocks start while the row
  // kernel's last ones run. That gains with a block for every
  // kSmoothTilesPerBlock tiles; with a block for every tile (32400 at 4K),
  // mostly returning at once, it would cost more than it gains (measured:
  // docs/benchmarks.md, Design measurements, "Warp: the smooth fill's
  // sums" and "Chained launches").
  const unsigned blocks = static_cast<unsigned>((plan.tiles() + kSmoothTilesPerBlock - 1) / kSmoothTilesPerBlock);
  P3D_CUDA_TRY(launch_chained(kernel, blocks, threads_cache->threads, plan.smem, stream, out, W, H, plan.radius, sc));
  return {};
}

// Where row groups give way to blocks of one row (of one eye of one row in
// RowsTogether kernels): after the last group that a whole wave of `slots`
// blocks (as many as the device holds resident) takes. Blocks start in
// index order, so the groups go first; the rows left over, too few groups
// to fill a wave, then take a block a row or eye, which spreads them over
// more SMs in shorter blocks. A frame with fewer groups than slots, or a
// whole number of waves, has no tail: the height rounded up to whole
// groups.
// For example, at 4K 540 groups of 4 rows meet 264 RowsTogether slots on
// a Hopper card of 132 SMs: without the tail, 12 groups would run alone
// after two full waves (measured: docs/benchmarks.md, Design
// measurements, "Warp: row groups").
int group_tail_y0(int H, int group_rows, int slots) {
  const int groups = (H + group_rows - 1) / group_rows;
  if (group_rows <= 1 || slots <= 0 || groups <= slots || groups % slots == 0) return groups * group_rows;
  return (groups / slots) * slots * group_rows;
}

CudaStatus invalid_frames() {
  return CudaStatus{cudaErrorInvalidValue, "warp_frames_fit(src, depth, out)", __FILE__, __LINE__};
}

}  // namespace

CudaStatus WarpRendererGpu::render(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                                   ImageView<const float> depth, const FrameView &out, cudaStream_t stream,
                                   long long *holes_out) {
  return render(params, src, m, full_grid(depth), out, stream, holes_out);
}

CudaStatus WarpRendererGpu::render(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                                   DepthGrid<const float> depth, const FrameView &out, cudaStream_t stream,
                                   long long *holes_out) {
  return render_pair(params, src, m, depth, out, nullptr, stream, holes_out, nullptr);
}

CudaStatus WarpRendererGpu::render_packed(const WarpParams &params, const PackParams &pack, const FrameView &src,
                                          const YuvToRgb &m, DepthGrid<const float> depth, const FrameView &out,
                                          cudaStream_t stream, bool *fused_out) {
  if (fused_out) *fused_out = false;
  PackParams pp = pack;
  pp.input = StereoInput::SideBySide;
  pp.input_right_first = false;
  // The pair in the output's packed format (pack's input and output share
  // one), or RGBA for a 4:2:0 output.
  const PixelFormat pair_format = is_packed_rgb(out.format) ? out.format : PixelFormat::RGBA;
  if (pack_is_identity(pp) && out.format == pair_format) return render(params, src, m, depth, out, stream);
  if (src.width <= 0 || src.height <= 0 || src.width > kMaxFrameSide || src.height > kMaxFrameSide)
    return invalid_frames();
  const int W = src.width, H = src.height;
  P3D_CUDA_TRY_STATUS(pair_.ensure(8 * static_cast<size_t>(W) * H));
  FrameView pair{};
  pair.format = pair_format;
  pair.width = 2 * W;
  pair.height = H;
  pair.plane[0] = pair_.as<uint8_t>();
  pair.stride[0] = 8 * W;
  if (!pack_args_valid(pp, pair, out))
    return CudaStatus{cudaErrorInvalidValue, "render_packed: pack_args_valid(pack, pair, out)", __FILE__, __LINE__};
  // The gamma mixes fuse (dubois-linear mixes in linear light, in float).
  FusedAnaglyph fused{};
  const bool fusable = pp.layout == PackLayout::Anaglyph && pp.method != AnaglyphMethod::DuboisLinear &&
                       out.format == pair_format && rows_aligned(out, 0, 4);
  if (fusable) {
    const AnaglyphMatrices am = anaglyph_matrices(pp.glasses, pp.method);
    fused.out = out;
    for (int k = 0; k < 9; ++k) {
      fused.left[k] = am.left_q[k];
      fused.right[k] = am.right_q[k];
    }
    fused.swap = pp.swap_eyes;
  }
  bool used = false;
  P3D_CUDA_TRY_STATUS(render_pair(params, src, m, depth, pair, fusable ? &fused : nullptr, stream, nullptr, &used));
  if (fused_out) *fused_out = used;
  if (used) return {};
  return pack_gpu(pp, pair, out, stream);
}

CudaStatus WarpRendererGpu::render_pair(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                                        DepthGrid<const float> depth, const FrameView &out,
                                        const FusedAnaglyph *fused_request, cudaStream_t stream, long long *holes_out,
                                        bool *fused_used) {
  if (!warp_frames_fit(src, depth, out)) return invalid_frames();
  const WarpParams p = warp_sanitize(params);
  const int W = src.width, H = src.height;
  const float D = disparity_scale(p, W);
  const EyeShifts eyes{{warp_eye_shift(p, D, 0), warp_eye_shift(p, D, 1)}};
  const bool average = p.fill == HoleFill::NeighborAverage;
  const bool smooth = p.fill == HoleFill::BackgroundSmooth;

  if (smem_optin_ < 0) {
    int dev = 0;
    P3D_CUDA_TRY(cudaGetDevice(&dev));
    P3D_CUDA_TRY(cudaDeviceGetAttribute(&smem_optin_, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev));
  }
  // 64 bytes: room for the kernel's static __shared__ counter.
  auto fits = [&](size_t key_bytes) {
    return row_smem_bytes(W, key_bytes, 1) + 64 <= static_cast<size_t>(smem_optin_);
  };
  const bool narrow = warp_narrow_keys_fit(eyes.shift[0], eyes.shift[1], D, p.convergence) &&
                      fits(sizeof(NarrowKeys::Word));
  const bool wide_shared = !narrow && fits(sizeof(WideKeys::Word));
  if (!fits(0))  // rows wider than ~50000 pixels on Hopper
    return CudaStatus{cudaErrorInvalidValue, "row_smem_bytes(W) <= cudaDevAttrMaxSharedMemoryPerBlockOptin", __FILE__,
                      __LINE__};
  bool per_eye = false;
  int group_rows = 1;
  if (narrow && eyes.shift[0] != 0.f && eyes.shift[1] != 0.f) {
    if (rows_.width != W || rows_.fill != p.fill)
      P3D_CUDA_TRY_STATUS(choose_row_kernels(p.fill, W, smem_optin_, &attributes_set_, &rows_));
    if (rows_.groups && depth.shift > 0) group_rows = 1 << (depth.shift < kGroupShiftMax ? depth.shift : kGroupShiftMax);
    per_eye = rows_.both_eyes || group_rows > 1;
  }
  const KeyPlace keys = per_eye  ? KeyPlace::NarrowSharedPerEye
                        : narrow ? KeyPlace::NarrowShared
                        : wide_shared ? KeyPlace::WideShared
                                      : KeyPlace::WideGlobal;
  const bool rows_together = group_rows > 1 && rows_.rows_together;
  const size_t smem = rows_together ? together_smem_bytes(W, group_rows)
                                    : row_smem_bytes(W, narrow ? sizeof(NarrowKeys::Word)
                                                               : wide_shared ? sizeof(WideKeys::Word) : 0,
                                                     per_eye ? 2 : 1);
  if (keys == KeyPlace::WideGlobal)
    P3D_CUDA_TRY_STATUS(keys_.ensure(static_cast<size_t>(W) * H * sizeof(WideKeys::Word)));
  if (average) P3D_CUDA_TRY_STATUS(scratch_.ensure(2 * 2 * static_cast<size_t>(W) * H));  // two masks, both eyes
  const size_t plane = 2 * static_cast<size_t>(W) * H;                                      // both eyes
  const size_t chunk_flags = 2 * static_cast<size_t>(H) * row_chunks(W);  // both eyes
  const SmoothPlan plan = smooth ? plan_smooth(eyes, D, W, H, smem_optin_) : SmoothPlan{};
  const size_t list_offset = align16(plane * kSmoothBytesPerPixel + chunk_flags);  // the tile list's words
  if (smooth) {
    const size_t had = smooth_.size();
    P3D_CUDA_TRY_STATUS(smooth_.ensure(list_offset + sizeof(unsigned) * plan.tiles()));
    // Cleared once a (re)allocation: the sums kernel's copy loads every
    // anchor of a chunk with holes beside its state and drops those whose
    // state names none, so no byte it loads may be uninitialised memory
    // (compute-sanitizer initcheck), though no such value is ever used.
    if (smooth_.size() != had) P3D_CUDA_TRY(zero_chained(smooth_.get(), smooth_.size(), stream));
  }
  const size_t counter_bytes = kTileMarksOffset + sizeof(unsigned) * plan.tiles();
  P3D_CUDA_TRY_STATUS(counters_.ensure(counter_bytes));
  uint8_t *counters = counters_.as<uint8_t>();
  auto *total = reinterpret_cast<unsigned long long *>(counters + kTotalOffset);
  P3D_CUDA_TRY(zero_chained(counters, counter_bytes, stream));

  uint8_t *mask = average ? scratch_.as<uint8_t>() : nullptr;
  // BackgroundSmooth scratch, both eyes each: anchors, states, chunk flags,
  // then the tile list; the tile marks and counts are in counters_.
  SmoothScratch sc{};
  if (smooth) {
    sc.anchor = smooth_.as<Rgba>();
    sc.state = reinterpret_cast<uint8_t *>(sc.anchor + plane);
    sc.chunk_holes = sc.state + plane;
    sc.tile_list = reinterpret_cast<unsigned *>(smooth_.as<uint8_t>() + list_offset);
    sc.tile_mark = reinterpret_cast<unsigned *>(counters + kTileMarksOffset);
    sc.tile_count = reinterpret_cast<unsigned *>(counters + kTileCountOffset);
    sc.tile_rows = plan.tile_rows;
    sc.tiles_x = plan.tiles_x;
    sc.tiles_y = plan.tiles_y;
  }
  const bool words = rows_aligned(out, 0, 4);
  // The pack fused where the rows are resolved together (both eyes of a
  // target at hand) and the sums kernel fills the holes.
  const bool fuse = fused_request && rows_together && smooth && words;
  const int tail_y0 = group_tail_y0(H, group_rows, rows_.group_slots);
  const RowLaunch launch{src, m, depth, out, eyes, D, p.convergence, p.fill,
                         keys, keys_.as<WideKeys::Word>(), mask, sc, total, words, smem, stream, smem_optin_,
                         &attributes_set_, group_rows, tail_y0, rows_.wide_groups, rows_together,
                         rows_.wide_group_threads, fuse ? *fused_request : FusedAnaglyph{}};
  P3D_CUDA_TRY_STATUS(launch_row_kernel(launch));
  if (average) P3D_CUDA_TRY_STATUS(neighbour_average(out, W, H, stream));
  if (smooth)
    P3D_CUDA_TRY_STATUS(launch_smooth(plan, sc, out, W, H, stream, smem_optin_, &attributes_set_, &sums_launch_));
  if (fuse) {  // one wave of resident blocks, or fewer if the frame could not fill them
    if (resident_patch_blocks_ < 0) {
      int dev = 0, sms = 0, threads = 0;
      P3D_CUDA_TRY(cudaGetDevice(&dev));
      P3D_CUDA_TRY(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
      P3D_CUDA_TRY(cudaDeviceGetAttribute(&threads, cudaDevAttrMaxThreadsPerMultiProcessor, dev));
      resident_patch_blocks_ = max(1, sms * (threads / kPatchThreads));
    }
    const size_t most = (plan.tiles() * plan.tile_rows * kSmoothTileW + static_cast<size_t>(max(0, H - tail_y0)) * W) /
                            kPatchPerThread / kPatchThreads + 1;
    const unsigned blocks = static_cast<unsigned>(min(most, static_cast<size_t>(resident_patch_blocks_)));
    P3D_CUDA_TRY(launch_chained(fused_anaglyph_patch_kernel, blocks, kPatchThreads, 0, stream, out, *fused_request,
                                sc, min(tail_y0, H)));
  }
  if (fused_used) *fused_used = fuse;

  if (holes_out) {
    unsigned long long h = 0;
    P3D_CUDA_TRY(cudaMemcpyAsync(&h, total, sizeof(h), cudaMemcpyDeviceToHost, stream));
    P3D_CUDA_TRY(cudaStreamSynchronize(stream));
    *holes_out = static_cast<long long>(h);
  }
  return {};
}

// NeighborAverage driver: batches of kWarpFillBatch Jacobi steps; the host
// reads the batch's per-step fill counts (one stream sync per batch) and
// stops once no hole is left or a step filled nothing. Steps after such a
// step are no-ops (masks copied), so running the rest of a batch is harmless.
CudaStatus WarpRendererGpu::neighbour_average(const FrameView &out, int W, int H, cudaStream_t stream) {
  uint8_t *counters = counters_.as<uint8_t>();
  auto *filled = reinterpret_cast<unsigned *>(counters + kFilledOffset);
  unsigned long long total = 0;
  P3D_CUDA_TRY(cudaMemcpyAsync(&total, counters + kTotalOffset, sizeof(total), cudaMemcpyDeviceToHost, stream));
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));

  const size_t masks = 2 * static_cast<size_t>(W) * H;
  uint8_t *cur = scratch_.as<uint8_t>(), *next = cur + masks;
  long long remaining = static_cast<long long>(total);
  bool stuck = false;
  while (remaining > 0 && !stuck) {
    P3D_CUDA_TRY(cudaMemsetAsync(filled, 0, sizeof(unsigned) * kWarpFillBatch, stream));
    for (int i = 0; i < kWarpFillBatch; ++i) {
      P3D_CUDA_TRY(launch_chained(neighbour_average_kernel, pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream, out, W,
                                  H, cur, next, filled + i));
      std::swap(cur, next);
    }
    unsigned counts[kWarpFillBatch] = {};
    P3D_CUDA_TRY(cudaMemcpyAsync(counts, filled, sizeof(counts), cudaMemcpyDeviceToHost, stream));
    P3D_CUDA_TRY(cudaStreamSynchronize(stream));
    for (int i = 0; i < kWarpFillBatch && !stuck; ++i) {
      remaining -= counts[i];
      stuck = counts[i] == 0;
    }
  }
  if (remaining > 0) {
    P3D_CUDA_TRY(
        launch_chained(paint_holes_kernel, pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream, out, W, H, cur));
  }
  return {};
}

}  // namespace p3d
