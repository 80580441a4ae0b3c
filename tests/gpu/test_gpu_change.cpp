// The adaptive bookkeeping on the device (cuda/change_gpu.h) against
// common/change_map.h, and the adaptive kernels against their full runs.
// What the tests prove:
//  * FrameHistoryGpu flags the tiles FrameHistory flags, frame after frame
//    (unchanged frames, one byte, a box, small noise that adds up under a
//    tolerance, a new picture, a new size), in every format, on frames
//    with odd sizes and unaligned rows, at tolerances 0, 1.5 and 8;
//  * mark_grid_changes_gpu marks compare_grids' tiles, and dilate_gpu is
//    ChangeMap::dilated, for cells and reaches of several sizes;
//  * KeptOutputGpu: an unchanged frame gets the kept output, byte for
//    byte; a changed one runs; a frame that changed every tile is not kept
//    (the next unchanged frame is computed again); `whole` runs the frame;
//    the warp's rows are ChangeMap::rows_within at its reach, and the warp
//    rendering only those rows gives a whole frame's bytes;
//  * the depth estimator with tile flags and the filter with dirty tiles
//    and a kept output give, frame after frame, the bytes of their full
//    runs (the elements' adaptive runs, the warp's and the pack's gates
//    included: test_gpu_elements.cpp, GpuAdaptive).
#include <algorithm>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "adaptive.h"
#include "bars.h"
#include "bilateral_gpu.h"
#include "change_gpu.h"
#include "change_map.h"
#include "depth_estimate_gpu.h"
#include "gpu_util.h"
#include "pack_gpu.h"
#include "test_data.h"
#include "warp_gpu.h"

namespace p3d {
namespace {

using test::DeviceDepth;
using test::DeviceFrame;
using test::check_cuda;
using test::format_name;

std::string tiles_text(const ChangeMap &m) {
  std::string s;
  for (int ty = 0; ty < m.tiles_y(); ++ty) {
    for (int tx = 0; tx < m.tiles_x(); ++tx) s += m.tile(tx, ty) ? '#' : '.';
    s += '/';
  }
  return s;
}

::testing::AssertionResult same_tiles(const ChangeMap &got, const ChangeMap &want) {
  bool same = got.width() == want.width() && got.height() == want.height();
  for (int ty = 0; same && ty < want.tiles_y(); ++ty)
    for (int tx = 0; same && tx < want.tiles_x(); ++tx) same = got.tile(tx, ty) == want.tile(tx, ty);
  if (same) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << tiles_text(got) << "\nwant " << tiles_text(want);
}

cv::Mat picture(int w, int h, uint32_t seed) {
  cv::Mat bgr(h, w, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(bgr, bgr, cv::Size(0, 0), 1.5);
  return bgr;
}

// A sequence of pictures: the same again, one pixel, a box, noise of one
// level over a region (it adds up under a tolerance), a new picture.
std::vector<cv::Mat> sequence(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<cv::Mat> out{picture(w, h, seed)};
  for (int k = 1; k < 16; ++k) {
    cv::Mat next = out.back().clone();
    switch (k % 6) {
      case 0: break;
      case 1: next.at<cv::Vec3b>(static_cast<int>(rng() % h), static_cast<int>(rng() % w))[0] ^= 0x40; break;
      case 2:
        cv::rectangle(next, cv::Rect(static_cast<int>(rng() % w), static_cast<int>(rng() % h), 9, 7),
                      cv::Scalar(rng() % 256, rng() % 256, rng() % 256), cv::FILLED);
        break;
      case 3:
      case 4: {
        const cv::Rect r(0, 0, w / 2, h / 2);
        cv::Mat roi = next(r);
        cv::add(roi, cv::Scalar(1, 1, 1), roi);
        break;
      }
      default: next = picture(w, h, seed + 100 + k); break;
    }
    out.push_back(next);
  }
  return out;
}

TEST(GpuChange, FrameHistoryFlagsTheTilesTheCpuFlags) {
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420, PixelFormat::RGBA, PixelFormat::BGRx})
    for (const cv::Size size : {cv::Size(97, 45), cv::Size(160, 96), cv::Size(33, 65)})
      for (float tolerance : {0.f, 1.5f, 8.f})
        for (bool unaligned : {false, true}) {
          FrameHistory cpu;
          FrameHistoryGpu gpu;
          ChangeMapGpu map;
          const std::vector<cv::Mat> frames = sequence(size.width, size.height, 3);
          for (size_t k = 0; k <= frames.size(); ++k) {
            // The last frame is of another size: every tile again.
            const cv::Mat bgr = k < frames.size() ? frames[k] : picture(size.width + 2, size.height, 9);
            const HostFrame host = HostFrame::from_bgr(bgr, f);
            const DeviceFrame dev = unaligned ? DeviceFrame::upload_at(host, 3, 5) : DeviceFrame::upload(host);
            const ChangeMap want = cpu.compare(host.view(), tolerance);
            check_cuda(gpu.compare(dev.view(), tolerance, map, nullptr));
            ChangeMap got;
            check_cuda(map.download(&got, nullptr));
            EXPECT_TRUE(same_tiles(got, want)) << format_name(f) << " " << size.width << "x" << size.height
                                               << " tolerance " << tolerance << (unaligned ? " unaligned" : "")
                                               << " frame " << k;
          }
        }
}

TEST(GpuChange, GridChangesAndDilationMatchTheCpu) {
  std::mt19937 rng(5);
  for (int shift : {0, 1, 2, 3, 6})
    for (const cv::Size size : {cv::Size(97, 45), cv::Size(300, 170)}) {
      const int cw = grid_cells(size.width, shift), ch = grid_cells(size.height, shift);
      cv::Mat a(ch, cw, CV_32FC1);
      cv::randu(a, 0.f, 1.f);
      for (int k = 0; k < 8; ++k) {
        cv::Mat b = a.clone();
        for (int c = 0; c < k % 4; ++c) b.at<float>(static_cast<int>(rng() % ch), static_cast<int>(rng() % cw)) += 1.f;
        DeviceDepth da(size.width, size.height, shift), db(size.width, size.height, shift);
        check_cuda(CudaStatus{cudaMemcpy2D(da.view().data, da.view().pitch, a.data, a.step, cw * 4, ch,
                                           cudaMemcpyHostToDevice)});
        check_cuda(CudaStatus{cudaMemcpy2D(db.view().data, db.view().pitch, b.data, b.step, cw * 4, ch,
                                           cudaMemcpyHostToDevice)});
        const DepthGrid<const float> ha{ImageView<const float>{reinterpret_cast<const float *>(a.data), cw, ch, a.step},
                                        size.width, size.height, shift};
        const DepthGrid<const float> hb{ImageView<const float>{reinterpret_cast<const float *>(b.data), cw, ch, b.step},
                                        size.width, size.height, shift};
        ChangeMapGpu map, dilated;
        check_cuda(map.resize(size.width, size.height));
        check_cuda(map.fill(false, nullptr));
        check_cuda(mark_grid_changes_gpu(as_const(da.grid()), as_const(db.grid()), map, nullptr));
        ChangeMap got;
        check_cuda(map.download(&got, nullptr));
        const ChangeMap want = compare_grids(ha, hb);
        EXPECT_TRUE(same_tiles(got, want)) << "shift " << shift << " case " << k;
        for (const cv::Point reach : {cv::Point(0, 0), cv::Point(5, 1), cv::Point(33, 64), cv::Point(200, 7)}) {
          check_cuda(dilate_gpu(map, reach.x, reach.y, dilated, nullptr));
          ChangeMap got_dilated;
          check_cuda(dilated.download(&got_dilated, nullptr));
          EXPECT_TRUE(same_tiles(got_dilated, want.dilated(reach.x, reach.y)))
              << "shift " << shift << " reach " << reach.x << "," << reach.y;
        }
      }
      // Another geometry: every tile.
      DeviceDepth da(size.width, size.height, shift), other(size.width, size.height, shift + 1);
      ChangeMapGpu map;
      check_cuda(map.resize(size.width, size.height));
      check_cuda(map.fill(false, nullptr));
      check_cuda(mark_grid_changes_gpu(as_const(da.grid()), as_const(other.grid()), map, nullptr));
      ChangeMap got;
      check_cuda(map.download(&got, nullptr));
      EXPECT_TRUE(got.all());
    }
}

// The frame a gated "stage" writes: its seed's bytes when it runs.
HostFrame stage_output(PixelFormat f, int w, int h, uint32_t seed) {
  HostFrame out(f, w, h);
  out.fill_random(seed);
  return out;
}

// Whether two frames of one format and size hold the same visible bytes.
bool same_bytes(const HostFrame &a, const HostFrame &b) {
  const FrameView x = a.view(), y = b.view();
  if (x.format != y.format || x.width != y.width || x.height != y.height) return false;
  for (int p = 0; p < frame_plane_count(x.format); ++p) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(x.format, x.width, x.height, p, &row_bytes, &rows);
    for (int r = 0; r < rows; ++r)
      if (std::memcmp(x.plane[p] + static_cast<size_t>(r) * x.stride[p], y.plane[p] + static_cast<size_t>(r) * y.stride[p],
                      static_cast<size_t>(row_bytes)) != 0)
        return false;
  }
  return true;
}

// KeptOutputGpu's rule, with a copy standing in for a stage's kernels
// (copy_rows_gated: runs only when the gate is open).
TEST(GpuChange, KeptOutputRunsKeepsAndRestores) {
  for (PixelFormat f : {PixelFormat::RGBA, PixelFormat::NV12, PixelFormat::I420}) {
    const int w = 70, h = 45;
    KeptOutputGpu kept;
    ChangeMapGpu changes;
    check_cuda(changes.resize(w, h));
    // flags: 0 none, 1 one tile, 2 all. whole: the parameters changed.
    struct Step {
      int flags;
      bool whole;
      bool runs;
    };
    // The first frame runs and is kept; unchanged frames restore; a frame
    // that changed every tile runs and is not kept, so the next unchanged
    // one runs; whole runs.
    const std::vector<Step> steps = {{2, false, true},  {0, false, false}, {1, false, true}, {0, false, false},
                                     {2, false, true},  {0, false, true},  {0, false, false}, {0, true, true},
                                     {0, false, false}};
    HostFrame last;
    for (size_t k = 0; k < steps.size(); ++k) {
      check_cuda(changes.fill(steps[k].flags == 2, nullptr));
      if (steps[k].flags == 1) check_cuda(CudaStatus{cudaMemset(changes.data() + 1, 1, 1)});
      const HostFrame fresh = stage_output(f, w, h, 40 + static_cast<uint32_t>(k));
      const DeviceFrame src = DeviceFrame::upload(fresh);
      DeviceFrame out = DeviceFrame::upload(stage_output(f, w, h, 999));  // a pool buffer's old bytes
      const FrameView o = out.view(), s = src.view();
      check_cuda(kept.decide(changes, o, steps[k].whole, nullptr));
      for (int p = 0; p < frame_plane_count(f); ++p) {
        int row_bytes = 0, rows = 0;
        frame_plane_size(f, w, h, p, &row_bytes, &rows);
        check_cuda(copy_rows_gated(o.plane[p], o.stride[p], s.plane[p], s.stride[p], row_bytes, rows, kept.gate(),
                                   nullptr));
      }
      check_cuda(kept.finish(o, nullptr));
      const HostFrame got = out.download();
      const HostFrame &want = steps[k].runs ? fresh : last;
      EXPECT_TRUE(same_bytes(got, want)) << format_name(f) << " step " << k << (steps[k].runs ? " runs" : " keeps");
      last = got;
    }
    // An output of another size with no tile changed: what is kept does
    // not fit it, so the frame runs (and nothing is copied out of bounds).
    const HostFrame wider = stage_output(f, w + 30, h, 77);
    const DeviceFrame src = DeviceFrame::upload(wider);
    DeviceFrame out = DeviceFrame::upload(stage_output(f, w + 30, h, 998));
    check_cuda(changes.fill(false, nullptr));
    check_cuda(kept.decide(changes, out.view(), false, nullptr));
    EXPECT_FALSE(kept.gate().state == nullptr);
    const FrameView o = out.view(), s = src.view();
    for (int p = 0; p < frame_plane_count(f); ++p) {
      int row_bytes = 0, rows = 0;
      frame_plane_size(f, w + 30, h, p, &row_bytes, &rows);
      check_cuda(copy_rows_gated(o.plane[p], o.stride[p], s.plane[p], s.stride[p], row_bytes, rows, kept.gate(),
                                 nullptr));
    }
    check_cuda(kept.finish(o, nullptr));
    EXPECT_TRUE(same_bytes(out.download(), wider)) << format_name(f) << ": another size runs";
  }
}

// The rows KeptOutputGpu::decide marks for the warp: ChangeMap::rows_within
// of the flags at the reach, every row on the first frame and with
// `whole`; the share counts the rows the changes reach either way.
TEST(GpuChange, KeptOutputRowsAreTheRowsWithinTheReach) {
  std::mt19937 rng(16);
  for (const cv::Size sz : {cv::Size(70, 45), cv::Size(33, 300), cv::Size(1920, 1080), cv::Size(64, 8192)}) {
    KeptOutputGpu kept;
    ChangeMapGpu changes;
    check_cuda(changes.resize(sz.width, sz.height));
    const DeviceFrame out = DeviceFrame::upload(stage_output(PixelFormat::RGBA, 8, 8, 1));
    int step = 0;
    for (const int reach : {0, 1, 15, 31, 32, 100, sz.height})
      for (const double p : {0.0, 0.01, 0.2})
        for (const bool whole : {false, true}) {
          ChangeMap m(sz.width, sz.height, false);
          std::vector<uint8_t> flags(changes.tiles());
          for (int ty = 0; ty < m.tiles_y(); ++ty)
            for (int tx = 0; tx < m.tiles_x(); ++tx)
              if (std::uniform_real_distribution<double>(0, 1)(rng) < p) {
                m.mark(tx, ty);
                flags[static_cast<size_t>(ty) * m.tiles_x() + tx] = 1;
              }
          check_cuda(CudaStatus{cudaMemcpy(changes.data(), flags.data(), flags.size(), cudaMemcpyHostToDevice)});
          check_cuda(kept.decide(changes, out.view(), whole, nullptr, reach));
          check_cuda(CudaStatus{cudaDeviceSynchronize()});
          const StageGate gate = kept.gate();
          ASSERT_NE(gate.rows, nullptr);
          std::vector<uint8_t> rows(static_cast<size_t>(sz.height));
          check_cuda(CudaStatus{cudaMemcpy(rows.data(), gate.rows, rows.size(), cudaMemcpyDeviceToHost)});
          const std::vector<uint8_t> within = m.rows_within(reach);
          const bool every_row = whole || step == 0;
          EXPECT_EQ(rows, every_row ? std::vector<uint8_t>(rows.size(), 1) : within)
              << sz.width << "x" << sz.height << " reach " << reach << " share " << p << (whole ? " whole" : "");
          const double reached = static_cast<double>(std::count(within.begin(), within.end(), 1));
          EXPECT_DOUBLE_EQ(kept.last_rows_share(), reached / sz.height);
          ++step;
        }
    // Without a reach the gate has no rows.
    check_cuda(kept.decide(changes, out.view(), false, nullptr));
    EXPECT_EQ(kept.gate().rows, nullptr);
  }
}

// A depth map of near and far boxes on a slope, which leaves holes for
// the fills (the same for every frame unless a test changes it).
cv::Mat boxes_depth(int w, int h, uint32_t seed) {
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = 0.2f + 0.3f * y / h;
  std::mt19937 rng(seed);
  for (int k = 0; k < 12; ++k) {
    const cv::Rect r(static_cast<int>(rng() % w), static_cast<int>(rng() % h), 4 + static_cast<int>(rng() % (w / 4)),
                     4 + static_cast<int>(rng() % (h / 4)));
    d(r & cv::Rect(0, 0, w, h)).setTo(0.5f + 0.5f * static_cast<float>(rng() % 100) / 100.f);
  }
  return d;
}

// The adaptive warp on the device renders only the rows its changes reach
// (the gate's rows, KeptOutputGpu::decide at warp_rows_reach) into the
// pair it keeps, and packs the whole pair: each frame equals a fresh
// renderer's whole frame, with the source or the depth changed in a band
// of rows (the top and bottom rows among them), a new picture and then an
// unchanged frame (run because nothing was kept, its rows none), for the
// fills that keep rows, layouts packed from the pair, the pair itself and
// the anaglyph (fused at 4K, where the depth is on 4 x 4 cells and rows
// are rendered together). A last frame changes a band the map does not
// mark, far from the one it marks: its rows must be left out (the output
// then keeps their old bytes), except where every row is rendered (the
// pair as the output, the anaglyph that may fuse).
TEST(GpuChange, WarpRowsRenderOnlyTheRowsTheChangesReach) {
  const PackLayout layouts[] = {PackLayout::SideBySideHalf, PackLayout::TopBottomHalf, PackLayout::SideBySide,
                                PackLayout::Anaglyph};
  for (const cv::Size size : {cv::Size(200, 120), cv::Size(1280, 720), cv::Size(3840, 2160)})
    for (const HoleFill fill : {HoleFill::BackgroundSmooth, HoleFill::None, HoleFill::Background})
      for (const PackLayout layout : layouts) {
        // 4K: the rows-together kernels with both their packs (fused for
        // the anaglyph), BackgroundSmooth only (the others take the same
        // row gate at the other sizes).
        if (size.width >= 3840 &&
            (fill != HoleFill::BackgroundSmooth || (layout != PackLayout::SideBySideHalf && layout != PackLayout::Anaglyph)))
          continue;
        SCOPED_TRACE(::testing::Message() << size.width << "x" << size.height << " fill " << static_cast<int>(fill)
                                          << " layout " << static_cast<int>(layout));
        const WarpParams wp = test::warp_params(8.f, 0.5f, StereoView::Both, fill);
        const PackParams pp = test::pack_params(layout);
        const PixelFormat out_format = layout == PackLayout::SideBySideHalf ? PixelFormat::I420 : PixelFormat::RGBA;
        const int shift = size.width >= 3840 ? 2 : 0;  // the filter's automatic cells at 4K
        int ow = 0, oh = 0;
        pack_size(layout, size.width, size.height, &ow, &oh);
        const int reach = warp_rows_reach(wp, size.width, size.height);
        WarpRendererGpu adaptive;
        KeptOutputGpu kept;
        ChangeMapGpu changes;
        check_cuda(changes.resize(size.width, size.height));
        cv::Mat bgr = picture(size.width, size.height, 21), depth = boxes_depth(size.width, size.height, 22);
        std::mt19937 rng(23);
        double rows_share = 0;
        const int bh = 5, last = 9;
        for (int k = 0; k <= last; ++k) {
          ChangeMap map(size.width, size.height, k == 0 || k == 6);
          auto band = [&](int y) { return cv::Rect(static_cast<int>(rng() % (size.width - 20)), y, 20, bh); };
          auto mark = [&](const cv::Rect &r) { map.mark_pixels(PixelRect{r.x, r.y, r.x + r.width, r.y + r.height}); };
          if (k == 6) {
            bgr = picture(size.width, size.height, 24);
          } else if (k == last) {  // the top band marked, one near the bottom not
            const cv::Rect top = band(0), bottom = band(size.height - 4 * bh);
            bgr(top).setTo(cv::Scalar(10, 200, 30));
            bgr(bottom).setTo(cv::Scalar(250, 20, 90));
            mark(top);
          } else if (k > 0 && k != 7) {  // a band of rows: the first, the last, or anywhere
            const int y = k % 3 == 1   ? 0
                          : k % 3 == 2 ? size.height - bh
                                       : static_cast<int>(rng() % static_cast<unsigned>(size.height - bh));
            const cv::Rect r = band(y);
            if (k % 2)
              bgr(r).setTo(cv::Scalar(rng() % 256, rng() % 256, rng() % 256));
            else
              depth(r).setTo(0.9f);
            mark(r);
          }
          std::vector<uint8_t> flags(changes.tiles());
          for (int ty = 0; ty < map.tiles_y(); ++ty)
            for (int tx = 0; tx < map.tiles_x(); ++tx)
              flags[static_cast<size_t>(ty) * map.tiles_x() + tx] = map.tile(tx, ty);
          check_cuda(CudaStatus{cudaMemcpy(changes.data(), flags.data(), flags.size(), cudaMemcpyHostToDevice)});
          const DeviceFrame src = DeviceFrame::upload(HostFrame::from_bgr(bgr, PixelFormat::RGBA));
          const DeviceDepth d = DeviceDepth::upload_grid(depth, shift);
          // A pool buffer's old bytes.
          DeviceFrame out = DeviceFrame::upload(stage_output(out_format, ow, oh, 900 + k));
          bool fused = false;
          check_cuda(kept.decide(changes, out.view(), false, nullptr, reach));
          check_cuda(adaptive.render_packed(wp, pp, src.view(), YuvToRgb{}, as_const(d.grid()), out.view(), nullptr,
                                            &fused, kept.gate()));
          check_cuda(kept.finish(out.view(), nullptr));
          check_cuda(CudaStatus{cudaDeviceSynchronize()});
          if (k > 0 && k != 6) rows_share += kept.last_rows_share();
          WarpRendererGpu whole;
          DeviceFrame want = DeviceFrame::upload(stage_output(out_format, ow, oh, 800 + k));
          check_cuda(whole.render_packed(wp, pp, src.view(), YuvToRgb{}, as_const(d.grid()), want.view(), nullptr));
          // The pair is the output, or an anaglyph the row kernel may fuse
          // (render_packed: every row whether it fuses or not).
          const bool every_row = layout == PackLayout::SideBySide || layout == PackLayout::Anaglyph;
          (void)fused;
          if (k < last || every_row)
            EXPECT_TRUE(same_bytes(out.download(), want.download())) << "frame " << k;
          else
            EXPECT_FALSE(same_bytes(out.download(), want.download())) << "the unmarked band was rendered";
        }
        EXPECT_LT(rows_share / (last - 1), 0.5) << "the changes reached most rows: the test renders whole frames";
      }
}

// A copy of a device grid's cells (the same geometry).
DeviceDepth copy_of(const DeviceDepth &d) {
  const DepthGrid<float> g = d.grid();
  DeviceDepth c(g.width, g.height, g.shift);
  check_cuda(CudaStatus{cudaMemcpy2D(c.view().data, c.view().pitch, g.cells.data, g.cells.pitch,
                                     sizeof(float) * g.cells.width, g.cells.height, cudaMemcpyDeviceToDevice)});
  return c;
}

// Depth on its block grid and the filter on its cells, as the elements
// run them on CUDA memory, adaptive against full, over a sequence with
// unchanged frames, small changes, drift and cuts: the same bytes.
TEST(GpuChange, AdaptiveDepthAndFilterGiveTheFullRunsBytes) {
  for (const cv::Size size : {cv::Size(160, 96), cv::Size(1280, 720)})
    for (PixelFormat f : {PixelFormat::NV12, PixelFormat::RGBA}) {
      DepthParams dp;
      dp.temporal_smoothing = 0.4f;
      const DepthParams params = frame_scaled(dp, size.width, size.height);
      BilateralParams bp;
      bp.scale = size.height >= 720 ? 2 : 1;
      const BilateralParams filter = frame_scaled(bp, size.width, size.height);
      const int block_shift = block_grid_shift(params, size.width, size.height);
      const int cell_shift = bilateral_grid_shift(bilateral_sanitize(filter), size.width, size.height);
      DepthEstimatorGpu full_depth, adaptive_depth;
      BilateralFilterGpu full_filter, adaptive_filter;
      FrameHistoryGpu history;
      ChangeMapGpu changes, dirty;
      std::unique_ptr<DeviceDepth> prev_depth, prev_out;
      const int reach = bilateral_reach(filter, size.width, size.height);
      const std::vector<cv::Mat> frames = sequence(size.width, size.height, 11);
      for (size_t k = 0; k < frames.size(); ++k) {
        const DeviceFrame dev = DeviceFrame::upload(HostFrame::from_bgr(frames[k], f));
        DeviceDepth depth_a(size.width, size.height, block_shift), depth_b(size.width, size.height, block_shift);
        check_cuda(full_depth.estimate(params, dev.view(), depth_a.grid(), nullptr));
        check_cuda(history.compare(dev.view(), 0.f, changes, nullptr));
        const TileFlags flags = changes.flags();
        check_cuda(adaptive_depth.estimate(params, dev.view(), depth_b.grid(), nullptr, &flags));
        EXPECT_EQ(cv::norm(depth_a.download(), depth_b.download(), cv::NORM_INF), 0.0)
            << format_name(f) << " " << size.width << " frame " << k << ": depth";
        // The filter: the frame's changes and the depth's, within reach.
        if (prev_depth)
          check_cuda(mark_grid_changes_gpu(as_const(prev_depth->grid()), as_const(depth_b.grid()), changes, nullptr));
        check_cuda(dilate_gpu(changes, reach, reach, dirty, nullptr));
        DeviceDepth out_a(size.width, size.height, cell_shift), out_b(size.width, size.height, cell_shift);
        out_b.poison();
        check_cuda(full_filter.run(filter, dev.view(), as_const(depth_a.grid()), out_a.grid(), nullptr));
        check_cuda(adaptive_filter.run(filter, dev.view(), as_const(depth_b.grid()), out_b.grid(), nullptr,
                                       prev_out ? dirty.flags() : TileFlags{},
                                       prev_out ? as_const(prev_out->grid()) : DepthGrid<const float>{}));
        const cv::Mat a = out_a.download(), b = out_b.download();
        EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << format_name(f) << " " << size.width << " frame " << k
                                                     << ": filter";
        prev_depth = std::make_unique<DeviceDepth>(copy_of(depth_b));
        prev_out = std::make_unique<DeviceDepth>(copy_of(out_b));
      }
    }
}

}  // namespace
}  // namespace p3d
