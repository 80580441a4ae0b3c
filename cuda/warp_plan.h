// The warp's host-side planning: which row kernel (key place, block kind,
// row groups) renders a frame and with how much shared memory, where the
// row groups give way to the tail, the BackgroundSmooth sums kernel's tiles,
// shared memory and block size, and the fused anaglyph's patch grid.
//
// Plain C++, no CUDA runtime: each choice is a function of numbers. The
// launchers (cuda/warp.cu, warp_rows.cuh, warp_smooth.cuh, warp_packed.cu)
// ask the device (the opt-in shared memory a block, the threads an SM
// holds resident of each candidate kernel, the SM count) and pass what it
// said; tests/plan/test_warp_plan.cpp checks the choices on the CPU. The
// P3D_HD functions give the shared-memory layouts that the kernels index
// with as well.
#pragma once

#include <cstddef>
#include <cstdint>

#include "../common/p3d_defs.h"
#include "../common/warp.h"

namespace p3d {
namespace warp_detail {

// The eyes' shift factors (0: copy the source).
struct EyeShifts {
  float shift[2];
};

// ---- The row kernel ---------------------------------------------------------

// Dynamic shared memory of the row kernel: [keys: W key words an eye when
// in shared memory] [the source row, W converted pixels, aligned to them]
// [per 32-pixel chunk and eye: its hole bits (bit i: pixel 32 c + i is a
// hole)] [the same for its clean bits (BackgroundSmooth)]. key_bytes: a
// key word's size, 0 for keys in global memory; eyes: the eyes that have
// arrays of their own (2 when the kernel renders them together, else 1);
// pixel_bytes: a converted pixel's size, sizeof(Rgba) for 8-bit pictures,
// sizeof(Rgba16) for 16-bit ones (the source row and the smooth fill's
// anchors).
P3D_HD int row_chunks(int W) { return (W + 31) / 32; }
size_t row_smem_bytes(int W, size_t key_bytes, int eyes, size_t pixel_bytes = sizeof(Rgba));

// Whether a row of W pixels with key words of key_bytes (0: keys in global
// memory) fits one block's shared memory of smem_optin bytes. 64 bytes:
// room for the kernel's static __shared__ counter.
bool row_fits(int W, size_t key_bytes, int smem_optin, size_t pixel_bytes = sizeof(Rgba));

// The row kernel's blocks. One row a block (Row), or the rows of a group
// in a block of a row's size and launch bounds (Group) or in one of half
// the threads an SM holds, one row after another (WideGroup) or side by
// side with a source row buffer each (RowsTogether: render_rows_together,
// cuda/warp_rows.cuh).
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
P3D_HD constexpr int tail_blocks_a_row(RowBlock b) { return b == RowBlock::RowsTogether ? 2 : 1; }
constexpr int kRowThreadsMax = 512;
// At most 1 << kGroupShiftMax rows a group (4: the 4K and 8K grids'
// cells). Even where that leaves few blocks for the GPU's slots (4K: 540
// Group blocks for 528 slots on a Hopper card of 132 SMs) the longer
// groups win over groups of 2 rows (measured: docs/benchmarks.md, Design
// measurements, "Warp: row groups").
constexpr int kGroupShiftMax = 2;

// The z-buffer a frame's row kernel uses: NarrowKeys in shared memory where
// every hit is near its target (warp_narrow_keys_fit) and the row fits,
// else WideKeys in shared memory, else WideKeys in global memory (rows of
// about 19000 pixels and more on Hopper).
// NarrowSharedPerEye: NarrowKeys in shared memory, a z-buffer for each
// eye, both eyes rendered at once (both warped, and the second z-buffer
// costs no resident thread: choose_row_kernels).
enum class KeyPlace { NarrowSharedPerEye, NarrowShared, WideShared, WideGlobal };

// Threads a row's block has (Row and Group blocks).
int row_threads(int W);

// Shared memory of a RowsTogether block of `rows` rows: a row's with both
// z-buffers, and a source row more for each further row.
size_t together_smem_bytes(int W, int rows, size_t pixel_bytes = sizeof(Rgba));

// The row kernels chosen for rows of `width` pixels and `fill` with both
// eyes warped and 32-bit keys (choose_row_kernels): both eyes at once, and
// row groups where the depth is on cells of 2 x 2 pixels or more, in
// blocks of a row's size or in wide blocks of wide_group_threads, row by
// row or all rows together.
struct RowKernelChoice {
  int width = -1;
  HoleFill fill = HoleFill::None;
  size_t pixel_bytes = sizeof(Rgba);  // the converted source pixel the kernels take
  bool both_eyes = false;
  bool groups = false;
  bool wide_groups = false;
  bool rows_together = false;
  int wide_group_threads = 0;  // a WideGroup or RowsTogether block's size
  int group_slots = 0;         // the group blocks the device holds resident (waves)
};

// What the device holds of each candidate row kernel for rows of W pixels
// (NarrowKeys, the fill's instances; cuda/warp_rows.cuh, query_row_kernels_of):
// resident threads an SM (blocks an SM times the block's threads) of the
// eyes in turn and both eyes at once in a row's block (row_threads), of
// Group blocks, of WideGroup blocks and of RowsTogether blocks of 1 <<
// kGroupShiftMax rows (0 where they do not fit: rows_together_fit); the
// wide kernels' block sizes (their launch bound on the device's
// architecture); the SM count.
struct RowKernelResidency {
  int in_turn = 0, both = 0, group = 0, wide = 0, together = 0;
  int wide_block = 0, together_block = 0;
  int sms = 0;
};

// Whether a row of W pixels with both z-buffers fits a block (else only
// the eyes in turn run, and nothing is asked of the device).
bool both_eyes_fit(int W, int smem_optin, size_t pixel_bytes = sizeof(Rgba));
// Whether a RowsTogether block of the longest group fits.
bool rows_together_fit(int W, int smem_optin, size_t pixel_bytes = sizeof(Rgba));

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
// Where both z-buffers do not fit (both_eyes_fit), only width, fill and
// pixel size are set. 16-bit pictures (pixel_bytes 8) go by the same rule
// with their larger rows: at 4K on Hopper the eyes in turn and two
// WideGroup blocks hold 2048 threads, a row's block with both z-buffers
// 1536 and a RowsTogether block 1024, so their cells' rows take WideGroup
// blocks.
RowKernelChoice choose_row_kernels(HoleFill fill, int W, int smem_optin, const RowKernelResidency &resident,
                                   size_t pixel_bytes = sizeof(Rgba));

// A frame as the row plan sees it.
struct RowFrame {
  int W = 0, H = 0;
  bool narrow_keys = false;  // warp_narrow_keys_fit for the frame's shifts
  bool both_warped = false;  // both eyes' shift factors are not 0
  int depth_shift = 0;       // the depth grid's cells: 1 << depth_shift pixels a side
  int smem_optin = 0;        // the device's opt-in shared memory a block
  size_t pixel_bytes = sizeof(Rgba);  // the converted source pixel (row_smem_bytes)
};

// Whether the frame's rows take choose_row_kernels' kernels (NarrowKeys
// fit the shifts and shared memory, both eyes warped).
bool row_kernels_apply(const RowFrame &f);

// The row kernel a frame runs: its key place, its rows a block and block
// kind, its shared memory, and where its row groups end (group_tail_y0).
struct RowPlan {
  KeyPlace keys = KeyPlace::WideGlobal;
  int group_rows = 1;  // rows a block (NarrowSharedPerEye only; 1: a row's block)
  bool rows_together = false;  // groups in RowsTogether blocks, of wide_group_threads
  bool wide_groups = false;    // groups in WideGroup blocks, of wide_group_threads
  int wide_group_threads = 0;
  size_t smem = 0;  // the row kernel's dynamic shared memory
  int tail_y0 = 0;  // row groups: from this row on, a block a row or eye
};

// The plan of a frame whose row fits (row_fits with keys in global
// memory); `rows`: choose_row_kernels' choice for the frame's width and
// fill, read only where row_kernels_apply.
RowPlan plan_rows(const RowFrame &f, const RowKernelChoice &rows);

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
int group_tail_y0(int H, int group_rows, int slots);

// ---- BackgroundSmooth's sums ------------------------------------------------

// Scratch per pixel and eye: anchor (a converted pixel of pixel_bytes),
// state; and a byte per 32-pixel chunk of a row and eye (has it a hole).
P3D_HD size_t smooth_bytes_per_pixel(size_t pixel_bytes) { return pixel_bytes + 1; }
// A wide sum of anchors of pixel_bytes: SmoothSum, or SmoothSum16 for Rgba16.
P3D_HD size_t smooth_wide_sum_bytes(size_t pixel_bytes) {
  return pixel_bytes == sizeof(Rgba16) ? sizeof(SmoothSum16) : sizeof(SmoothSum);
}

// A tile of the sums kernel (cuda/warp_smooth.cuh) is kSmoothTileW columns
// x up to kSmoothTileRowsMax rows of one eye, in a block of
// kSmoothTileThreads threads, or kSmoothTileThreadsMax where an SM holds as
// many tiles of that size (choose_smooth_threads).
constexpr int kSmoothTileW = 32, kSmoothTileThreads = 256, kSmoothTileRowsMax = 32;
constexpr int kSmoothTileThreadsMax = 512;
constexpr int kSmoothTilesPerBlock = 8;  // the sums kernel's grid (smooth_tile_kernel)
// Windows of at most this many rows up and down take tiles of 16 rows (plan_smooth).
constexpr int kSmoothShortR = 32;
static_assert(kSmoothTileW == 32, "a tile's columns are one chunk of the row kernel's chunk flags");
static_assert(kSmoothTileThreads % 32 == 0 && kSmoothTileThreadsMax % 32 == 0,
              "whole warps: the row kernel's chunk loops and the copies");
P3D_HD size_t align16(size_t n) { return (n + 15) & ~static_cast<size_t>(15); }
P3D_HD int smooth_tile_columns(int Rx) { return kSmoothTileW + 2 * Rx; }

// V in shared memory (TileSums, cuda/warp_smooth.cuh). Wide: SmoothSum (20
// bytes; SmoothSum16, 40, for 16-bit anchors). Narrow, for 8-bit anchors
// when a column window holds at most 257 anchors (R <= kSmoothNarrowRMax):
// each channel sum fits 16 bits (255 * 257 = 65535), so V takes 10 bytes,
// (r | g << 16, b | a << 16) and the count, which lets more tiles share an
// SM.
constexpr int kSmoothNarrowRMax = 128;
static_assert(255 * (2 * kSmoothNarrowRMax + 1) <= 65535, "a narrow V channel fits 16 bits");
constexpr size_t kSmoothWidePixelBytes = sizeof(SmoothSum);
constexpr size_t kSmoothNarrowPixelBytes = 2 * sizeof(uint32_t) + sizeof(uint16_t);
// V of `count` pixels: wide, one wide sum each; narrow, the channel words
// (two 32-bit words a pixel) then the counts, each 16-byte aligned.
P3D_HD size_t smooth_v_bytes(bool narrow, size_t count, size_t pixel_bytes = sizeof(Rgba)) {
  return narrow ? align16(count * 2 * sizeof(uint32_t)) + align16(count * sizeof(uint16_t))
                : align16(count * smooth_wide_sum_bytes(pixel_bytes));
}
P3D_HD size_t smooth_tile_v_bytes(bool narrow, int Rx, int S, size_t pixel_bytes = sizeof(Rgba)) {
  return smooth_v_bytes(narrow, static_cast<size_t>(smooth_tile_columns(Rx)) * S, pixel_bytes);
}
// The staged copy: anchors (pixel_bytes each), states (bytes), then the
// chunk flags of its rows (at most 2 + (columns - 1) / 32 chunks a row).
P3D_HD size_t smooth_tile_copy_pixels(int R, int Rx, int S) {
  return static_cast<size_t>(smooth_tile_columns(Rx)) * (S + 2 * R);
}
P3D_HD size_t smooth_tile_copy_bytes(int R, int Rx, int S, size_t pixel_bytes = sizeof(Rgba)) {
  const size_t flag_columns = 2 + (smooth_tile_columns(Rx) - 1) / 32;
  return smooth_tile_copy_pixels(R, Rx, S) * smooth_bytes_per_pixel(pixel_bytes) + flag_columns * (S + 2 * R);
}

// BackgroundSmooth's sums for a frame: the eyes' radii, the tile rows, and
// the sums kernel's shared memory.
struct SmoothPlan {
  int radius[2];  // R of each eye
  bool narrow, staged;
  int tile_rows, tiles_x, tiles_y;
  size_t smem;
  size_t tiles() const { return 2 * static_cast<size_t>(tiles_x) * tiles_y; }
};

// narrow: V's narrow sums (8-bit anchors, R <= kSmoothNarrowRMax over the
// warped eyes); staged: the tile's states and anchors copied into shared
// memory, where that fits smem_optin beside V. pixel_bytes: the anchors'
// size (row_smem_bytes).
SmoothPlan plan_smooth(const EyeShifts &eyes, float D, int W, int H, int smem_optin,
                       size_t pixel_bytes = sizeof(Rgba));

// The sums kernel's block size, from the blocks an SM holds resident of
// the plan's kernel (no register bound) with kSmoothTileThreads and with
// kSmoothTileThreadsMax threads (tiles, tiles_max), and of its twin bound
// to kSmoothTileThreads threads and as many blocks as an SM holds threads
// for (tiles_tight); `tight`: launch the twin.
// kSmoothTileThreadsMax where an SM holds as many tiles of that size as of
// kSmoothTileThreads, else kSmoothTileThreads. A tile's copy, walks and
// row sums all share its threads out, so more threads finish a tile
// sooner; but where registers, not shared memory, bound the tiles an SM
// holds, twice the threads hold half the tiles, and a frame's tiles take
// more waves: 512 threads pay at 8K (3 tiles an SM either way: 64 KB of
// shared memory a tile), not at 4K (6 tiles an SM with 256, 3 with 512);
// 1080p's tiles are bound by registers as at 4K, so the rule keeps 256
// there (measured: docs/benchmarks.md, Design measurements, "Warp: the
// smooth fill's sums"). The twin (32 registers a thread on Hopper, so 8
// tiles an SM at 4K instead of 6) runs where it keeps more threads
// resident, which it does where registers, not shared memory, bound the
// tiles: 4K and 1080p, not 8K. A 4K frame lists about a thousand tiles,
// which 8 tiles an SM take in one wave; 1080p's few hundred tiles fit
// either way, and gain nothing (measured: docs/benchmarks.md, Design
// measurements, "Warp: the smooth fill's sums").
struct SmoothThreads {
  int threads;
  bool tight;
};
SmoothThreads choose_smooth_threads(int tiles, int tiles_max, int tiles_tight);

// The sums kernel's block size last chosen, for a kernel and its shared
// memory (cuda/warp_smooth.cuh, smooth_tile_threads).
struct SmoothSumsLaunch {
  const void *kernel = nullptr;  // the kernel with no register bound, for the frame's plan
  size_t smem = 0;
  const void *launch = nullptr;  // the kernel launched: it, or its register-bound twin
  int threads = 0;
};

// ---- The fused anaglyph's patch kernel (cuda/warp_packed.cu) ---------------

// kPatchPerThread pixels of one row an item (a quarter of a tile's row, or
// of a tail row), in blocks of kPatchThreads.
constexpr int kPatchThreads = 256, kPatchPerThread = 4;
static_assert(kSmoothTileW % kPatchPerThread == 0, "a tile row is whole items");

// One wave of the patch kernel's blocks on a device of `sms` SMs holding
// threads_per_sm threads each (at least one block).
int patch_resident_blocks(int sms, int threads_per_sm);
// The patch kernel's grid: one wave of resident blocks, or fewer if the
// frame could not fill them (every tile of the plan listed, and the tail
// rows from tail_y0 on).
unsigned patch_blocks(const SmoothPlan &plan, int W, int H, int tail_y0, int resident_blocks);

}  // namespace warp_detail
}  // namespace p3d
