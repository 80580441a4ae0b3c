// Unit tests of the CPU depth estimator (common/depth_estimate.h): known
// answers for every step, the temporal decisions, edge sizes and formats.
#include <cmath>
#include <cstring>
#include <queue>
#include <random>
#include <set>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "block_regions.h"
#include "depth_estimate.h"
#include "host_frame.h"
#include "test_data.h"

namespace p3d {
namespace {

using test::kAllFormats;

constexpr int kPad = 5;  // row padding of every test frame: stride != width * bpp

HostFrame solid(int w, int h, cv::Scalar bgr, PixelFormat f = PixelFormat::RGBA) {
  return HostFrame::from_bgr(cv::Mat(h, w, CV_8UC3, bgr), f, kPad);
}

// Depth output starts as NaN so a pixel the estimator skips fails all_finite().
cv::Mat nan_depth(int w, int h) { return cv::Mat(h, w, CV_32FC1, cv::Scalar(NAN)); }

bool all_finite(const cv::Mat &m) {
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x)
      if (!std::isfinite(m.at<float>(y, x))) return false;
  return true;
}

cv::Mat estimate(DepthEstimatorCpu &est, const DepthParams &p, const HostFrame &f, TemporalDecision *d = nullptr) {
  cv::Mat depth = nan_depth(f.width(), f.height());
  const TemporalDecision got = est.estimate(p, f.view(), depth_view_of(depth));
  if (d) *d = got;
  return depth;
}

bool identical(const cv::Mat &a, const cv::Mat &b) {
  return a.size() == b.size() && std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

// Hypothesis of a block centre from the spec's formula, in double.
double centre(int b, int B, int n) { return (b * B + std::min(B, n - b * B) / 2.0) / n; }
double quantised(double h) { return std::floor(h * 65535 + 0.5) / 65535; }

// Independent reference for step 2: breadth-first flood fill, labelling each
// component by its smallest block index (the first one met in index order).
// yuv: the features are Y'CbCr means (blocks_joined()).
std::vector<int> flood_labels(const std::vector<float> &f, int bx, int by, float thr, bool yuv = false) {
  std::vector<int> label(static_cast<size_t>(bx) * by, -1);
  for (int s = 0; s < bx * by; ++s) {
    if (label[s] >= 0) continue;
    std::queue<int> q;
    q.push(s);
    label[s] = s;
    while (!q.empty()) {
      const int k = q.front();
      q.pop();
      const int x = k % bx, y = k / bx;
      const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto &n : nb) {
        if (n[0] < 0 || n[1] < 0 || n[0] >= bx || n[1] >= by) continue;
        const int m = n[1] * bx + n[0];
        if (label[m] < 0 && blocks_joined(&f[k * 3], &f[m * 3], thr, yuv)) {
          label[m] = s;
          q.push(m);
        }
      }
    }
  }
  return label;
}

// ------------------------------------------------------------- features ---

TEST(DepthFeatures, MeansOfPartialBlocksRgba) {
  // 3x2 RGBA, B=2: block 0 = columns 0-1, block 1 = column 2 (partial).
  HostFrame f(PixelFormat::RGBA, 3, 2, kPad);
  const uint8_t r[2][3] = {{10, 20, 200}, {30, 41, 100}};
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) store_rgba(f.view(), x, y, Rgba{r[y][x], uint8_t(2 * x), 7, 255});
  std::vector<float> feat;
  block_features_cpu(f.view(), 2, feat);
  ASSERT_EQ(feat.size(), 6u);
  EXPECT_FLOAT_EQ(feat[0], (10 + 20 + 30 + 41) / 4.f);
  EXPECT_FLOAT_EQ(feat[1], (0 + 2 + 0 + 2) / 4.f);
  EXPECT_FLOAT_EQ(feat[2], 7.f);
  EXPECT_FLOAT_EQ(feat[3], 150.f);
  EXPECT_FLOAT_EQ(feat[4], 4.f);
  EXPECT_FLOAT_EQ(feat[5], 7.f);
}

TEST(DepthFeatures, YuvFeaturesAreNativeChannels) {
  for (PixelFormat fmt : {PixelFormat::NV12, PixelFormat::I420}) {
    HostFrame f(fmt, 4, 4, kPad);
    f.fill(0);
    const FrameView v = f.view();
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) v.plane[0][y * v.stride[0] + x] = static_cast<uint8_t>(16 * y + x);
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) {
        if (fmt == PixelFormat::NV12) {
          v.plane[1][y * v.stride[1] + 2 * x] = 90;
          v.plane[1][y * v.stride[1] + 2 * x + 1] = static_cast<uint8_t>(200 + x);
        } else {
          v.plane[1][y * v.stride[1] + x] = 90;
          v.plane[2][y * v.stride[2] + x] = static_cast<uint8_t>(200 + x);
        }
      }
    std::vector<float> feat;
    block_features_cpu(v, 4, feat);
    ASSERT_EQ(feat.size(), 3u) << test::format_name(fmt);
    EXPECT_FLOAT_EQ(feat[0], (16 * 6 * 4 + 6 * 4) / 16.f) << test::format_name(fmt);  // mean of 16y + x
    EXPECT_FLOAT_EQ(feat[1], 90.f) << test::format_name(fmt);
    EXPECT_FLOAT_EQ(feat[2], 200.5f) << test::format_name(fmt);
  }
}

// Step 1: every block's means are those of load_native3() summed over its
// pixels, for every format, odd and even sizes (partial blocks), odd and
// even block sizes, rows of many vectors; the adaptive call computes its
// subset of blocks and leaves the others as they were.
TEST(DepthFeatures, MeansAreThoseOfEveryPixelsNativeChannels) {
  const uint32_t seed = std::random_device{}();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  for (PixelFormat fmt : test::kAllFormats)
    for (int B : {2, 3, 4, 5, 8, 64})
      for (const auto &size : {std::pair<int, int>{37, 21}, {64, 32}, {2, 2}, {1, 5}, {131, 67}}) {
        HostFrame f(fmt, size.first, size.second, kPad);
        f.fill_random(rng());
        const FrameView v = f.view();
        const int bx = (v.width + B - 1) / B, by = (v.height + B - 1) / B;
        std::vector<uint8_t> only(static_cast<size_t>(bx) * by);
        for (uint8_t &o : only) o = rng() % 2;
        std::vector<float> all, some(static_cast<size_t>(bx) * by * 3, -1.f);
        block_features_cpu(v, B, all);
        block_features_cpu(v, B, some, &only);
        for (int j = 0; j < by; ++j)
          for (int i = 0; i < bx; ++i) {
            uint32_t sum[3] = {0, 0, 0};
            int n = 0;
            for (int y = j * B; y < std::min(v.height, (j + 1) * B); ++y)
              for (int x = i * B; x < std::min(v.width, (i + 1) * B); ++x, ++n) {
                int c[3];
                load_native3(v, x, y, c);
                for (int k = 0; k < 3; ++k) sum[k] += c[k];
              }
            const size_t b = static_cast<size_t>(j) * bx + i;
            for (int k = 0; k < 3; ++k) {
              ASSERT_EQ(all[3 * b + k], block_mean(sum[k], n))
                  << test::format_name(fmt) << " B=" << B << " block " << i << "," << j << " channel " << k;
              ASSERT_EQ(some[3 * b + k], only[b] ? block_mean(sum[k], n) : -1.f) << "the adaptive subset";
            }
          }
      }
}

// -------------------------------------------------------------- regions ---

TEST(DepthRegions, TwoFlatHalvesGiveTwoRegions) {
  cv::Mat bgr(32, 64, CV_8UC3, cv::Scalar(0, 0, 255));
  bgr.colRange(32, 64).setTo(cv::Scalar(255, 0, 0));
  const HostFrame f = HostFrame::from_bgr(bgr, PixelFormat::RGBA, kPad);
  DepthParams p;
  p.block_size = 4;
  DepthEstimatorCpu est;
  const cv::Mat depth = estimate(est, p, f);
  ASSERT_EQ(est.blocks_x(), 16);
  ASSERT_EQ(est.blocks_y(), 8);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 16; ++i) EXPECT_EQ(est.labels()[j * 16 + i], i < 8 ? 0 : 8) << i << "," << j;
  EXPECT_TRUE(all_finite(depth));
}

// ground_contact 0: the region's depth is the mean of its blocks' hq.
TEST(DepthRegions, UniformFrameIsOneRegionWithMeanHypothesis) {
  const int W = 40, H = 24, B = 4;  // 10 x 6 blocks
  DepthParams p;
  p.block_size = B;
  p.region_weight = 1.f;
  p.ground_contact = 0.f;
  DepthEstimatorCpu est;
  const cv::Mat depth = estimate(est, p, solid(W, H, cv::Scalar(40, 90, 160)));
  for (int l : est.labels()) EXPECT_EQ(l, 0);
  double mean = 0;
  for (int j = 0; j < 6; ++j) mean += std::floor(centre(j, B, H) * 65535 + 0.5);
  mean = mean / 6 / 65535;
  EXPECT_NEAR(mean, 0.5, 1e-9);  // the symmetric rows' hq sum to 65535 in pairs
  for (float b : est.block_depth()) EXPECT_NEAR(b, mean, 1e-6);
  // region_weight 0.75: b = 0.75 r + 0.25 h_q
  p.region_weight = 0.75f;
  DepthEstimatorCpu est2;
  const cv::Mat depth2 = estimate(est2, p, solid(W, H, cv::Scalar(40, 90, 160)));
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 10; ++i)
      EXPECT_NEAR(est2.block_depth()[j * 10 + i], 0.75 * mean + 0.25 * quantised(centre(j, B, H)), 1e-6);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) ASSERT_EQ(depth2.at<float>(y, x), est2.block_depth()[(y / B) * 10 + x / B]);
}

TEST(DepthRegions, EdgeThresholdZeroGivesOneRegionPerBlock) {
  HostFrame f(PixelFormat::BGRx, 37, 21, kPad);
  f.fill(77);  // even a uniform frame: L1 0 < 0 is false
  DepthParams p;
  p.block_size = 4;
  p.edge_threshold = 0.f;
  DepthEstimatorCpu est;
  const cv::Mat depth = estimate(est, p, f);
  const int bx = est.blocks_x(), by = est.blocks_y();
  ASSERT_EQ(bx, 10);
  ASSERT_EQ(by, 6);
  for (int k = 0; k < bx * by; ++k) {
    EXPECT_EQ(est.labels()[k], k);
    // A one-block region's mean is the block's own h_q, so b = h_q.
    EXPECT_NEAR(est.block_depth()[k], quantised(centre(k / bx, 4, 21)), 1e-6);
  }
  EXPECT_TRUE(all_finite(depth));
}

TEST(DepthRegions, LabelIsSmallestIndexOfComponent) {
  // 3x3 blocks: A B A / A B A / A A A; the right column of A reaches block 0
  // only through the bottom row, so a label-by-first-visit bug would show.
  const float A[3] = {10, 10, 10}, Bc[3] = {200, 10, 10};
  const bool isA[9] = {1, 0, 1, 1, 0, 1, 1, 1, 1};
  std::vector<float> feat;
  for (bool a : isA) feat.insert(feat.end(), a ? A : Bc, (a ? A : Bc) + 3);
  std::vector<int> labels;
  region_labels_cpu(feat, 3, 3, 24.f, false, labels);
  const std::vector<int> want = {0, 1, 0, 0, 1, 0, 0, 0, 0};
  EXPECT_EQ(labels, want);
}

TEST(DepthRegions, MatchesFloodFillOnRandomMazes) {
  std::mt19937 rng(std::random_device{}());
  for (int trial = 0; trial < 20; ++trial) {
    const int bx = 1 + rng() % 70, by = 1 + rng() % 50;
    // Two colours near the percolation threshold: long, branching regions.
    std::vector<float> feat;
    for (int k = 0; k < bx * by; ++k) {
      const float v = (rng() % 100) < 59 ? 20.f : 220.f;
      feat.insert(feat.end(), {v, v * 0.5f, 3.f});
    }
    std::vector<int> labels;
    region_labels_cpu(feat, bx, by, 24.f, false, labels);
    EXPECT_EQ(labels, flood_labels(feat, bx, by, 24.f)) << bx << "x" << by;
  }
}

// The edge test of whole tile rows at a time (several pairs a vector) is
// blocks_joined() pair by pair: features whose differences lie around the
// threshold, integer ones that meet it exactly, R'G'B' and Y'CbCr.
TEST(DepthRegions, EdgesNearTheThresholdAreBlocksJoined) {
  const uint32_t seed = std::random_device{}();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 8; ++trial)
    for (const bool yuv : {false, true}) {
      const int bx = 1 + rng() % 150, by = 1 + rng() % 40;
      std::vector<float> feat(3 * static_cast<size_t>(bx) * by);
      for (float &f : feat) f = trial % 2 ? static_cast<float>(100 + rng() % 17) : 100.f + (rng() % 1000) / 50.f;
      const float threshold = yuv ? 18.f : 24.f;
      BlockRegions regions;
      regions.label(feat, bx, by, threshold, yuv, nullptr);
      ASSERT_EQ(regions.labels(), flood_labels(feat, bx, by, threshold, yuv))
          << bx << "x" << by << (yuv ? " Y'CbCr" : " R'G'B'") << ", trial " << trial;
    }
}

// The largest threshold at which blocks_joined(a, b) is false: the pair's
// distance as blocks_joined computes it (found by bisection over the
// positive floats, whose bit patterns are ordered).
float joined_distance(const float *a, const float *b, bool yuv) {
  uint32_t lo = 0, hi = 0x7f800000u;  // blocks_joined(lo) false, blocks_joined(hi = +inf) true
  while (hi - lo > 1) {
    const uint32_t mid = lo + (hi - lo) / 2;
    float t;
    std::memcpy(&t, &mid, sizeof t);
    (blocks_joined(a, b, t, yuv) ? hi : lo) = mid;
  }
  float d;
  std::memcpy(&d, &lo, sizeof d);
  return d;
}

// Pairs whose distance is exactly the threshold (not joined) or one ulp
// under it (joined), in checkerboards of two features wide enough for the
// vector edge tests (joined_bits) and their scalar tail: every edge of the
// picture has that distance, so the labels are all blocks or one region.
// Any other order of the distance's float operations than blocks_joined's
// gives another distance for some of the random pairs, and other labels.
TEST(DepthRegions, EdgesExactlyAtTheThresholdAreBlocksJoined) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> level(0.f, 255.f);
  for (const bool yuv : {false, true})
    for (int pair = 0; pair < 48; ++pair) {
      float a[3], b[3];
      for (int c = 0; c < 3; ++c) {
        a[c] = level(rng);
        b[c] = level(rng);
      }
      const float d = joined_distance(a, b, yuv);
      const int bx = 67, by = 3;
      std::vector<float> feat(3 * static_cast<size_t>(bx) * by);
      for (int y = 0; y < by; ++y)
        for (int x = 0; x < bx; ++x)
          std::memcpy(&feat[3 * (static_cast<size_t>(y) * bx + x)], (x + y) % 2 ? b : a, sizeof a);
      for (const float threshold : {d, std::nextafter(d, INFINITY)}) {
        BlockRegions regions;
        regions.label(feat, bx, by, threshold, yuv, nullptr);
        ASSERT_EQ(regions.labels(), flood_labels(feat, bx, by, threshold, yuv))
            << (yuv ? "Y'CbCr" : "R'G'B'") << " pair " << pair << ", threshold " << threshold
            << (threshold == d ? " (the distance)" : " (an ulp over it)");
      }
    }
}

// Each region's statistics as a flood fill gives them, checked against
// BlockRegions at every region's label.
void expect_region_stats(const BlockRegions &regions, const std::vector<int> &want, const std::vector<uint32_t> &hq,
                         const std::string &where) {
  std::vector<uint64_t> sum(want.size(), 0);
  std::vector<uint32_t> count(want.size(), 0), max(want.size(), 0);
  for (size_t k = 0; k < want.size(); ++k) {
    sum[want[k]] += hq[k];
    ++count[want[k]];
    max[want[k]] = std::max(max[want[k]], hq[k]);
  }
  for (size_t k = 0; k < want.size(); ++k) {
    if (want[k] != static_cast<int>(k)) continue;
    ASSERT_TRUE(regions.sum(k) == sum[k] && regions.count(k) == count[k] && regions.max(k) == max[k])
        << "region " << k << ", " << where;
  }
}

// BlockRegions labels tiles of blocks in parallel and joins them serially;
// its labels and each region's hq sum, count and max must be those of a
// flood fill, whatever the number of threads: grids of up to 6 x 19 tiles,
// one thread and at least four.
TEST(DepthRegions, StatisticsOfEveryRegionWhateverTheThreads) {
  const uint32_t seed = std::random_device{}();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  const int threads = cv::getNumThreads();
  for (int trial = 0; trial < 12; ++trial) {
    const int bx = 1 + rng() % 90, by = 1 + rng() % 300;
    std::vector<float> feat;
    std::vector<uint32_t> hq;
    for (int k = 0; k < bx * by; ++k) {
      const float v = (rng() % 100) < 59 ? 20.f : 220.f;
      feat.insert(feat.end(), {v, v * 0.5f, 3.f});
      hq.push_back(rng() % 65536);
    }
    const std::vector<int> want = flood_labels(feat, bx, by, 24.f);
    for (int t : {1, std::max(threads, 4)}) {
      cv::setNumThreads(t);
      BlockRegions regions;
      regions.label(feat, bx, by, 24.f, false, hq.data());
      const std::string where = std::to_string(bx) + "x" + std::to_string(by) + ", " + std::to_string(t) + " threads";
      ASSERT_EQ(regions.labels(), want) << where;
      expect_region_stats(regions, want, hq, where);
    }
    cv::setNumThreads(threads);
  }
}

// Incremental calls label again only the tiles whose features changed and
// join the tiles again. After edits of small rects (which merge and split
// regions that reach across the grid) the labels and statistics must be a
// flood fill's, exactly the changed tiles labelled; a new threshold, other
// features' space, forget() with new hypotheses and a whole call in
// between must label every tile.
TEST(DepthRegions, IncrementalLabellingIsAFreshOne) {
  const uint32_t seed = std::random_device{}();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  constexpr int TW = BlockRegions::kTileW, TH = BlockRegions::kTileH;
  for (int trial = 0; trial < 6; ++trial) {
    const int bx = 20 + rng() % 140, by = 10 + rng() % 90;
    const int tiles_x = (bx + TW - 1) / TW, tiles = tiles_x * ((by + TH - 1) / TH);
    std::vector<float> feat;
    std::vector<uint32_t> hq;
    auto colour = [&](size_t k, float v) {
      feat[3 * k] = v;
      feat[3 * k + 1] = v * 0.5f;
      feat[3 * k + 2] = 3.f;
    };
    feat.resize(3 * static_cast<size_t>(bx) * by);
    for (size_t k = 0; k < static_cast<size_t>(bx) * by; ++k) {
      colour(k, (rng() % 100) < 59 ? 20.f : 220.f);
      hq.push_back(rng() % 65536);
    }
    BlockRegions regions;
    regions.label(feat, bx, by, 24.f, false, hq.data(), true);
    for (int step = 0; step < 20; ++step) {
      const std::string where = std::to_string(bx) + "x" + std::to_string(by) + ", step " + std::to_string(step);
      std::vector<uint8_t> changed(static_cast<size_t>(tiles), 0);
      const int w = 1 + rng() % 6, h = 1 + rng() % 6, x0 = rng() % bx, y0 = rng() % by;
      for (int y = y0; y < std::min(by, y0 + h); ++y)
        for (int x = x0; x < std::min(bx, x0 + w); ++x) {
          const size_t k = static_cast<size_t>(y) * bx + x;
          const float v = (rng() % 100) < 59 ? 20.f : 220.f;
          if (feat[3 * k] != v) changed[(y / TH) * tiles_x + x / TW] = 1;
          colour(k, v);
        }
      // Steps that must label every tile: another threshold (13, and 14
      // back), Y'CbCr features (16, and 17 back), new hypotheses after
      // forget() (5), a whole call between incremental ones (9, 10).
      const float threshold = step == 13 ? 30.f : 24.f;
      const bool yuv = step == 16;
      if (step == 5) {
        for (uint32_t &q : hq) q = rng() % 65536;
        regions.forget();
      }
      regions.label(feat, bx, by, threshold, yuv, hq.data(), step != 9);
      const std::vector<int> want = flood_labels(feat, bx, by, threshold, yuv);
      ASSERT_EQ(regions.labels(), want) << where;
      expect_region_stats(regions, want, hq, where);
      const bool all = step == 5 || step == 9 || step == 10 || step == 13 || step == 14 || step == 16 || step == 17;
      const int expected = all ? tiles : static_cast<int>(std::count(changed.begin(), changed.end(), 1));
      ASSERT_EQ(regions.tiles_labelled(), expected) << where;
    }
  }
}

// ----------------------------------------------------------- hypotheses ---

TEST(DepthHypothesis, KnownValues) {
  EXPECT_EQ(hypothesis_depth(Hypothesis::TopBottom, 0.3f, 0.7f), 0.7f);
  EXPECT_EQ(hypothesis_depth(Hypothesis::LeftRight, 0.3f, 0.7f), 0.3f);
  EXPECT_EQ(hypothesis_depth(Hypothesis::Flat, 0.3f, 0.7f), 0.5f);
  EXPECT_NEAR(hypothesis_depth(Hypothesis::CenterNear, 0.5f, 0.5f), 1.f, 1e-7);
  EXPECT_NEAR(hypothesis_depth(Hypothesis::CenterNear, 0.f, 0.f), 0.f, 1e-6);
  EXPECT_NEAR(hypothesis_depth(Hypothesis::CenterNear, 0.5f, 0.f), 1 - 0.5 / std::sqrt(0.5), 1e-6);
  // Block centres: a partial last block is centred on its own pixels.
  EXPECT_FLOAT_EQ(block_centre(0, 4, 33), 2.f / 33);
  EXPECT_FLOAT_EQ(block_centre(8, 4, 33), 32.5f / 33);
  EXPECT_EQ(block_hypothesis_q(Hypothesis::TopBottom, 0, 0, 4, 1, 1), 32768u);  // 0.5 * 65535 + 0.5
}

TEST(DepthHypothesis, Directions) {
  const int W = 64, H = 48, B = 8;  // 8 x 6 blocks
  DepthParams p;
  p.block_size = B;
  p.region_weight = 0.f;  // the hypothesis alone
  const HostFrame f = solid(W, H, cv::Scalar(128, 128, 128));
  auto depth_for = [&](Hypothesis h) {
    p.hypothesis = h;
    DepthEstimatorCpu est;
    cv::Mat d = estimate(est, p, f);
    EXPECT_TRUE(all_finite(d));
    return d;
  };
  const cv::Mat tb = depth_for(Hypothesis::TopBottom);
  EXPECT_LT(tb.at<float>(0, 10), 0.1f);  // top is far
  EXPECT_GT(tb.at<float>(H - 1, 10), 0.9f);  // bottom is near
  for (int y = B; y < H; ++y) EXPECT_GT(tb.at<float>(y, 0), tb.at<float>(y - B, 0));
  for (int x = 1; x < W; ++x) EXPECT_EQ(tb.at<float>(20, x), tb.at<float>(20, 0));

  const cv::Mat lr = depth_for(Hypothesis::LeftRight);
  EXPECT_LT(lr.at<float>(10, 0), 0.1f);  // left is far
  EXPECT_GT(lr.at<float>(10, W - 1), 0.9f);
  for (int x = B; x < W; ++x) EXPECT_GT(lr.at<float>(0, x), lr.at<float>(0, x - B));
  for (int y = 1; y < H; ++y) EXPECT_EQ(lr.at<float>(y, 30), lr.at<float>(0, 30));

  const cv::Mat cn = depth_for(Hypothesis::CenterNear);
  const float centre_d = cn.at<float>(H / 2, W / 2), corner = cn.at<float>(0, 0);
  EXPECT_GT(centre_d, 0.8f);
  EXPECT_LT(corner, 0.2f);
  EXPECT_FLOAT_EQ(cn.at<float>(0, 0), cn.at<float>(H - 1, W - 1));  // symmetric
  EXPECT_FLOAT_EQ(cn.at<float>(0, W - 1), cn.at<float>(H - 1, 0));

  const cv::Mat flat = depth_for(Hypothesis::Flat);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) ASSERT_NEAR(flat.at<float>(y, x), 0.5f, 1e-5f);
}

TEST(DepthEstimator, RegionWeightZeroGivesPureHypothesis) {
  HostFrame f(PixelFormat::I420, 50, 30, kPad);
  f.fill_random(std::random_device{}());
  DepthParams p;
  p.block_size = 6;  // 9 x 5 blocks, the last ones partial
  p.region_weight = 0.f;
  p.hypothesis = Hypothesis::LeftRight;
  DepthEstimatorCpu est;
  const cv::Mat depth = estimate(est, p, f);
  ASSERT_EQ(est.blocks_x(), 9);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 50; ++x) ASSERT_NEAR(depth.at<float>(y, x), quantised(centre(x / 6, 6, 50)), 1e-6) << x;
}

TEST(DepthEstimator, RegionDepthIsMeanOverRegion) {
  // Left quarter one colour, rest another: region means over different block sets.
  cv::Mat bgr(16, 64, CV_8UC3, cv::Scalar(0, 200, 0));
  bgr.colRange(0, 16).setTo(cv::Scalar(250, 250, 250));
  DepthParams p;
  p.block_size = 8;  // 8 x 2 blocks: 2 columns of blocks in the left region
  p.region_weight = 1.f;
  p.ground_contact = 0.f;
  p.hypothesis = Hypothesis::LeftRight;
  DepthEstimatorCpu est;
  estimate(est, p, HostFrame::from_bgr(bgr, PixelFormat::BGRA, kPad));
  double left = 0, right = 0;
  for (int i = 0; i < 8; ++i) (i < 2 ? left : right) += quantised(centre(i, 8, 64));
  left /= 2;
  right /= 6;
  for (int k = 0; k < 16; ++k) EXPECT_NEAR(est.block_depth()[k], k % 8 < 2 ? left : right, 1e-6) << k;
}

// Ground contact: a region takes the hypothesis of its nearest block (the
// largest hq). Top-bottom: a grey square standing on a black floor touches it
// at its lowest block row, so the whole square gets that row's depth, and
// the floor its own lowest row; ground_contact 0.5 and region_weight 0.5
// blend as step 4 says, in float, operation by operation.
TEST(DepthEstimator, GroundContactTakesTheRegionsNearestBlock) {
  const int W = 64, H = 48, B = 4;  // 16 x 12 blocks; the square is blocks (4..7, 2..6)
  cv::Mat bgr(H, W, CV_8UC3, cv::Scalar(0, 0, 0));
  bgr(cv::Rect(16, 8, 16, 20)).setTo(cv::Scalar(200, 200, 200));
  const HostFrame f = HostFrame::from_bgr(bgr, PixelFormat::BGRA, kPad);
  DepthParams p;
  p.block_size = B;
  p.region_weight = 1.f;
  p.ground_contact = 1.f;
  DepthEstimatorCpu est;
  estimate(est, p, f);
  const float square = static_cast<float>(quantised(centre(6, B, H)));
  const float floor = static_cast<float>(quantised(centre(11, B, H)));
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 16; ++i) {
      const bool in = i >= 4 && i <= 7 && j >= 2 && j <= 6;
      EXPECT_EQ(est.block_depth()[j * 16 + i], in ? square : floor) << i << "," << j;
    }
  // Blends, against the formula of step 4 (region sums written out here).
  p.ground_contact = 0.5f;
  p.region_weight = 0.5f;
  DepthEstimatorCpu est2;
  estimate(est2, p, f);
  uint64_t sq_sum = 0, fl_sum = 0;
  uint32_t sq_n = 0, fl_n = 0;
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 16; ++i) {
      const uint32_t hq = block_hypothesis_q(Hypothesis::TopBottom, i, j, B, W, H);
      const bool in = i >= 4 && i <= 7 && j >= 2 && j <= 6;
      (in ? sq_sum : fl_sum) += hq;
      ++(in ? sq_n : fl_n);
    }
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 16; ++i) {
      const bool in = i >= 4 && i <= 7 && j >= 2 && j <= 6;
      const uint32_t hq = block_hypothesis_q(Hypothesis::TopBottom, i, j, B, W, H);
      const float r_mean = static_cast<float>(in ? sq_sum : fl_sum) / static_cast<float>(in ? sq_n : fl_n) / 65535.f;
      const float r_near = (in ? square : floor);
      const float r = 0.5f * r_near + (1.f - 0.5f) * r_mean;
      const float want = 0.5f * r + (1.f - 0.5f) * (static_cast<float>(hq) / 65535.f);
      EXPECT_EQ(est2.block_depth()[j * 16 + i], want) << i << "," << j;
    }
  // The helpers: ground_contact 0 is the region mean bit for bit, 1 the maximum.
  EXPECT_EQ(region_depth(0.f, 3 * 65535ull, 4, 65535), static_cast<float>(3 * 65535ull) / 4.f / 65535.f);
  EXPECT_EQ(region_depth(1.f, 12345, 7, 40000), 40000.f / 65535.f);
}

// The cue follows the hypothesis: with left-right the nearest block of a
// region is its rightmost one.
TEST(DepthEstimator, GroundContactFollowsTheHypothesis) {
  cv::Mat bgr(16, 64, CV_8UC3, cv::Scalar(0, 200, 0));
  bgr.colRange(0, 16).setTo(cv::Scalar(250, 250, 250));
  DepthParams p;
  p.block_size = 8;  // 8 x 2 blocks: block columns 0-1 and 2-7
  p.region_weight = 1.f;
  p.ground_contact = 1.f;
  p.hypothesis = Hypothesis::LeftRight;
  DepthEstimatorCpu est;
  estimate(est, p, HostFrame::from_bgr(bgr, PixelFormat::BGRA, kPad));
  for (int k = 0; k < 16; ++k)
    EXPECT_EQ(est.block_depth()[k], static_cast<float>(quantised(centre(k % 8 < 2 ? 1 : 7, 8, 64)))) << k;
}

// ------------------------------------------------------------- temporal ---

DepthParams temporal_params() {
  DepthParams p;
  p.block_size = 4;
  p.temporal_smoothing = 0.5f;
  p.static_threshold = 0.5f;
  p.cut_threshold = 30.f;
  return p;
}

TEST(DepthTemporal, IdenticalFrameIsReusedUnchanged) {
  HostFrame f(PixelFormat::NV12, 48, 34, kPad);
  f.fill_random(std::random_device{}());
  DepthParams p = temporal_params();
  DepthEstimatorCpu est;
  TemporalDecision d;
  const cv::Mat first = estimate(est, p, f, &d);
  EXPECT_EQ(d, TemporalDecision::Cut);  // first frame
  // Other parameters would give another depth: reuse must ignore them.
  p.hypothesis = Hypothesis::LeftRight;
  const cv::Mat second = estimate(est, p, f, &d);
  EXPECT_EQ(d, TemporalDecision::Reuse);
  EXPECT_EQ(est.last_diff(), 0.f);
  EXPECT_TRUE(identical(first, second));
}

TEST(DepthTemporal, SmallChangeSmoothsWithBlendFormula) {
  DepthParams p = temporal_params();
  p.temporal_smoothing = 0.3f;
  DepthEstimatorCpu est;
  TemporalDecision d;
  estimate(est, p, solid(30, 22, cv::Scalar(100, 100, 100)), &d);
  ASSERT_EQ(d, TemporalDecision::Cut);
  const std::vector<float> prev = est.block_depth();
  // Every channel +5: diff = 5 exactly, between the thresholds.
  const HostFrame next = solid(30, 22, cv::Scalar(105, 105, 105));
  DepthParams p2 = p;
  p2.hypothesis = Hypothesis::CenterNear;  // so that b differs from prev
  estimate(est, p2, next, &d);
  ASSERT_EQ(d, TemporalDecision::Smooth);
  EXPECT_EQ(est.last_diff(), 5.f);
  DepthEstimatorCpu fresh;
  estimate(fresh, p2, next);
  const std::vector<float> &b = fresh.block_depth();
  ASSERT_EQ(b.size(), prev.size());
  int differ = 0;
  for (size_t k = 0; k < b.size(); ++k) {
    EXPECT_EQ(est.block_depth()[k], 0.3f * prev[k] + (1.f - 0.3f) * b[k]) << k;
    differ += prev[k] != b[k];
  }
  EXPECT_GT(differ, 0);
  // The smoothed frame became the reference: the same frame again is reused.
  estimate(est, p2, next, &d);
  EXPECT_EQ(d, TemporalDecision::Reuse);
}

TEST(DepthTemporal, VeryDifferentFrameCutsWithoutBlending) {
  DepthParams p = temporal_params();
  DepthEstimatorCpu est;
  TemporalDecision d;
  estimate(est, p, solid(41, 23, cv::Scalar(50, 50, 50)), &d);
  cv::Mat bgr(23, 41, CV_8UC3, cv::Scalar(220, 220, 220));
  bgr.rowRange(0, 12).setTo(cv::Scalar(10, 200, 30));
  const HostFrame other = HostFrame::from_bgr(bgr, PixelFormat::RGBx, kPad);
  const cv::Mat got = estimate(est, p, other, &d);
  EXPECT_EQ(d, TemporalDecision::Cut);
  EXPECT_GE(est.last_diff(), 30.f);
  DepthEstimatorCpu fresh;
  EXPECT_TRUE(identical(got, estimate(fresh, p, other)));  // immediate reset: no trace of the old frame
}

TEST(DepthTemporal, ThresholdsAreInclusive) {
  DepthParams p = temporal_params();
  p.static_threshold = 5.f;  // diff == static_threshold -> reuse
  DepthEstimatorCpu est;
  TemporalDecision d;
  estimate(est, p, solid(16, 16, cv::Scalar(60, 60, 60)), &d);
  estimate(est, p, solid(16, 16, cv::Scalar(65, 65, 65)), &d);
  EXPECT_EQ(d, TemporalDecision::Reuse);
  p.static_threshold = 0.5f;
  p.cut_threshold = 5.f;  // reference still 60: diff 5 == cut_threshold -> cut
  estimate(est, p, solid(16, 16, cv::Scalar(65, 65, 65)), &d);
  EXPECT_EQ(d, TemporalDecision::Cut);
}

TEST(DepthTemporal, ReferenceIsLastComputedFrameNotReusedOne) {
  DepthParams p = temporal_params();
  p.static_threshold = 0.4f;
  DepthEstimatorCpu est;
  TemporalDecision d;
  estimate(est, p, solid(16, 16, cv::Scalar(100, 100, 100)), &d);
  // One channel +1: diff 1/3 -> reuse; the reference stays the first frame.
  estimate(est, p, solid(16, 16, cv::Scalar(100, 100, 101)), &d);
  EXPECT_EQ(d, TemporalDecision::Reuse);
  // One channel +2: 2/3 against the first frame (1/3 against the reused one).
  estimate(est, p, solid(16, 16, cv::Scalar(100, 100, 102)), &d);
  EXPECT_EQ(d, TemporalDecision::Smooth);
  EXPECT_NEAR(est.last_diff(), 2.0 / 3.0, 1e-6);
}

TEST(DepthTemporal, SizeChangeBlockChangeAndResetCut) {
  DepthParams p = temporal_params();
  DepthEstimatorCpu est;
  TemporalDecision d;
  estimate(est, p, solid(32, 32, cv::Scalar(9, 9, 9)), &d);
  EXPECT_EQ(d, TemporalDecision::Cut);
  estimate(est, p, solid(32, 32, cv::Scalar(9, 9, 9)), &d);
  EXPECT_EQ(d, TemporalDecision::Reuse);
  estimate(est, p, solid(32, 30, cv::Scalar(9, 9, 9)), &d);
  EXPECT_EQ(d, TemporalDecision::Cut);  // size change
  p.block_size = 8;
  estimate(est, p, solid(32, 30, cv::Scalar(9, 9, 9)), &d);
  EXPECT_EQ(d, TemporalDecision::Cut);  // block grid change
  est.reset();
  estimate(est, p, solid(32, 30, cv::Scalar(9, 9, 9)), &d);
  EXPECT_EQ(d, TemporalDecision::Cut);
  estimate(est, p, solid(32, 30, cv::Scalar(9, 9, 9)), &d);
  EXPECT_EQ(d, TemporalDecision::Reuse);
}

TEST(DepthTemporal, FixedPointMeanIsExactForLevelDifferences) {
  // Any mean of whole-level differences is represented exactly.
  EXPECT_EQ(temporal_diff_fixed(105.f, 100.f), 5ull << 24);
  EXPECT_EQ(temporal_mean_diff(15ull << 24, 3), 5.f);
  EXPECT_EQ(temporal_diff_fixed(0.25f, 0.5f), 1ull << 22);
  EXPECT_EQ(temporal_decision(false, 0.f, DepthParams{}), TemporalDecision::Cut);
}

// ------------------------------------------------------ sizes, formats ---

TEST(DepthEdgeSizes, OddSizesWriteEveryPixel) {
  const int sizes[][2] = {{1, 1}, {3, 2}, {2, 3}, {33, 17}, {1001, 7}, {5, 64}};
  std::mt19937 rng(std::random_device{}());
  for (const auto &s : sizes)
    for (int B : {2, 4, 5, 64}) {
      HostFrame f(PixelFormat::NV12, s[0], s[1], kPad);
      f.fill_random(rng());
      DepthParams p;
      p.block_size = B;
      p.edge_threshold = 40.f;
      DepthEstimatorCpu est;
      const cv::Mat depth = estimate(est, p, f);
      EXPECT_EQ(est.blocks_x(), (s[0] + B - 1) / B);
      EXPECT_EQ(est.blocks_y(), (s[1] + B - 1) / B);
      ASSERT_TRUE(all_finite(depth)) << s[0] << "x" << s[1] << " B=" << B;
      double lo, hi;
      cv::minMaxLoc(depth, &lo, &hi);
      EXPECT_GE(lo, 0.0);
      EXPECT_LE(hi, 1.0);
      EXPECT_EQ(est.labels(), flood_labels([&] {
                  std::vector<float> feat;
                  block_features_cpu(f.view(), B, feat);
                  return feat;
                }(), est.blocks_x(), est.blocks_y(), 40.f, true));  // NV12
    }
}

TEST(DepthEdgeSizes, OnePixelFrame) {
  DepthParams p;
  p.region_weight = 0.5f;
  DepthEstimatorCpu est;
  const cv::Mat d = estimate(est, p, solid(1, 1, cv::Scalar(1, 2, 3)));
  EXPECT_EQ(d.at<float>(0, 0), 32768.f / 65535.f);  // centre 0.5, quantised
}

TEST(DepthEdgeSizes, OutOfRangeBlockSizeIsClamped) {
  DepthParams p;
  p.block_size = 1;
  DepthEstimatorCpu est;
  estimate(est, p, solid(9, 9, cv::Scalar(1, 2, 3)));
  EXPECT_EQ(est.blocks_x(), 5);  // block 2
  p.block_size = 500;
  estimate(est, p, solid(130, 9, cv::Scalar(1, 2, 3)));
  EXPECT_EQ(est.blocks_x(), 3);  // block 64
}

// block_size 0: one block per 540 pixels of the shorter side, 2 to 64.
TEST(DepthEdgeSizes, AutoBlockSizeFollowsTheShorterSide) {
  DepthParams p;
  EXPECT_EQ(p.block_size, 0);  // the default is auto
  const int cases[][3] = {{1, 1, 2},       {768, 576, 2},     {1282, 1110, 2},   {1920, 1080, 2}, {1080, 1920, 2},
                          {2560, 1440, 2}, {3840, 2160, 4},   {2160, 3840, 4},   {5120, 2880, 5}, {7680, 4320, 8},
                          {40000, 40000, 64}};
  for (const auto &c : cases) EXPECT_EQ(effective_block_size(p, c[0], c[1]), c[2]) << c[0] << "x" << c[1];
  DepthEstimatorCpu est;
  estimate(est, p, solid(1620, 1200, cv::Scalar(1, 2, 3)));
  EXPECT_EQ(est.blocks_x(), 1620 / 2);
  p.block_size = 4;  // an explicit size is kept whatever the picture
  EXPECT_EQ(effective_block_size(p, 7680, 4320), 4);
}

// ------------------------------------------------- feature smoothing ---

// Two flat halves whose colours differ by about the edge threshold, with
// camera-like noise in the right half: one frame +/-2 around a difference
// of 22 (edge_threshold 24), so raw features flip between joined (20) and
// split (24) every frame.
HostFrame noisy_halves(int frame) {
  cv::Mat bgr(16, 32, CV_8UC3, cv::Scalar(100, 100, 100));
  bgr.colRange(16, 32).setTo(cv::Scalar(100, 100, frame % 2 ? 124 : 120));
  return HostFrame::from_bgr(bgr, PixelFormat::RGBA, kPad);
}

DepthParams feature_params(float feature_smoothing) {
  DepthParams p = temporal_params();
  p.feature_smoothing = feature_smoothing;
  return p;
}

int regions(const std::vector<int> &labels) { return static_cast<int>(std::set<int>(labels.begin(), labels.end()).size()); }

TEST(DepthFeatureSmoothing, NoiseNoLongerFlipsEdges) {
  for (const float w : {0.f, 0.9f}) {
    DepthEstimatorCpu est;
    std::set<int> counts;
    for (int t = 0; t < 20; ++t) {
      TemporalDecision d;
      estimate(est, feature_params(w), noisy_halves(t), &d);
      if (t > 0) {
        ASSERT_NE(d, TemporalDecision::Cut);  // diff 4 / 2 / 3 levels: smooth
      }
      if (t >= 1) counts.insert(regions(est.labels()));
    }
    if (w == 0.f)
      EXPECT_EQ(counts, (std::set<int>{1, 2})) << "without smoothing the edge flips";
    else
      EXPECT_EQ(counts, (std::set<int>{1})) << "smoothed, the halves (22 apart on average) stay one region";
  }
}

// Every frame but a cut moves s towards f by the formula, reused frames too;
// a cut restarts s from f.
TEST(DepthFeatureSmoothing, FollowsTheFormulaAndRestartsAtCuts) {
  const DepthParams p = feature_params(0.75f);
  DepthEstimatorCpu est;
  TemporalDecision d;
  estimate(est, p, noisy_halves(0), &d);
  ASSERT_EQ(d, TemporalDecision::Cut);
  std::vector<float> f;
  block_features_cpu(noisy_halves(0).view(), 4, f);
  EXPECT_EQ(est.smoothed_features(), f);  // a first frame is a cut: s = f
  std::vector<float> s = est.smoothed_features();
  for (int t = 1; t < 4; ++t) {
    const HostFrame frame = noisy_halves(t);
    block_features_cpu(frame.view(), 4, f);
    estimate(est, p, frame, &d);
    ASSERT_NE(d, TemporalDecision::Cut);
    for (size_t k = 0; k < s.size(); ++k) s[k] = 0.75f * s[k] + (1.f - 0.75f) * f[k];
    ASSERT_EQ(est.smoothed_features(), s) << "frame " << t;
  }
  // A reused frame (the same picture again) still moves s.
  estimate(est, p, noisy_halves(3), &d);
  ASSERT_EQ(d, TemporalDecision::Reuse);
  for (size_t k = 0; k < s.size(); ++k) s[k] = 0.75f * s[k] + (1.f - 0.75f) * f[k];
  EXPECT_EQ(est.smoothed_features(), s);
  // A cut: s is this frame's features, nothing of the past.
  const HostFrame other = solid(32, 16, cv::Scalar(10, 200, 60));
  estimate(est, p, other, &d);
  ASSERT_EQ(d, TemporalDecision::Cut);
  block_features_cpu(other.view(), 4, f);
  EXPECT_EQ(est.smoothed_features(), f);
}

// A block whose colour moves by 8 levels (L1) or more takes its new feature
// at once, so the regions of a moving object do not lag behind it.
TEST(DepthFeatureSmoothing, MovedBlocksStartAfresh) {
  const DepthParams p = feature_params(0.9f);
  cv::Mat bgr(16, 32, CV_8UC3, cv::Scalar(100, 100, 100));
  DepthEstimatorCpu est;
  TemporalDecision d;
  estimate(est, p, HostFrame::from_bgr(bgr, PixelFormat::RGBA, kPad), &d);
  EXPECT_EQ(regions(est.labels()), 1);
  // The right half brightens by 30 in one channel: diff 30 / 2 / 3 = 5, a smooth frame.
  bgr.colRange(16, 32).setTo(cv::Scalar(100, 100, 130));
  const HostFrame moved = HostFrame::from_bgr(bgr, PixelFormat::RGBA, kPad);
  estimate(est, p, moved, &d);
  ASSERT_EQ(d, TemporalDecision::Smooth);
  std::vector<float> f;
  block_features_cpu(moved.view(), 4, f);
  EXPECT_EQ(est.smoothed_features(), f);  // left unchanged (s == f), right moved: both f
  EXPECT_EQ(regions(est.labels()), 2) << "the new edge is seen in the frame it appears";
  // Under the gate (L1 7), s moves by the formula; at it (L1 8), s = f.
  float s[3] = {100.f, 100.f, 100.f};
  const float g[3] = {100.f, 104.f, 103.f};
  smooth_block_feature(false, 0.5f, g, s);
  EXPECT_EQ(s[1], 102.f);
  EXPECT_EQ(s[2], 101.5f);
  const float h[3] = {108.f, 102.f, 101.5f};
  smooth_block_feature(false, 0.5f, h, s);
  EXPECT_EQ(s[0], 108.f);
}

// feature_smoothing 0 is the estimator before the smoothing: labels of the
// frame's own features, frame after frame.
TEST(DepthFeatureSmoothing, ZeroIsTheFrameAlone) {
  DepthEstimatorCpu est;
  std::mt19937 rng(7);
  std::vector<float> f;
  std::vector<int> labels;
  HostFrame frame(PixelFormat::I420, 61, 37, kPad);
  for (int t = 0; t < 6; ++t) {
    frame.fill_random(rng());
    estimate(est, feature_params(0.f), frame);
    block_features_cpu(frame.view(), 4, f);
    EXPECT_EQ(est.smoothed_features(), f);
    region_labels_cpu(f, est.blocks_x(), est.blocks_y(), 24.f, true, labels);  // I420
    EXPECT_EQ(est.labels(), labels);
  }
}

TEST(DepthFormats, FlatColoursGiveSameLabelsInEveryFormat) {
  // Four flat rectangles on an 8-pixel grid (block and chroma aligned), in
  // colours far apart in R'G'B' and in Y'CbCr alike.
  cv::Mat bgr(48, 72, CV_8UC3, cv::Scalar(255, 255, 255));
  bgr(cv::Rect(0, 0, 40, 24)).setTo(cv::Scalar(0, 0, 255));
  bgr(cv::Rect(40, 0, 32, 32)).setTo(cv::Scalar(0, 160, 0));
  bgr(cv::Rect(8, 32, 24, 16)).setTo(cv::Scalar(200, 0, 0));
  DepthParams p;
  p.block_size = 4;
  std::vector<int> reference;
  for (PixelFormat fmt : kAllFormats) {
    DepthEstimatorCpu est;
    const cv::Mat depth = estimate(est, p, HostFrame::from_bgr(bgr, fmt, kPad));
    EXPECT_TRUE(all_finite(depth)) << test::format_name(fmt);
    const std::set<int> regions(est.labels().begin(), est.labels().end());
    EXPECT_EQ(regions.size(), 4u) << test::format_name(fmt);
    if (reference.empty())
      reference = est.labels();
    else
      EXPECT_EQ(est.labels(), reference) << test::format_name(fmt);
  }
}

TEST(DepthFormats, RealImageAllFinite) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  for (PixelFormat fmt : kAllFormats) {
    DepthEstimatorCpu est;
    const cv::Mat depth = estimate(est, DepthParams{}, HostFrame::from_bgr(aloe, fmt, kPad));
    EXPECT_TRUE(all_finite(depth)) << test::format_name(fmt);
    const std::set<int> regions(est.labels().begin(), est.labels().end());
    EXPECT_GT(regions.size(), 1u);  // a real picture has edges
    EXPECT_LT(regions.size(), est.labels().size());  // and flat stretches
  }
}

// The edge threshold counts R'G'B' levels in every format, so a picture
// decoded as 4:2:0 Y'CbCr (what decoders and jpegdec deliver) gets about the
// depth it gets as RGBA. Before blocks_joined() converted Y'CbCr
// differences, grey edges counted 3.5 times less there and Aloe as I420
// came out nearly one region: mean depth 0.93 against 0.56, mean absolute
// difference 0.37. What remains is 4:2:0 chroma and 8-bit rounding moving
// a few edges near the threshold.
TEST(DepthFormats, RealImageDepthDoesNotDependOnTheFormat) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  DepthEstimatorCpu rgb_est;
  const cv::Mat rgb = estimate(rgb_est, DepthParams{}, HostFrame::from_bgr(aloe, PixelFormat::RGBA, kPad));
  for (PixelFormat fmt : {PixelFormat::I420, PixelFormat::NV12}) {
    DepthEstimatorCpu est;
    const cv::Mat depth = estimate(est, DepthParams{}, HostFrame::from_bgr(aloe, fmt, kPad));
    const double mean_abs = cv::norm(depth, rgb, cv::NORM_L1) / static_cast<double>(depth.total());
    EXPECT_LT(mean_abs, 0.05) << test::format_name(fmt);
    EXPECT_NEAR(cv::mean(depth)[0], cv::mean(rgb)[0], 0.03) << test::format_name(fmt);
  }
}

// --------------------------------------------------------- depth from grey ---

TEST(DepthFromGrey, KnownGreys) {
  HostFrame f(PixelFormat::RGBA, 5, 1, kPad);
  const uint8_t g[5] = {0, 51, 128, 255, 0};
  for (int x = 0; x < 4; ++x) store_rgba(f.view(), x, 0, Rgba{g[x], g[x], g[x], 255});
  store_rgba(f.view(), 4, 0, Rgba{255, 0, 0, 255});  // pure red: its luma weight
  cv::Mat d = nan_depth(5, 1);
  depth_from_grey_cpu(f.view(), YuvToRgb(), depth_view_of(d));
  for (int x = 0; x < 4; ++x) EXPECT_NEAR(d.at<float>(0, x), g[x] / 255.0, 1e-6) << x;
  EXPECT_NEAR(d.at<float>(0, 4), 0.299, 1e-6);
}

TEST(DepthFromGrey, LimitedRangeYuv) {
  for (PixelFormat fmt : {PixelFormat::NV12, PixelFormat::I420}) {
    HostFrame f(fmt, 3, 2, kPad);
    f.fill(128);  // neutral chroma
    const FrameView v = f.view();
    const uint8_t y[3] = {16, 126, 235};
    for (int r = 0; r < 2; ++r)
      for (int x = 0; x < 3; ++x) v.plane[0][r * v.stride[0] + x] = y[x];
    cv::Mat d = nan_depth(3, 2);
    depth_from_grey_cpu(v, YuvToRgb(), depth_view_of(d));
    for (int r = 0; r < 2; ++r) {
      EXPECT_NEAR(d.at<float>(r, 0), 0.0, 1e-6);
      EXPECT_NEAR(d.at<float>(r, 1), 128 / 255.0, 1e-6);  // (126-16)*255/219 = 128.08 -> level 128
      EXPECT_NEAR(d.at<float>(r, 2), 1.0, 1e-6);
    }
  }
}

TEST(DepthFromGrey, EveryFormatEveryPixel) {
  cv::Mat grey(17, 23, CV_8UC3);
  cv::randu(grey, 0, 256);
  cv::cvtColor(grey, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, grey, cv::COLOR_GRAY2BGR);
  for (PixelFormat fmt : kAllFormats) {
    const HostFrame f = HostFrame::from_bgr(grey, fmt, kPad);
    cv::Mat d = nan_depth(23, 17);
    depth_from_grey_cpu(f.view(), YuvToRgb(), depth_view_of(d));
    ASSERT_TRUE(all_finite(d)) << test::format_name(fmt);
    for (int y = 0; y < 17; ++y)
      for (int x = 0; x < 23; ++x) {
        // YUV round trips may move a grey by a level or two.
        const double tol = is_packed_rgb(fmt) ? 1e-6 : 2.5 / 255;
        ASSERT_NEAR(d.at<float>(y, x), grey.at<cv::Vec3b>(y, x)[0] / 255.0, tol) << test::format_name(fmt);
      }
  }
}

}  // namespace
}  // namespace p3d
