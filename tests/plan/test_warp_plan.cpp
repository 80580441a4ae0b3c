// The warp's host planning (cuda/warp_plan.h) on the CPU: which row kernel
// (key place, block kind, row groups) a frame of each width takes, that
// every plan's shared memory fits the device's opt-in limit, where row
// groups give way to the tail (group_tail_y0), the BackgroundSmooth sums'
// tiles, V width and staging at their limits, the sums kernel's block
// size, and the fused anaglyph's patch grid.
//
// The device's answers (threads an SM holds of each kernel) come from a
// model of an SM of compute capability 9.0 (CUDA C++ Programming Guide,
// "Technical Specifications per Compute Capability" and "Shared Memory"):
// 2048 resident threads, 228 KB of shared memory, up to 227 KB a block by
// opting in, 1 KB reserved a block, allocated in 128-byte units. The row
// kernels' register bounds let their blocks reach the thread limit, so
// threads and shared memory alone bound them. With it the planner must
// make the choices the code's comments give for Hopper: RowsTogether
// blocks at 4K, WideGroup blocks at 8K, the eyes in turn from about 4600
// pixels a row.
#include <algorithm>
#include <cstddef>

#include <gtest/gtest.h>

#include "warp_plan.h"

namespace p3d {
namespace warp_detail {
namespace {

constexpr int kOptin = 227 * 1024;
constexpr int kSmemPerSm = 228 * 1024;
constexpr int kReservedPerBlock = 1024;
constexpr int kThreadsPerSm = 2048;
constexpr int kSms = 132;
constexpr int kRowStaticSmem = 16;  // the row kernel's static __shared__ bytes
constexpr int kWideBlock = kThreadsPerSm / 2;  // kWideGroupThreads on sm_90

// Threads an SM holds of blocks of `threads` with `smem` bytes of dynamic
// shared memory (the model above).
int resident_threads(int threads, size_t smem) {
  const size_t block = (smem + kRowStaticSmem + 127) / 128 * 128 + kReservedPerBlock;
  const int by_smem = static_cast<int>(kSmemPerSm / block);
  return std::min(kThreadsPerSm / threads, by_smem) * threads;
}

// What query_row_kernels reads of such a device for rows of W pixels of
// pixel_bytes converted pixels (sizeof(Rgba16) for 16-bit pictures).
RowKernelResidency modelled_residency(int W, size_t pixel_bytes = sizeof(Rgba)) {
  RowKernelResidency r;
  const size_t both = row_smem_bytes(W, sizeof(NarrowKeys::Word), 2, pixel_bytes);
  r.in_turn = resident_threads(row_threads(W), row_smem_bytes(W, sizeof(NarrowKeys::Word), 1, pixel_bytes));
  r.both = resident_threads(row_threads(W), both);
  r.group = resident_threads(row_threads(W), both);
  r.wide_block = r.together_block = kWideBlock;
  r.wide = resident_threads(kWideBlock, both);
  if (rows_together_fit(W, kOptin, pixel_bytes))
    r.together = resident_threads(kWideBlock, together_smem_bytes(W, 1 << kGroupShiftMax, pixel_bytes));
  r.sms = kSms;
  return r;
}

RowKernelChoice modelled_choice(int W, HoleFill fill = HoleFill::BackgroundSmooth) {
  return choose_row_kernels(fill, W, kOptin, modelled_residency(W));
}

// Both eyes warped, NarrowKeys fit the shifts.
RowFrame both_warped(int W, int H, int depth_shift) {
  RowFrame f;
  f.W = W;
  f.H = H;
  f.narrow_keys = true;
  f.both_warped = true;
  f.depth_shift = depth_shift;
  f.smem_optin = kOptin;
  return f;
}

// ---- Row kernels -------------------------------------------------------------

TEST(WarpPlanRows, RowThreads) {
  EXPECT_EQ(row_threads(1), 256);
  EXPECT_EQ(row_threads(1024), 256);
  EXPECT_EQ(row_threads(1025), kRowThreadsMax);
  EXPECT_EQ(row_threads(7680), kRowThreadsMax);
  EXPECT_EQ(tail_blocks_a_row(RowBlock::RowsTogether), 2);
  EXPECT_EQ(tail_blocks_a_row(RowBlock::Group), 1);
  EXPECT_EQ(tail_blocks_a_row(RowBlock::WideGroup), 1);
  EXPECT_EQ(tail_blocks_a_row(RowBlock::Row), 1);
}

TEST(WarpPlanRows, SharedMemoryLayout) {
  // keys, the source row (4 bytes a pixel), hole and clean bits per chunk,
  // per eye that has arrays of its own.
  EXPECT_EQ(row_chunks(1), 1);
  EXPECT_EQ(row_chunks(32), 1);
  EXPECT_EQ(row_chunks(33), 2);
  EXPECT_EQ(row_smem_bytes(3840, 4, 1), 3840u * 4 + 3840u * 4 + 120u * 8);
  EXPECT_EQ(row_smem_bytes(3840, 4, 2), 2u * 3840 * 4 + 3840u * 4 + 2u * 120 * 8);
  EXPECT_EQ(row_smem_bytes(3840, 0, 1), 3840u * 4 + 120u * 8);
  // A RowsTogether block: a further source row for each further row.
  EXPECT_EQ(together_smem_bytes(3840, 1), row_smem_bytes(3840, 4, 2));
  EXPECT_EQ(together_smem_bytes(3840, 4), row_smem_bytes(3840, 4, 2) + 3u * 3840 * 4);
}

TEST(WarpPlanRows, RowsTogetherAt1080pAnd4K) {
  for (int W : {1920, 3840}) {
    const RowKernelChoice c = modelled_choice(W);
    EXPECT_EQ(c.width, W);
    EXPECT_EQ(c.fill, HoleFill::BackgroundSmooth);
    EXPECT_TRUE(c.both_eyes) << W;
    EXPECT_TRUE(c.groups) << W;
    EXPECT_TRUE(c.rows_together) << W;
    EXPECT_FALSE(c.wide_groups) << W;
    EXPECT_EQ(c.wide_group_threads, kWideBlock) << W;
    EXPECT_EQ(c.group_slots, 2 * kSms) << W;  // two 1024-thread blocks an SM
  }
}

TEST(WarpPlanRows, WideGroupsAt8K) {
  // 8K: both z-buffers keep two row blocks (1024 threads) where the eyes in
  // turn keep three (1536), RowsTogether one; two WideGroup blocks hold
  // 2048.
  const RowKernelChoice c = modelled_choice(7680);
  EXPECT_FALSE(c.both_eyes);
  EXPECT_TRUE(c.groups);
  EXPECT_TRUE(c.wide_groups);
  EXPECT_FALSE(c.rows_together);
  EXPECT_EQ(c.wide_group_threads, kWideBlock);
  EXPECT_EQ(c.group_slots, 2 * kSms);
}

TEST(WarpPlanRows, BothEyesUpToAbout4600Pixels) {
  int first_in_turn = -1;
  for (int W = 1024; W <= 8192 && first_in_turn < 0; W += 32)
    if (!modelled_choice(W).both_eyes) first_in_turn = W;
  EXPECT_GE(first_in_turn, 4400);
  EXPECT_LE(first_in_turn, 4800);
  for (int W : {1280, 1920, 2560, 3840, 4096}) EXPECT_TRUE(modelled_choice(W).both_eyes) << W;
  for (int W : {5120, 6144, 7680}) EXPECT_FALSE(modelled_choice(W).both_eyes) << W;
}

TEST(WarpPlanRows, NothingAskedWhereBothZBuffersDoNotFit) {
  // Rows whose both z-buffers pass the opt-in limit: only width and fill,
  // whatever the residency says.
  int W = 1024;
  while (both_eyes_fit(W, kOptin)) W += 16;
  EXPECT_GT(W, 18000);
  EXPECT_LT(W, 19000);
  RowKernelResidency plenty;
  plenty.in_turn = plenty.both = plenty.group = plenty.wide = plenty.together = kThreadsPerSm;
  plenty.wide_block = plenty.together_block = kWideBlock;
  plenty.sms = kSms;
  const RowKernelChoice c = choose_row_kernels(HoleFill::Background, W, kOptin, plenty);
  EXPECT_EQ(c.width, W);
  EXPECT_EQ(c.fill, HoleFill::Background);
  EXPECT_FALSE(c.both_eyes);
  EXPECT_FALSE(c.groups);
  EXPECT_EQ(c.group_slots, 0);
}

TEST(WarpPlanRows, RowsTogetherOnlyWhereItsBlockFits) {
  // Past ~9500 pixels four source rows and both z-buffers pass the limit:
  // a RowsTogether residency, even the best, is not taken.
  const int W = 10000;
  ASSERT_TRUE(both_eyes_fit(W, kOptin));
  ASSERT_FALSE(rows_together_fit(W, kOptin));
  RowKernelResidency r;
  r.in_turn = r.both = 1024;
  r.group = 1024;
  r.wide = 1024;
  r.together = kThreadsPerSm;
  r.wide_block = r.together_block = kWideBlock;
  r.sms = kSms;
  const RowKernelChoice c = choose_row_kernels(HoleFill::None, W, kOptin, r);
  EXPECT_FALSE(c.rows_together);
  EXPECT_TRUE(c.groups);  // Group blocks tie the row kernel and come next
  EXPECT_FALSE(c.wide_groups);
  EXPECT_EQ(c.group_slots, kSms * (1024 / row_threads(W)));
}

TEST(WarpPlanRows, TiesGoToTheEarlierKindInOrder) {
  // RowsTogether, then Group, then WideGroup, each where it holds at least
  // as many threads as the row kernel; the eyes together where they hold
  // as many as the eyes in turn.
  RowKernelResidency r;
  r.in_turn = 1536;
  r.both = 1536;
  r.group = 1536;
  r.wide = 1536;
  r.together = 1536;
  r.wide_block = r.together_block = kWideBlock;
  r.sms = 10;
  RowKernelChoice c = choose_row_kernels(HoleFill::None, 3840, kOptin, r);
  EXPECT_TRUE(c.both_eyes);
  EXPECT_TRUE(c.rows_together);
  EXPECT_EQ(c.group_slots, 10 * 1);  // 1536 / 1024 blocks an SM

  r.together = 1024;
  c = choose_row_kernels(HoleFill::None, 3840, kOptin, r);
  EXPECT_FALSE(c.rows_together);
  EXPECT_TRUE(c.groups);
  EXPECT_FALSE(c.wide_groups);
  EXPECT_EQ(c.group_slots, 10 * 3);  // 1536 / 512

  r.group = 1024;
  c = choose_row_kernels(HoleFill::None, 3840, kOptin, r);
  EXPECT_TRUE(c.wide_groups);
  EXPECT_EQ(c.wide_group_threads, kWideBlock);

  r.wide = 1024;
  c = choose_row_kernels(HoleFill::None, 3840, kOptin, r);
  EXPECT_FALSE(c.groups);
  EXPECT_EQ(c.group_slots, 0);

  r.both = 1024;  // the eyes in turn keep more threads resident
  c = choose_row_kernels(HoleFill::None, 3840, kOptin, r);
  EXPECT_FALSE(c.both_eyes);
}

// ---- A frame's row plan ------------------------------------------------------

TEST(WarpPlanFrame, KeyPlaceByWidth) {
  // One eye warped: no row kernel choice is read, only the key place.
  RowFrame f;
  f.H = 16;
  f.narrow_keys = true;
  f.both_warped = false;
  f.smem_optin = kOptin;
  const RowKernelChoice stale = modelled_choice(3840);
  for (int W : {1920, 3840, 7680, 20000, 28000}) {
    f.W = W;
    const RowPlan p = plan_rows(f, stale);
    EXPECT_EQ(p.keys, KeyPlace::NarrowShared) << W;
    EXPECT_EQ(p.smem, row_smem_bytes(W, 4, 1)) << W;
    EXPECT_EQ(p.group_rows, 1) << W;
    EXPECT_FALSE(p.rows_together) << W;
    EXPECT_EQ(p.tail_y0, f.H) << W;
  }
  // 32-bit keys in shared memory up to about 28000 pixels, 64-bit ones up
  // to about 19000, then in global memory; rows are refused past about
  // 54000.
  f.W = 28500;
  EXPECT_EQ(plan_rows(f, stale).keys, KeyPlace::WideGlobal);
  EXPECT_EQ(plan_rows(f, stale).smem, row_smem_bytes(28500, 0, 1));
  f.narrow_keys = false;
  f.W = 18900;
  EXPECT_EQ(plan_rows(f, stale).keys, KeyPlace::WideShared);
  EXPECT_EQ(plan_rows(f, stale).smem, row_smem_bytes(18900, 8, 1));
  f.W = 19000;
  EXPECT_EQ(plan_rows(f, stale).keys, KeyPlace::WideGlobal);
  EXPECT_TRUE(row_fits(54000, 0, kOptin));
  EXPECT_FALSE(row_fits(55000, 0, kOptin));
}

TEST(WarpPlanFrame, RowGroupsFollowTheDepthCells) {
  const int W = 3840, H = 2160;
  const RowKernelChoice c = modelled_choice(W);
  // Full-size depth: both eyes at once, a row a block.
  RowPlan p = plan_rows(both_warped(W, H, 0), c);
  EXPECT_EQ(p.keys, KeyPlace::NarrowSharedPerEye);
  EXPECT_EQ(p.group_rows, 1);
  EXPECT_FALSE(p.rows_together);
  EXPECT_EQ(p.smem, row_smem_bytes(W, 4, 2));
  EXPECT_EQ(p.tail_y0, H);
  // Cells of 2 x 2: pairs of rows; 4 x 4 and larger: four rows.
  p = plan_rows(both_warped(W, H, 1), c);
  EXPECT_EQ(p.group_rows, 2);
  EXPECT_TRUE(p.rows_together);
  EXPECT_EQ(p.smem, together_smem_bytes(W, 2));
  for (int shift : {2, 3}) {
    p = plan_rows(both_warped(W, H, shift), c);
    EXPECT_EQ(p.keys, KeyPlace::NarrowSharedPerEye);
    EXPECT_EQ(p.group_rows, 1 << kGroupShiftMax) << shift;
    EXPECT_TRUE(p.rows_together);
    EXPECT_EQ(p.wide_group_threads, kWideBlock);
    EXPECT_EQ(p.smem, together_smem_bytes(W, 4));
    // 540 groups on 264 slots: two whole waves, then a block a row or eye.
    EXPECT_EQ(p.tail_y0, 2 * 264 * 4);
  }
}

TEST(WarpPlanFrame, EightK) {
  const int W = 7680, H = 4320;
  const RowKernelChoice c = modelled_choice(W);
  // Full-size depth: the eyes in turn keep more rows resident.
  RowPlan p = plan_rows(both_warped(W, H, 0), c);
  EXPECT_EQ(p.keys, KeyPlace::NarrowShared);
  EXPECT_EQ(p.smem, row_smem_bytes(W, 4, 1));
  // The filter's 4 x 4 cells: WideGroup blocks with both z-buffers.
  p = plan_rows(both_warped(W, H, 2), c);
  EXPECT_EQ(p.keys, KeyPlace::NarrowSharedPerEye);
  EXPECT_EQ(p.group_rows, 4);
  EXPECT_TRUE(p.wide_groups);
  EXPECT_FALSE(p.rows_together);
  EXPECT_EQ(p.wide_group_threads, kWideBlock);
  EXPECT_EQ(p.smem, row_smem_bytes(W, 4, 2));
  EXPECT_EQ(p.tail_y0, 4 * 264 * 4);  // 1080 groups: four whole waves, 24 groups in the tail
}

TEST(WarpPlanFrame, ChoiceIgnoredWhereNarrowKeysDoNotFit) {
  // Shifts too large for 32-bit keys: 64-bit keys, the eyes in turn, no
  // groups, whatever the row kernel choice says.
  RowFrame f = both_warped(3840, 2160, 2);
  f.narrow_keys = false;
  const RowPlan p = plan_rows(f, modelled_choice(3840));
  EXPECT_EQ(p.keys, KeyPlace::WideShared);
  EXPECT_EQ(p.group_rows, 1);
  EXPECT_FALSE(p.rows_together);
  EXPECT_FALSE(p.wide_groups);
  EXPECT_EQ(p.tail_y0, 2160);
  EXPECT_FALSE(row_kernels_apply(f));
  EXPECT_TRUE(row_kernels_apply(both_warped(3840, 2160, 2)));
}

TEST(WarpPlanFrame, EveryPlanFitsTheOptInLimit) {
  // The row kernel's dynamic shared memory and its 64 static bytes fit
  // the limit for every width whose row fits at all, any key place,
  // depth grid and choice.
  for (int optin : {48 * 1024, 99 * 1024, kOptin}) {
    for (int W = 1; row_fits(W, 0, optin); W += W < 64 ? 1 : 37) {
      RowKernelResidency r = modelled_residency(W);
      const RowKernelChoice c = choose_row_kernels(HoleFill::BackgroundSmooth, W, optin, r);
      for (bool narrow : {false, true})
        for (bool both : {false, true})
          for (int shift = 0; shift <= 3; ++shift) {
            RowFrame f = both_warped(W, 64, shift);
            f.narrow_keys = narrow;
            f.both_warped = both;
            f.smem_optin = optin;
            const RowPlan p = plan_rows(f, c);
            ASSERT_LE(p.smem + 64, static_cast<size_t>(optin))
                << "W " << W << " optin " << optin << " narrow " << narrow << " both " << both << " shift " << shift;
            ASSERT_GE(p.tail_y0, 0);
            ASSERT_LE(p.tail_y0, 64 + p.group_rows - 1);
          }
    }
  }
}

// ---- The tail of row groups --------------------------------------------------

TEST(WarpPlanTail, GroupTailY0) {
  // 4K: 540 groups of 4 on 264 slots leave 12 groups after two waves.
  EXPECT_EQ(group_tail_y0(2160, 4, 264), 2112);
  // 1080p: 270 groups, 6 past one wave.
  EXPECT_EQ(group_tail_y0(1080, 4, 264), 1056);
  // A partial last group counts as a group: 541 groups.
  EXPECT_EQ(group_tail_y0(2161, 4, 264), 2112);
  // Whole waves, or fewer groups than slots: no tail, the height rounded
  // up to whole groups.
  EXPECT_EQ(group_tail_y0(2 * 264 * 4, 4, 264), 2 * 264 * 4);
  EXPECT_EQ(group_tail_y0(264 * 4, 4, 264), 264 * 4);
  EXPECT_EQ(group_tail_y0(100, 4, 264), 100);
  EXPECT_EQ(group_tail_y0(101, 4, 264), 104);
  // A row a block, or no slots known: no tail.
  EXPECT_EQ(group_tail_y0(2160, 1, 264), 2160);
  EXPECT_EQ(group_tail_y0(2160, 4, 0), 2160);
  // Pairs of rows.
  EXPECT_EQ(group_tail_y0(2160, 2, 264), 4 * 264 * 2);
}

// ---- BackgroundSmooth's sums -------------------------------------------------

EyeShifts shifts(float s0, float s1) { return EyeShifts{{s0, s1}}; }

// R = 1 + floor(|s| D / 2): shift 0.5 and D = 4 (R - 1) give R.
float d_for_radius(int R) { return 4.f * (R - 1); }

TEST(WarpPlanSmooth, RadiiAndTiles) {
  const SmoothPlan p = plan_smooth(shifts(0.5f, -0.5f), d_for_radius(29), 3840, 2160, kOptin);
  EXPECT_EQ(p.radius[0], 29);
  EXPECT_EQ(p.radius[1], 29);
  EXPECT_TRUE(p.narrow);
  EXPECT_TRUE(p.staged);
  EXPECT_EQ(p.tile_rows, 16);
  EXPECT_EQ(p.tiles_x, 120);
  EXPECT_EQ(p.tiles_y, 135);
  EXPECT_EQ(p.tiles(), 2u * 120 * 135);
  const int Rx = smooth_fill_radius_x(29);
  EXPECT_EQ(p.smem, smooth_tile_v_bytes(true, Rx, 16) + smooth_tile_copy_bytes(29, Rx, 16));
  // Partial tiles at the right and bottom edges.
  const SmoothPlan q = plan_smooth(shifts(0.5f, -0.5f), d_for_radius(29), 33, 17, kOptin);
  EXPECT_EQ(q.tiles_x, 2);
  EXPECT_EQ(q.tiles_y, 2);
}

TEST(WarpPlanSmooth, TileRowsAtTheShortWindowLimit) {
  EXPECT_EQ(plan_smooth(shifts(0.5f, -0.5f), d_for_radius(kSmoothShortR), 3840, 2160, kOptin).tile_rows, 16);
  EXPECT_EQ(plan_smooth(shifts(0.5f, -0.5f), d_for_radius(kSmoothShortR + 1), 3840, 2160, kOptin).tile_rows,
            kSmoothTileRowsMax);
}

TEST(WarpPlanSmooth, NarrowSumsAtTheirLimit) {
  EXPECT_TRUE(plan_smooth(shifts(0.5f, -0.5f), d_for_radius(kSmoothNarrowRMax), 7680, 4320, kOptin).narrow);
  EXPECT_FALSE(plan_smooth(shifts(0.5f, -0.5f), d_for_radius(kSmoothNarrowRMax + 1), 7680, 4320, kOptin).narrow);
  // Only warped eyes count: an eye with shift 0 is copied, whatever its R.
  const SmoothPlan one = plan_smooth(shifts(0.f, -0.5f), d_for_radius(kSmoothNarrowRMax), 7680, 4320, kOptin);
  EXPECT_TRUE(one.narrow);
  EXPECT_EQ(one.radius[1], kSmoothNarrowRMax);
  const SmoothPlan both = plan_smooth(shifts(1.f, -0.5f), d_for_radius(kSmoothNarrowRMax), 7680, 4320, kOptin);
  EXPECT_FALSE(both.narrow);  // eye 0's R is 2 R - 1
}

TEST(WarpPlanSmooth, WideWindowsShortenTheTiles) {
  // The largest window (|s| D = 2048, R = 1025): V of 544 columns of 20
  // bytes holds 6 rows in 64 KB.
  const SmoothPlan p = plan_smooth(shifts(1.f, -1.f), 2048.f, 8192, 8192, kOptin);
  EXPECT_EQ(p.radius[0], 1025);
  EXPECT_FALSE(p.narrow);
  EXPECT_EQ(static_cast<size_t>(p.tile_rows),
            65536 / (smooth_tile_columns(smooth_fill_radius_x(1025)) * kSmoothWidePixelBytes));
  EXPECT_EQ(p.tile_rows, 6);
  EXPECT_LE(smooth_tile_v_bytes(false, smooth_fill_radius_x(1025), p.tile_rows), 65536u);
  // Its copy (2R + 6 rows) does not fit beside V: the walks read global
  // memory.
  EXPECT_FALSE(p.staged);
  EXPECT_EQ(p.smem, smooth_tile_v_bytes(false, smooth_fill_radius_x(1025), 6));
}

TEST(WarpPlanSmooth, StagedExactlyWhereTheCopyFits) {
  const int R = 58, Rx = smooth_fill_radius_x(R), S = kSmoothTileRowsMax;
  const size_t v = smooth_tile_v_bytes(true, Rx, S), copy = smooth_tile_copy_bytes(R, Rx, S);
  const int fits = static_cast<int>(v + copy + 64);
  SmoothPlan p = plan_smooth(shifts(0.5f, -0.5f), d_for_radius(R), 7680, 4320, fits);
  EXPECT_TRUE(p.staged);
  EXPECT_EQ(p.smem, v + copy);
  EXPECT_LE(p.smem + 64, static_cast<size_t>(fits));
  p = plan_smooth(shifts(0.5f, -0.5f), d_for_radius(R), 7680, 4320, fits - 1);
  EXPECT_FALSE(p.staged);
  EXPECT_EQ(p.smem, v);
}

TEST(WarpPlanSmooth, NarrowSumsLayout) {
  // Wide V: a SmoothSum a pixel. Narrow V: two channel words a pixel, then
  // 16-bit counts, each part 16-byte aligned.
  EXPECT_EQ(smooth_v_bytes(false, 10), align16(10 * sizeof(SmoothSum)));
  EXPECT_EQ(smooth_v_bytes(true, 10), align16(80) + align16(20));
  EXPECT_EQ(kSmoothNarrowPixelBytes, 10u);
  EXPECT_EQ(smooth_tile_columns(7), kSmoothTileW + 14);
  EXPECT_EQ(smooth_tile_copy_pixels(5, 1, 16), 34u * 26);
  EXPECT_EQ(smooth_tile_copy_bytes(5, 1, 16), 34u * 26 * 5 + 3u * 26);
}

TEST(WarpPlanSmooth, BlockSize) {
  // Shared memory bounds the tiles (8K: 3 an SM either way): 512 threads,
  // and the register-bound twin gains nothing.
  SmoothThreads t = choose_smooth_threads(3, 3, 3);
  EXPECT_EQ(t.threads, kSmoothTileThreadsMax);
  EXPECT_FALSE(t.tight);
  // Registers bound them (4K: 6 tiles of 256, 3 of 512, 8 of the twin):
  // the twin.
  t = choose_smooth_threads(6, 3, 8);
  EXPECT_EQ(t.threads, kSmoothTileThreads);
  EXPECT_TRUE(t.tight);
  // The twin holding no more threads than the loose kernel: 256 loose.
  t = choose_smooth_threads(6, 3, 6);
  EXPECT_EQ(t.threads, kSmoothTileThreads);
  EXPECT_FALSE(t.tight);
}

// ---- The fused anaglyph's patch grid -----------------------------------------

TEST(WarpPlanPatch, OneWaveAtMost) {
  EXPECT_EQ(patch_resident_blocks(132, 2048), 132 * (2048 / kPatchThreads));
  EXPECT_EQ(patch_resident_blocks(0, 2048), 1);
  EXPECT_EQ(patch_resident_blocks(4, 128), 1);
  SmoothPlan plan{};
  plan.tile_rows = 16;
  plan.tiles_x = 120;
  plan.tiles_y = 135;
  // Every tile listed and a tail: more items than a wave, so one wave.
  EXPECT_EQ(patch_blocks(plan, 3840, 2160, 2112, 1056), 1056u);
  // A tiny frame: as many blocks as its items need.
  plan.tiles_x = 1;
  plan.tiles_y = 1;
  const size_t items = (2 * 16 * kSmoothTileW + 0) / kPatchPerThread;
  EXPECT_EQ(patch_blocks(plan, 32, 16, 16, 1056), items / kPatchThreads + 1);
}

}  // namespace
}  // namespace warp_detail
}  // namespace p3d

namespace p3d {
namespace warp_detail {
namespace {

// ---- 16-bit pictures ---------------------------------------------------------

constexpr size_t kDeepPixel = sizeof(Rgba16);

// The source row starts on its pixels' alignment after the keys; 8-bit
// rows keep their layout (4-byte keys end on a pixel).
TEST(WarpPlanDeep, RowLayoutAlignsTheSixteenBitRow) {
  EXPECT_EQ(row_smem_bytes(97, 4, 1, kDeepPixel), 392u + 97u * 8 + 4u * 8);  // 388 key bytes padded to 392
  EXPECT_EQ(row_smem_bytes(97, 4, 1), 388u + 97u * 4 + 4u * 8);
  EXPECT_EQ(row_smem_bytes(3840, 4, 2, kDeepPixel), 2u * 3840 * 4 + 3840u * 8 + 2u * 120 * 8);
  EXPECT_EQ(together_smem_bytes(3840, 4, kDeepPixel), row_smem_bytes(3840, 4, 2, kDeepPixel) + 3u * 3840 * 8);
  // Half as wide a row fits at 8 bytes a converted pixel.
  EXPECT_TRUE(row_fits(27000, 0, kOptin, kDeepPixel));
  EXPECT_FALSE(row_fits(29000, 0, kOptin, kDeepPixel));
  EXPECT_TRUE(row_fits(54000, 0, kOptin));
}

// A 16-bit frame takes the same kinds of row kernel as an 8-bit one, by
// the threads each holds with rows of 8-byte pixels. At 1080p RowsTogether
// blocks (77 KB) still hold as many threads as a row's block. At 4K both
// z-buffers beside a 16-bit row (61 KB) leave room for a row's block fewer
// (1536 threads, where the eyes in turn hold 2048) and a RowsTogether
// block (154 KB) for one a SM, but two WideGroup blocks hold 2048: the
// rows of a cell go through one scatter in WideGroup blocks.
TEST(WarpPlanDeep, RowKernelsOfSixteenBitRows) {
  const RowKernelChoice c =
      choose_row_kernels(HoleFill::BackgroundSmooth, 1920, kOptin, modelled_residency(1920, kDeepPixel), kDeepPixel);
  EXPECT_EQ(c.pixel_bytes, kDeepPixel);
  EXPECT_TRUE(c.both_eyes);
  EXPECT_TRUE(c.groups);
  EXPECT_TRUE(c.rows_together);
  RowFrame f;
  f.W = 1920;
  f.H = 1080;
  f.narrow_keys = f.both_warped = true;
  f.depth_shift = 2;
  f.smem_optin = kOptin;
  f.pixel_bytes = kDeepPixel;
  const RowPlan p = plan_rows(f, c);
  EXPECT_EQ(p.keys, KeyPlace::NarrowSharedPerEye);
  EXPECT_EQ(p.group_rows, 4);
  EXPECT_TRUE(p.rows_together);
  EXPECT_EQ(p.smem, together_smem_bytes(1920, 4, kDeepPixel));

  const RowKernelResidency r = modelled_residency(3840, kDeepPixel);
  EXPECT_EQ(r.in_turn, 2048);
  EXPECT_EQ(r.both, 1536);
  EXPECT_EQ(r.together, 1024);
  EXPECT_EQ(r.wide, 2048);
  const RowKernelChoice uhd = choose_row_kernels(HoleFill::BackgroundSmooth, 3840, kOptin, r, kDeepPixel);
  EXPECT_FALSE(uhd.both_eyes);
  EXPECT_TRUE(uhd.groups);
  EXPECT_TRUE(uhd.wide_groups);
  EXPECT_FALSE(uhd.rows_together);
  EXPECT_EQ(uhd.wide_group_threads, kWideBlock);
  f.W = 3840;
  f.H = 2160;
  const RowPlan q = plan_rows(f, uhd);
  EXPECT_EQ(q.keys, KeyPlace::NarrowSharedPerEye);
  EXPECT_EQ(q.group_rows, 4);
  EXPECT_TRUE(q.wide_groups);
  EXPECT_EQ(q.smem, row_smem_bytes(3840, sizeof(NarrowKeys::Word), 2, kDeepPixel));
}

TEST(WarpPlanDeep, SmoothSumsAreWide) {
  const SmoothPlan p = plan_smooth(shifts(0.5f, -0.5f), d_for_radius(29), 3840, 2160, kOptin, kDeepPixel);
  EXPECT_FALSE(p.narrow);
  const int Rx = smooth_fill_radius_x(29);
  EXPECT_EQ(smooth_tile_v_bytes(false, Rx, p.tile_rows, kDeepPixel),
            align16(static_cast<size_t>(smooth_tile_columns(Rx)) * p.tile_rows * sizeof(SmoothSum16)));
  const size_t copy = smooth_tile_copy_bytes(29, Rx, p.tile_rows, kDeepPixel);
  EXPECT_EQ(p.smem, smooth_tile_v_bytes(false, Rx, p.tile_rows, kDeepPixel) + (p.staged ? copy : 0));
  EXPECT_LE(p.smem + 64, static_cast<size_t>(kOptin));
  EXPECT_EQ(smooth_bytes_per_pixel(kDeepPixel), 9u);
}

}  // namespace
}  // namespace warp_detail
}  // namespace p3d
