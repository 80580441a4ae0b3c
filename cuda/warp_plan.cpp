// The warp's host-side planning (warp_plan.h): the choices alone; the
// launchers ask the device.
#include "warp_plan.h"

#include <algorithm>

namespace p3d {
namespace warp_detail {

size_t row_smem_bytes(int W, size_t key_bytes, int eyes, size_t pixel_bytes) {
  const size_t keys = eyes * key_bytes * W;
  return (keys + pixel_bytes - 1) / pixel_bytes * pixel_bytes + pixel_bytes * static_cast<size_t>(W) +
         eyes * 2 * sizeof(unsigned) * static_cast<size_t>(row_chunks(W));
}

bool row_fits(int W, size_t key_bytes, int smem_optin, size_t pixel_bytes) {
  return row_smem_bytes(W, key_bytes, 1, pixel_bytes) + 64 <= static_cast<size_t>(smem_optin);
}

int row_threads(int W) { return W > 1024 ? kRowThreadsMax : 256; }

size_t together_smem_bytes(int W, int rows, size_t pixel_bytes) {
  return row_smem_bytes(W, sizeof(NarrowKeys::Word), 2, pixel_bytes) +
         pixel_bytes * static_cast<size_t>(W) * (rows - 1);
}

bool both_eyes_fit(int W, int smem_optin, size_t pixel_bytes) {
  return row_smem_bytes(W, sizeof(NarrowKeys::Word), 2, pixel_bytes) + 64 <= static_cast<size_t>(smem_optin);
}

bool rows_together_fit(int W, int smem_optin, size_t pixel_bytes) {
  return together_smem_bytes(W, 1 << kGroupShiftMax, pixel_bytes) + 64 <= static_cast<size_t>(smem_optin);
}

RowKernelChoice choose_row_kernels(HoleFill fill, int W, int smem_optin, const RowKernelResidency &resident,
                                   size_t pixel_bytes) {
  RowKernelChoice c;
  c.width = W;
  c.fill = fill;
  c.pixel_bytes = pixel_bytes;
  if (!both_eyes_fit(W, smem_optin, pixel_bytes)) return c;
  const int together_threads = rows_together_fit(W, smem_optin, pixel_bytes) ? resident.together : 0;
  c.both_eyes = resident.both >= resident.in_turn;
  const int row_best = c.both_eyes ? resident.both : resident.in_turn;
  if (together_threads > 0 && together_threads >= row_best) {
    c.groups = c.rows_together = true;
    c.wide_group_threads = resident.together_block;
    c.group_slots = resident.sms * (together_threads / resident.together_block);
  } else if (resident.group > 0 && resident.group >= row_best) {
    c.groups = true;
    c.group_slots = resident.sms * (resident.group / row_threads(W));
  } else if (resident.wide > 0 && resident.wide >= row_best) {
    c.groups = c.wide_groups = true;
    c.wide_group_threads = resident.wide_block;
    c.group_slots = resident.sms * (resident.wide / resident.wide_block);
  }
  return c;
}

bool row_kernels_apply(const RowFrame &f) {
  return f.narrow_keys && row_fits(f.W, sizeof(NarrowKeys::Word), f.smem_optin, f.pixel_bytes) && f.both_warped;
}

RowPlan plan_rows(const RowFrame &f, const RowKernelChoice &rows) {
  const bool narrow = f.narrow_keys && row_fits(f.W, sizeof(NarrowKeys::Word), f.smem_optin, f.pixel_bytes);
  const bool wide_shared = !narrow && row_fits(f.W, sizeof(WideKeys::Word), f.smem_optin, f.pixel_bytes);
  const bool apply = row_kernels_apply(f);
  const RowKernelChoice none;
  const RowKernelChoice &k = apply ? rows : none;
  RowPlan p;
  bool per_eye = false;
  if (apply) {
    if (k.groups && f.depth_shift > 0)
      p.group_rows = 1 << (f.depth_shift < kGroupShiftMax ? f.depth_shift : kGroupShiftMax);
    per_eye = k.both_eyes || p.group_rows > 1;
  }
  p.keys = per_eye       ? KeyPlace::NarrowSharedPerEye
           : narrow      ? KeyPlace::NarrowShared
           : wide_shared ? KeyPlace::WideShared
                         : KeyPlace::WideGlobal;
  p.rows_together = p.group_rows > 1 && k.rows_together;
  p.wide_groups = k.wide_groups;
  p.wide_group_threads = k.wide_group_threads;
  p.smem = p.rows_together ? together_smem_bytes(f.W, p.group_rows, f.pixel_bytes)
                           : row_smem_bytes(f.W, narrow ? sizeof(NarrowKeys::Word)
                                                        : wide_shared ? sizeof(WideKeys::Word) : 0,
                                            per_eye ? 2 : 1, f.pixel_bytes);
  p.tail_y0 = group_tail_y0(f.H, p.group_rows, k.group_slots);
  return p;
}

int group_tail_y0(int H, int group_rows, int slots) {
  const int groups = (H + group_rows - 1) / group_rows;
  if (group_rows <= 1 || slots <= 0 || groups <= slots || groups % slots == 0) return groups * group_rows;
  return (groups / slots) * slots * group_rows;
}

SmoothPlan plan_smooth(const EyeShifts &eyes, float D, int W, int H, int smem_optin, size_t pixel_bytes) {
  SmoothPlan p;
  const int R0 = smooth_fill_radius(eyes.shift[0], D), R1 = smooth_fill_radius(eyes.shift[1], D);
  const int Rmax = std::max(eyes.shift[0] == 0.f ? 0 : R0, eyes.shift[1] == 0.f ? 0 : R1),
            Rx = smooth_fill_radius_x(Rmax);
  p.radius[0] = R0;
  p.radius[1] = R1;
  p.narrow = Rmax <= kSmoothNarrowRMax && pixel_bytes == sizeof(Rgba);
  // Tile rows: 16 for windows of up to kSmoothShortR rows, else
  // kSmoothTileRowsMax; fewer when V would pass 64 KB (wide Rx). A listed
  // tile sums all its rows and copies 2R more, and holes are sparse: short
  // tiles do less work on rows without holes, tall ones copy the 2R rows
  // fewer times: 16 rows win at R = 15 and 29 (1080p, 4K), 32 at R = 58
  // (8K) (measured: docs/benchmarks.md, Design measurements, "Warp: the
  // smooth fill's sums").
  const size_t v_pixel = p.narrow ? kSmoothNarrowPixelBytes : smooth_wide_sum_bytes(pixel_bytes);
  const int rows = Rmax <= kSmoothShortR ? 16 : kSmoothTileRowsMax;
  const int S = std::max(1, std::min(rows, static_cast<int>(65536 / (smooth_tile_columns(Rx) * v_pixel))));
  p.tile_rows = S;
  p.tiles_x = (W + kSmoothTileW - 1) / kSmoothTileW;
  p.tiles_y = (H + S - 1) / S;
  p.smem = smooth_tile_v_bytes(p.narrow, Rx, S, pixel_bytes);
  const size_t copy = smooth_tile_copy_bytes(Rmax, Rx, S, pixel_bytes);
  p.staged = p.smem + copy + 64 <= static_cast<size_t>(smem_optin);
  if (p.staged) p.smem += copy;
  return p;
}

SmoothThreads choose_smooth_threads(int tiles, int tiles_max, int tiles_tight) {
  const int threads = tiles_max >= tiles ? kSmoothTileThreadsMax : kSmoothTileThreads;
  const bool use_tight = tiles_tight * kSmoothTileThreads > (tiles_max >= tiles ? tiles_max : tiles) * threads;
  return SmoothThreads{use_tight ? kSmoothTileThreads : threads, use_tight};
}

int patch_resident_blocks(int sms, int threads_per_sm) { return std::max(1, sms * (threads_per_sm / kPatchThreads)); }

unsigned patch_blocks(const SmoothPlan &plan, int W, int H, int tail_y0, int resident_blocks) {
  const size_t most =
      (plan.tiles() * plan.tile_rows * kSmoothTileW + static_cast<size_t>(std::max(0, H - tail_y0)) * W) /
          kPatchPerThread / kPatchThreads +
      1;
  return static_cast<unsigned>(std::min(most, static_cast<size_t>(resident_blocks)));
}

}  // namespace warp_detail
}  // namespace p3d
