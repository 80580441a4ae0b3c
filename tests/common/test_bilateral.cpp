// CPU cross-bilateral filter: known answers, degenerate parameters, sizes
// and every guide format, against an independent double-precision reference;
// the Separable mode against its own two-pass reference and the exact filter.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "bilateral.h"
#include "depth_estimate.h"
#include "host_frame.h"
#include "test_data.h"

namespace p3d {
namespace {

using test::kAllFormats;

// A float tolerance against the double reference: float weights and a float
// accumulation of up to (2*16+1)^2 = 1089 terms of depth in [0, 1]; the
// rounding error grows like sqrt(n) * 6e-8 (worst case n * 6e-8 = 6.5e-5,
// never approached by these inputs).
constexpr double kRefTol = 2e-5;

// A guide frame (NV12: plane 0 is the luma itself) holding `luma` (CV_8UC1).
HostFrame luma_guide(const cv::Mat &luma, int row_padding = 5) {
  HostFrame f(PixelFormat::NV12, luma.cols, luma.rows, row_padding);
  f.fill(128);
  const FrameView v = f.view();
  for (int y = 0; y < luma.rows; ++y)
    for (int x = 0; x < luma.cols; ++x) v.plane[0][y * v.stride[0] + x] = luma.at<uint8_t>(y, x);
  return f;
}

cv::Mat random_depth(int w, int h, uint64_t seed) {
  cv::Mat d(h, w, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(d, cv::RNG::UNIFORM, 0.0, 1.0);
  return d;
}

cv::Mat filter(const BilateralParams &p, const HostFrame &guide, const cv::Mat &depth) {
  cv::Mat out(depth.size(), CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  bilateral_filter_cpu(p, guide.view(), depth_view_of(depth), depth_view_of(out));
  return out;
}

// The definition of common/bilateral.h, written out in double with exp().
cv::Mat reference(const BilateralParams &p, const FrameView &guide, const cv::Mat &depth) {
  const int r = p.radius;
  cv::Mat out(depth.size(), CV_64FC1);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      const int gc = load_luma(guide, x, y);
      double sw = 0, swd = 0;
      for (int qy = std::max(0, y - r); qy <= std::min(depth.rows - 1, y + r); ++qy)
        for (int qx = std::max(0, x - r); qx <= std::min(depth.cols - 1, x + r); ++qx) {
          const double d2 = (qx - x) * (qx - x) + (qy - y) * (qy - y);
          const double g = load_luma(guide, qx, qy) - gc;
          const double ws = d2 == 0 ? 1.0 : std::exp(-d2 / (2.0 * p.sigma_space * p.sigma_space));
          const double wr = p.sigma_range > 0 ? std::exp(-g * g / (2.0 * p.sigma_range * p.sigma_range))
                                              : (g == 0 ? 1.0 : 0.0);
          sw += ws * wr;
          swd += ws * wr * depth.at<float>(qy, qx);
        }
      out.at<double>(y, x) = swd / sw;
    }
  return out;
}

double max_abs_diff(const cv::Mat &f32, const cv::Mat &f64) {
  double m = 0;
  for (int y = 0; y < f32.rows; ++y)
    for (int x = 0; x < f32.cols; ++x) {
      const double v = f32.at<float>(y, x);
      if (!std::isfinite(v)) return INFINITY;
      m = std::max(m, std::fabs(v - f64.at<double>(y, x)));
    }
  return m;
}

bool all_finite(const cv::Mat &m) { return cv::checkRange(m, true, nullptr, -1e30, 1e30); }

bool bit_equal(const cv::Mat &a, const cv::Mat &b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0) return false;
  return true;
}

// Left half `left`, right half `right` (the step between columns w/2-1 and w/2).
template <typename T>
cv::Mat step_image(int w, int h, int type, T left, T right) {
  cv::Mat m(h, w, type, cv::Scalar(left));
  m(cv::Rect(w / 2, 0, w - w / 2, h)).setTo(cv::Scalar(right));
  return m;
}

TEST(BilateralTables, CentreIsOneSymmetricAndGaussian) {
  const BilateralParams p{3, 2.f, 10.f};
  std::vector<float> space(bilateral_space_table_size(3)), range(kBilateralRangeTableSize);
  bilateral_tables(p, space.data(), range.data());
  const int side = 7;
  EXPECT_EQ(space[3 * side + 3], 1.f);
  EXPECT_EQ(range[0], 1.f);
  EXPECT_EQ(space[3 * side + 4], expf(-1.f / 8.f));
  EXPECT_NEAR(space[0], std::exp(-18.0 / 8.0), 1e-7);  // (dx, dy) = (-3, -3)
  for (int i = 0; i < side * side; ++i) EXPECT_EQ(space[i], space[side * side - 1 - i]);
  EXPECT_NEAR(range[10], std::exp(-0.5), 1e-7);
  for (int g = 1; g < kBilateralRangeTableSize; ++g) EXPECT_LE(range[g], range[g - 1]);
}

// No table weight is subnormal, for any sigma: each is 0, or the
// Gaussian's value from kBilateralMinWeight (2^-60) up, so every product
// of two is 0 or a normal float.
TEST(BilateralTables, NoSubnormalWeights) {
  for (const float sigma_space : {0.1f, 0.5f, 1.f, 3.f, 100.f})
    for (const float sigma_range : {0.01f, 1.f, 12.f, 50.f, 1000.f}) {
      const BilateralParams p = bilateral_sanitize({kMaxBilateralRadius, sigma_space, sigma_range});
      std::vector<float> space(bilateral_space_table_size(p.radius)), range(kBilateralRangeTableSize);
      bilateral_tables(p, space.data(), range.data());
      auto check = [&](float w, float gaussian) {
        if (gaussian < kBilateralMinWeight) return w == 0.f;
        return w == gaussian && std::fpclassify(w) == FP_NORMAL;
      };
      for (int g = 1; g < kBilateralRangeTableSize; ++g)
        ASSERT_TRUE(check(range[g], expf(-static_cast<float>(g * g) / (2.f * p.sigma_range * p.sigma_range))))
            << "range weight of " << g << " at sigma_range " << sigma_range;
      const int r = p.radius, side = 2 * r + 1;
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          if (dx == 0 && dy == 0) continue;
          ASSERT_TRUE(check(space[(dy + r) * side + dx + r],
                            expf(-static_cast<float>(dx * dx + dy * dy) / (2.f * p.sigma_space * p.sigma_space))))
              << "space weight of " << dx << "," << dy << " at sigma_space " << sigma_space;
        }
    }
}

TEST(BilateralTables, SanitiseClampsAndCanonicalises) {
  EXPECT_EQ(bilateral_sanitize({-4, 3.f, 12.f}).radius, 0);
  EXPECT_EQ(bilateral_sanitize({99, 3.f, 12.f}).radius, kMaxBilateralRadius);
  EXPECT_EQ(bilateral_sanitize({5, 0.f, 12.f}).radius, 0);
  EXPECT_EQ(bilateral_sanitize({5, -1.f, 12.f}).radius, 0);
  EXPECT_EQ(bilateral_sanitize({5, std::nanf(""), 12.f}).radius, 0);
  EXPECT_EQ(bilateral_sanitize({5, 3.f, std::nanf("")}).sigma_range, 0.f);
  EXPECT_EQ(bilateral_sanitize({5, 3.f, -2.f}).sigma_range, 0.f);
  const BilateralParams kept = bilateral_sanitize({7, 2.5f, 9.f});
  EXPECT_EQ(kept.radius, 7);
  EXPECT_EQ(kept.sigma_space, 2.5f);
  EXPECT_EQ(kept.sigma_range, 9.f);
}

TEST(BilateralCpu, DepthStepAlignedWithGuideStepIsKept) {
  const int w = 40, h = 20;
  const HostFrame guide = luma_guide(step_image<int>(w, h, CV_8UC1, 50, 200));
  const cv::Mat depth = step_image<float>(w, h, CV_32FC1, 0.2f, 0.8f);
  const cv::Mat out = filter({5, 3.f, 12.f}, guide, depth);
  // Across the edge the range weight is exp(-150^2 / 288) ~ 1e-34: nothing leaks.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ASSERT_NEAR(out.at<float>(y, x), depth.at<float>(y, x), 1e-6) << x << "," << y;
}

TEST(BilateralCpu, DepthStepUnderConstantGuideIsGaussianSmoothed) {
  const int w = 40, h = 20;
  const HostFrame guide = luma_guide(cv::Mat(h, w, CV_8UC1, cv::Scalar(90)));
  const cv::Mat depth = step_image<float>(w, h, CV_32FC1, 0.2f, 0.8f);
  const BilateralParams p{1, 1.f, 12.f};
  const cv::Mat out = filter(p, guide, depth);
  // Away from the top/bottom border the row factor cancels: 1-D Gaussian
  // with taps e^-1/2, 1, e^-1/2 over 0.2, 0.2, 0.8 left of the step.
  const double e = std::exp(-0.5);
  const double left = (0.2 * (1 + e) + 0.8 * e) / (1 + 2 * e);  // 0.36444
  EXPECT_NEAR(out.at<float>(10, w / 2 - 1), left, 1e-6);
  EXPECT_NEAR(out.at<float>(10, w / 2), 1.0 - left, 1e-6);
  EXPECT_NEAR(out.at<float>(10, w / 2 - 2), 0.2, 1e-6);  // flat beyond the radius
  // The whole image, corners (clipped windows) included.
  const BilateralParams wide{5, 3.f, 12.f};
  EXPECT_LE(max_abs_diff(filter(wide, guide, depth), reference(wide, guide.view(), depth)), kRefTol);
  EXPECT_GT(filter(wide, guide, depth).at<float>(10, w / 2 - 1), 0.3f);  // really blurred
}

// bilateral_keeps: one finite value other than -0 is its own filter
// output, bit for bit (-0 comes back +0, inf as NaN; NaN is left to the
// filter).
TEST(BilateralCpu, KeepsExactlyTheMapsItReturnsUnchanged) {
  const int w = 41, h = 19;
  HostFrame guide(PixelFormat::NV12, w, h, 3);
  guide.fill_random(12);
  const float inf = std::numeric_limits<float>::infinity();
  for (const float value : {0.f, 0.5f, 0.123f, 1.f, 7.f, -0.f, std::nanf(""), inf, -inf}) {
    const cv::Mat depth(h, w, CV_32FC1, cv::Scalar(value));
    const bool keeps = bilateral_keeps(depth_view_of(depth));
    EXPECT_EQ(keeps, std::isfinite(value) && !(value == 0.f && std::signbit(value))) << value;
    BilateralParams p = default_filter_params();
    const cv::Mat out = filter(p, guide, depth);
    const bool same = std::memcmp(out.data, depth.data, depth.total() * sizeof(float)) == 0;
    if (value == value) {
      EXPECT_EQ(same, keeps) << value;
    }
  }
  cv::Mat depth(h, w, CV_32FC1, cv::Scalar(0.25f));
  depth.at<float>(h - 1, w - 1) = 0.25000003f;
  EXPECT_FALSE(bilateral_keeps(as_const(depth_view_of(depth)))) << "the last value differs";
  EXPECT_TRUE(bilateral_keeps(as_const(sub_image(depth_view_of(depth), PixelRect{0, 0, w - 1, h})))) << "outside the rect";
}

// The taps sum differences from the centre's depth (bilateral_accumulate):
// a constant map comes back bit for bit, whatever the guide and sigmas, in
// both modes (what lets a stage skip the filter on a flat scene).
TEST(BilateralCpu, ConstantDepthComesBackUnchanged) {
  HostFrame guide(PixelFormat::RGBA, 37, 23, 3);
  guide.fill_random(11);
  for (const float value : {0.37f, 0.1f, 0.999f, 1e-7f})
    for (const BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable})
      for (float sr : {0.f, 2.f, 12.f, 1e30f}) {
        const cv::Mat depth(23, 37, CV_32FC1, cv::Scalar(value));
        BilateralParams p{6, 2.f, sr};
        p.mode = mode;
        const cv::Mat out = filter(p, guide, depth);
        EXPECT_EQ(cv::norm(out, depth, cv::NORM_INF), 0.0)
            << "value " << value << " mode " << static_cast<int>(mode) << " sigma_range " << sr;
      }
}

TEST(BilateralCpu, DegenerateSigmaRangeNeverGivesNanOrInf) {
  const int w = 31, h = 19;
  HostFrame guide(PixelFormat::BGRx, w, h, 4);
  guide.fill_random(5);
  const cv::Mat depth = random_depth(w, h, 6);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (float sr : {0.f, 1e-30f, 1e-20f, 1e30f, inf, nan, -3.f}) {
    const cv::Mat out = filter({5, 3.f, sr}, guide, depth);
    EXPECT_TRUE(all_finite(out)) << "sigma_range " << sr;
  }
  // sigma_range -> 0 averages only exact guide matches; 1e-30 squares to 0 in float.
  const cv::Mat exact = filter({5, 3.f, 0.f}, guide, depth);
  EXPECT_LE(max_abs_diff(exact, reference({5, 3.f, 0.f}, guide.view(), depth)), kRefTol);
  EXPECT_TRUE(bit_equal(exact, filter({5, 3.f, 1e-30f}, guide, depth)));
  EXPECT_TRUE(bit_equal(exact, filter({5, 3.f, nan}, guide, depth)));
  // Huge sigma_range: every range weight is exactly 1, as under a constant guide.
  const HostFrame flat = luma_guide(cv::Mat(h, w, CV_8UC1, cv::Scalar(7)));
  EXPECT_TRUE(bit_equal(filter({5, 3.f, 1e30f}, guide, depth), filter({5, 3.f, 12.f}, flat, depth)));
}

TEST(BilateralCpu, DegenerateSigmaSpace) {
  const int w = 23, h = 11;
  HostFrame guide(PixelFormat::I420, w, h, 2);
  guide.fill_random(8);
  const cv::Mat depth = random_depth(w, h, 9);
  // sigma_space <= 0 or NaN: the sigma -> 0 limit, the identity; 1e-30 reaches it numerically.
  for (float ss : {0.f, -1.f, std::nanf(""), 1e-30f})
    EXPECT_TRUE(bit_equal(filter({5, ss, 12.f}, guide, depth), depth)) << "sigma_space " << ss;
  // Huge sigma_space: a range-weighted box.
  const BilateralParams box{3, 1e30f, 12.f};
  const cv::Mat out = filter(box, guide, depth);
  EXPECT_TRUE(all_finite(out));
  EXPECT_LE(max_abs_diff(out, reference(box, guide.view(), depth)), kRefTol);
}

TEST(BilateralCpu, RadiusZeroIsIdentity) {
  HostFrame guide(PixelFormat::RGBA, 29, 13, 0);
  guide.fill_random(1);
  const cv::Mat depth = random_depth(29, 13, 2);
  EXPECT_TRUE(bit_equal(filter({0, 3.f, 12.f}, guide, depth), depth));
  EXPECT_TRUE(bit_equal(filter({-7, 3.f, 12.f}, guide, depth), depth));  // clamped to 0
}

TEST(BilateralCpu, Radius16MatchesReferenceAndLargerIsClamped) {
  const int w = 53, h = 41;
  HostFrame guide(PixelFormat::NV12, w, h, 3);
  guide.fill_random(21);
  const cv::Mat depth = random_depth(w, h, 22);
  const BilateralParams p{16, 6.f, 40.f};
  const cv::Mat out = filter(p, guide, depth);
  EXPECT_LE(max_abs_diff(out, reference(p, guide.view(), depth)), kRefTol);
  EXPECT_TRUE(bit_equal(out, filter({99, 6.f, 40.f}, guide, depth)));
}

TEST(BilateralCpu, TinySizes) {
  for (const cv::Size sz : {cv::Size(1, 1), cv::Size(3, 2), cv::Size(2, 3), cv::Size(1, 7)}) {
    for (int r : {0, 1, 5, 16}) {
      HostFrame guide(PixelFormat::NV12, sz.width, sz.height, 1);
      guide.fill_random(31 + r);
      const cv::Mat depth = random_depth(sz.width, sz.height, 32 + r);
      const BilateralParams p{r, 2.f, 30.f};
      const cv::Mat out = filter(p, guide, depth);
      EXPECT_LE(max_abs_diff(out, reference(p, guide.view(), depth)), kRefTol) << sz << " r=" << r;
      if (sz.area() == 1) {
        EXPECT_EQ(out.at<float>(0, 0), depth.at<float>(0, 0));  // weight 1 only
      }
    }
  }
}

TEST(BilateralCpu, InPlaceEqualsOutOfPlace) {
  HostFrame guide(PixelFormat::BGRA, 40, 30, 0);
  guide.fill_random(41);
  cv::Mat depth = random_depth(40, 30, 42);
  const BilateralParams p{4, 2.f, 15.f};
  const cv::Mat expected = filter(p, guide, depth);
  bilateral_filter_cpu(p, guide.view(), as_const(depth_view_of(depth)), depth_view_of(depth));
  EXPECT_TRUE(bit_equal(depth, expected));
}

TEST(BilateralCpu, SizeMismatchThrowsAndEmptyIsNoOp) {
  HostFrame guide(PixelFormat::RGBA, 10, 10, 0);
  const cv::Mat depth(9, 10, CV_32FC1, cv::Scalar(0.5f));
  cv::Mat out(9, 10, CV_32FC1);
  EXPECT_THROW(bilateral_filter_cpu({}, guide.view(), depth_view_of(depth), depth_view_of(out)), cv::Exception);
  HostFrame none(PixelFormat::RGBA, 0, 0, 0);
  cv::Mat empty;
  EXPECT_NO_THROW(bilateral_filter_cpu({}, none.view(), as_const(depth_view_of(empty)), depth_view_of(empty)));
}

// Every input format as guide: a real picture (Aloe, cropped to an odd size,
// padded rows) guiding a random depth map, against the double reference.
class BilateralFormats : public ::testing::TestWithParam<PixelFormat> {};

TEST_P(BilateralFormats, AloeGuideMatchesReference) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  const cv::Mat crop = aloe(cv::Rect(201, 150, 97, 61)).clone();
  const HostFrame guide = HostFrame::from_bgr(crop, GetParam(), 7);
  const cv::Mat depth = random_depth(crop.cols, crop.rows, 77);
  const BilateralParams p{5, 3.f, 12.f};
  const cv::Mat out = filter(p, guide, depth);
  EXPECT_LE(max_abs_diff(out, reference(p, guide.view(), depth)), kRefTol);
}

INSTANTIATE_TEST_SUITE_P(Bilateral, BilateralFormats, ::testing::ValuesIn(kAllFormats),
                         [](const auto &info) { return std::string(test::format_name(info.param)); });

TEST(BilateralCpu, FormatsWithTheSameLumaGiveTheSameResult) {
  // The filter sees only load_luma(): packed formats of one picture agree
  // bit for bit, as do the two YUV layouts.
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  const cv::Mat crop = aloe(cv::Rect(0, 0, 65, 33)).clone();
  const cv::Mat depth = random_depth(crop.cols, crop.rows, 3);
  const BilateralParams p{3, 2.f, 10.f};
  const cv::Mat rgba = filter(p, HostFrame::from_bgr(crop, PixelFormat::RGBA, 0), depth);
  for (PixelFormat f : test::kPackedFormats)
    EXPECT_TRUE(bit_equal(rgba, filter(p, HostFrame::from_bgr(crop, f, 3), depth))) << test::format_name(f);
  EXPECT_TRUE(bit_equal(filter(p, HostFrame::from_bgr(crop, PixelFormat::NV12, 1), depth),
                        filter(p, HostFrame::from_bgr(crop, PixelFormat::I420, 2), depth)));
}

// ---- Separable mode -------------------------------------------------------------

BilateralParams separable(int radius, float sigma_space, float sigma_range) {
  BilateralParams p{radius, sigma_space, sigma_range};
  p.mode = BilateralMode::Separable;
  return p;
}

// One pass of the Separable mode written out in double with exp(): taps
// along x (along_x) or y over `in` (CV_64FC1), weighted against the centre's guide.
cv::Mat reference_pass(const BilateralParams &p, const FrameView &guide, const cv::Mat &in, bool along_x) {
  const int r = p.radius, length = along_x ? in.cols : in.rows;
  cv::Mat out(in.size(), CV_64FC1);
  for (int y = 0; y < in.rows; ++y)
    for (int x = 0; x < in.cols; ++x) {
      const int gc = load_luma(guide, x, y), pos = along_x ? x : y;
      double sw = 0, swd = 0;
      for (int q = std::max(0, pos - r); q <= std::min(length - 1, pos + r); ++q) {
        const int qx = along_x ? q : x, qy = along_x ? y : q, d = q - pos, g = load_luma(guide, qx, qy) - gc;
        const double ws = d == 0 ? 1.0 : std::exp(-double(d * d) / (2.0 * p.sigma_space * p.sigma_space));
        const double wr = p.sigma_range > 0 ? std::exp(-double(g * g) / (2.0 * p.sigma_range * p.sigma_range))
                                            : (g == 0 ? 1.0 : 0.0);
        sw += ws * wr;
        swd += ws * wr * in.at<double>(qy, qx);
      }
      out.at<double>(y, x) = swd / sw;
    }
  return out;
}

// The two passes of common/bilateral.h: rows, then columns of the result.
cv::Mat separable_reference(const BilateralParams &p, const FrameView &guide, const cv::Mat &depth) {
  cv::Mat in;
  depth.convertTo(in, CV_64FC1);
  return reference_pass(p, guide, reference_pass(p, guide, in, true), false);
}

TEST(BilateralSeparable, MatchesTheTwoPassDefinition) {
  for (const cv::Size sz : {cv::Size(53, 41), cv::Size(1, 1), cv::Size(3, 2), cv::Size(1, 9), cv::Size(9, 1)})
    for (int r : {1, 5, 16}) {
      HostFrame guide(PixelFormat::NV12, sz.width, sz.height, 3);
      guide.fill_random(60 + r);
      const cv::Mat depth = random_depth(sz.width, sz.height, 61 + r);
      const BilateralParams p = separable(r, 0.6f * r + 0.5f, 20.f);
      const cv::Mat out = filter(p, guide, depth);
      EXPECT_TRUE(all_finite(out));
      EXPECT_LE(max_abs_diff(out, separable_reference(p, guide.view(), depth)), kRefTol) << sz << " r=" << r;
    }
}

// Depth and guide that vary along x only: the column pass averages equal
// values with equal guides, and the exact window factorises into the row
// pass, so both modes give the same map (up to float rounding).
TEST(BilateralSeparable, EqualsTheExactFilterForOneAxisImages) {
  const int w = 64, h = 24;
  cv::Mat luma(h, w, CV_8UC1), depth(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      luma.at<uint8_t>(y, x) = static_cast<uint8_t>(x < 30 ? 40 + x : 200 - x);
      depth.at<float>(y, x) = x < 30 ? 0.2f + 0.01f * x : 0.9f - 0.005f * x;
    }
  const HostFrame guide = luma_guide(luma);
  const cv::Mat exact = filter(BilateralParams{6, 3.f, 12.f}, guide, depth);
  const cv::Mat sep = filter(separable(6, 3.f, 12.f), guide, depth);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ASSERT_NEAR(sep.at<float>(y, x), exact.at<float>(y, x), 1e-6) << x << "," << y;
}

// A depth corner (one quadrant near) under a matching guide: the separable
// passes keep the corner where the guide has it, like the exact filter, and
// a constant map comes back unchanged.
TEST(BilateralSeparable, KeepsGuidedEdgesAndConstants) {
  const int w = 40, h = 30;
  cv::Mat luma(h, w, CV_8UC1, cv::Scalar(30)), depth(h, w, CV_32FC1, cv::Scalar(0.1f));
  luma(cv::Rect(20, 15, 20, 15)).setTo(cv::Scalar(220));
  depth(cv::Rect(20, 15, 20, 15)).setTo(cv::Scalar(0.8f));
  const HostFrame guide = luma_guide(luma);
  const cv::Mat sep = filter(separable(5, 3.f, 12.f), guide, depth);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ASSERT_NEAR(sep.at<float>(y, x), depth.at<float>(y, x), 1e-5) << x << "," << y;
  const cv::Mat flat(h, w, CV_32FC1, cv::Scalar(0.37f));
  HostFrame noisy(PixelFormat::RGBA, w, h, 0);
  noisy.fill_random(70);
  const cv::Mat out = filter(separable(7, 4.f, 10.f), noisy, flat);
  EXPECT_EQ(cv::norm(out, flat, cv::NORM_INF), 0.0);
}

TEST(BilateralSeparable, RadiusZeroInPlaceThreadsAndSanitise) {
  HostFrame guide(PixelFormat::BGRA, 37, 23, 0);
  guide.fill_random(71);
  cv::Mat depth = random_depth(37, 23, 72);
  EXPECT_TRUE(bit_equal(filter(separable(0, 3.f, 12.f), guide, depth), depth));
  const BilateralParams p = separable(4, 2.f, 15.f);
  const cv::Mat expected = filter(p, guide, depth);
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  EXPECT_TRUE(bit_equal(filter(p, guide, depth), expected));
  cv::setNumThreads(threads);
  bilateral_filter_cpu(p, guide.view(), as_const(depth_view_of(depth)), depth_view_of(depth));
  EXPECT_TRUE(bit_equal(depth, expected));
  BilateralParams odd = p;
  odd.mode = static_cast<BilateralMode>(7);
  EXPECT_EQ(bilateral_sanitize(odd).mode, BilateralMode::Exact);
  EXPECT_EQ(bilateral_sanitize(p).mode, BilateralMode::Separable);
}

// The CPU filter runs both modes in strips of 16 pixels (for speed; the
// last strip of a row overlaps the one before it, and a strip whose taps
// all read one finite depth is that depth without its taps); the GPU
// kernels run the per-pixel functions of common/bilateral.h. Both must
// give the same bits, so the CPU filter is pinned here to
// bilateral_pixel() and bilateral_pass_pixel() on the same tables, in both
// modes: sizes narrower and shorter than the window or a strip, rows with
// and without a partial last strip, several radii, random guides; random
// depth, and depth constant over blocks as the estimator makes it, some
// blocks 0, -0, infinite or NaN.
cv::Mat blocky_depth(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  const float specials[] = {0.f, -0.f, std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
  // 64 x 36 blocks hold the windows of whole strips up to radius 16
  // (16 + 2r columns, 2r + 1 rows), so flat strips occur at every radius.
  const int bw = 64, bh = 36;
  std::vector<float> block((w / bw + 1) * (h / bh + 1));
  for (float &v : block) v = rng() % 8 == 0 ? specials[rng() % 4] : std::uniform_real_distribution<float>(0.f, 1.f)(rng);
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = block[(y / bh) * (w / bw + 1) + x / bw];
  return d;
}

TEST(BilateralCpu, StripsEqualThePerPixelFunctionsBitForBit) {
  for (const cv::Size sz : {cv::Size(67, 45), cv::Size(1, 1), cv::Size(4, 3), cv::Size(1, 30), cv::Size(30, 1),
                            cv::Size(48, 20), cv::Size(16, 17), cv::Size(15, 9), cv::Size(203, 80)})
    for (int r : {0, 1, 5, 16})
      for (BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable})
        for (bool blocky : {false, true}) {
        SCOPED_TRACE(::testing::Message() << sz << " r=" << r << " mode=" << static_cast<int>(mode) << " blocky "
                                          << blocky);
        HostFrame guide(PixelFormat::I420, sz.width, sz.height, 2);
        guide.fill_random(90 + r);
        const cv::Mat depth =
            blocky ? blocky_depth(sz.width, sz.height, 92 + r) : random_depth(sz.width, sz.height, 91 + r);
        BilateralParams p{r, 0.6f * r + 0.5f, 14.f};
        p.mode = mode;
        const BilateralParams s = bilateral_sanitize(p);
        std::vector<float> space(bilateral_space_table_size(s.radius)), range(kBilateralRangeTableSize);
        bilateral_tables(s, space.data(), range.data());
        const cv::Mat luma = bilateral_guide_luma(guide.view());
        auto guide_at = [&](int x, int y) { return luma.at<uint8_t>(y, x); };
        auto depth_at = [&](int x, int y) { return depth.at<float>(y, x); };
        cv::Mat expected(depth.size(), CV_32FC1);
        if (mode == BilateralMode::Exact) {
          for (int y = 0; y < depth.rows; ++y)
            for (int x = 0; x < depth.cols; ++x)
              expected.at<float>(y, x) = bilateral_pixel(x, y, depth.cols, depth.rows, s.radius, space.data(),
                                                         range.data(), guide_at, depth_at);
        } else {
          cv::Mat mid(depth.size(), CV_32FC1);
          auto mid_at = [&](int x, int y) { return mid.at<float>(y, x); };
          for (int y = 0; y < depth.rows; ++y)
            for (int x = 0; x < depth.cols; ++x)
              mid.at<float>(y, x) = bilateral_pass_pixel(x, y, 1, 0, depth.cols, s.radius, space.data(),
                                                         range.data(), guide_at, depth_at);
          for (int y = 0; y < depth.rows; ++y)
            for (int x = 0; x < depth.cols; ++x)
              expected.at<float>(y, x) = bilateral_pass_pixel(x, y, 0, 1, depth.rows, s.radius, space.data(),
                                                              range.data(), guide_at, mid_at);
        }
        EXPECT_TRUE(bit_equal(filter(p, guide, depth), expected));
      }
}

// ---- the coarse grid (BilateralParams::scale) --------------------------------------

BilateralParams scaled(int radius, float sigma_space, float sigma_range, BilateralMode mode, int scale) {
  BilateralParams p{radius, sigma_space, sigma_range, mode};
  p.scale = scale;
  return p;
}

// The definition of the coarse grid (common/bilateral.h), written out here
// from its parts: the cells' guide (rounded mean luma, computed here in
// double from the luma image) as an NV12 frame, the depth of each cell's
// first pixel, the full-resolution filter with radius ceil(r / s) and
// sigma_space / s, each result copied over its cell.
cv::Mat coarse_definition(const BilateralParams &p, int s, const HostFrame &guide, const cv::Mat &depth) {
  const cv::Mat luma = bilateral_guide_luma(guide.view());
  const int cw = (depth.cols + s - 1) / s, ch = (depth.rows + s - 1) / s;
  cv::Mat cell_luma(ch, cw, CV_8UC1), cell_depth(ch, cw, CV_32FC1);
  for (int cy = 0; cy < ch; ++cy)
    for (int cx = 0; cx < cw; ++cx) {
      const cv::Rect cell = cv::Rect(cx * s, cy * s, s, s) & cv::Rect(0, 0, depth.cols, depth.rows);
      const double mean = cv::mean(luma(cell))[0];
      cell_luma.at<uint8_t>(cy, cx) = static_cast<uint8_t>(std::floor(mean + 0.5));
      cell_depth.at<float>(cy, cx) = depth.at<float>(cy * s, cx * s);
    }
  BilateralParams coarse = p;
  coarse.scale = 1;
  coarse.radius = (p.radius + s - 1) / s;
  coarse.sigma_space = p.sigma_space / static_cast<float>(s);
  const cv::Mat filtered = filter(coarse, luma_guide(cell_luma), cell_depth);
  cv::Mat out(depth.size(), CV_32FC1);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) out.at<float>(y, x) = filtered.at<float>(y / s, x / s);
  return out;
}

TEST(BilateralScale, AutomaticStepSanitiseAndCoarseParameters) {
  EXPECT_EQ(bilateral_auto_scale(1920, 1080), 1);
  EXPECT_EQ(bilateral_auto_scale(2560, 1440), 1);
  EXPECT_EQ(bilateral_auto_scale(3840, 2159), 1);
  EXPECT_EQ(bilateral_auto_scale(3840, 2160), 4);
  EXPECT_EQ(bilateral_auto_scale(4096, 2160), 4);
  EXPECT_EQ(bilateral_auto_scale(2160, 3840), 4);  // portrait: the shorter side
  EXPECT_EQ(bilateral_auto_scale(7680, 4320), 4);
  EXPECT_EQ(bilateral_auto_scale(8192, 8192), 4);
  EXPECT_EQ(bilateral_auto_scale(1, 1), 1);
  // A divisor of the estimator's automatic block at 4K and 8K, so that no
  // cell straddles two blocks: the block itself at 4K, half of it at 8K.
  for (const cv::Size sz : {cv::Size(3840, 2160), cv::Size(7680, 4320)}) {
    DepthParams dp;
    EXPECT_EQ(effective_block_size(dp, sz.width, sz.height) % bilateral_auto_scale(sz.width, sz.height), 0) << sz;
  }
  EXPECT_EQ(bilateral_sanitize(scaled(5, 3.f, 12.f, BilateralMode::Exact, -3)).scale, 1);
  EXPECT_EQ(bilateral_sanitize(scaled(5, 3.f, 12.f, BilateralMode::Exact, 99)).scale, kMaxBilateralScale);
  EXPECT_EQ(bilateral_sanitize(scaled(5, 3.f, 12.f, BilateralMode::Exact, 0)).scale, 0);
  EXPECT_EQ(BilateralParams().scale, 1);         // the reference definition: full resolution
  EXPECT_EQ(default_filter_params().scale, 0);   // what the element runs: automatic
  // Radius 0 is the identity at every step; the automatic step follows the size.
  EXPECT_EQ(bilateral_effective_scale(bilateral_sanitize(scaled(0, 3.f, 12.f, BilateralMode::Exact, 4)), 99, 99), 1);
  EXPECT_EQ(bilateral_effective_scale(bilateral_sanitize(scaled(5, 3.f, 12.f, BilateralMode::Exact, 0)), 3840, 2160),
            4);
  const BilateralParams c = bilateral_coarse_params(bilateral_sanitize(scaled(5, 3.f, 12.f, kDefaultFilterMode, 2)), 2);
  EXPECT_EQ(c.radius, 3);
  EXPECT_EQ(c.sigma_space, 1.5f);
  EXPECT_EQ(c.sigma_range, 12.f);
  EXPECT_EQ(c.mode, kDefaultFilterMode);
  EXPECT_EQ(c.scale, 1);
  EXPECT_EQ(bilateral_coarse_params(bilateral_sanitize(scaled(16, 8.f, 12.f, BilateralMode::Exact, 8)), 8).radius, 2);
  EXPECT_EQ(bilateral_coarse_params(bilateral_sanitize(scaled(1, 1.f, 12.f, BilateralMode::Exact, 8)), 8).radius, 1);
}

// The filter at a step s > 1 is the full-resolution filter on the cells,
// spread over them, bit for bit: both modes, steps that divide the size and
// steps that leave partial cells at the right and bottom, frames smaller
// than one cell, every guide format family, in place too.
TEST(BilateralScale, IsTheFilterOnTheCellsSpreadOverThem) {
  for (const cv::Size sz : {cv::Size(64, 48), cv::Size(67, 45), cv::Size(5, 3), cv::Size(1, 9), cv::Size(2, 2)})
    for (const int s : {2, 3, 4, 8})
      for (const BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable})
        for (const PixelFormat f : {PixelFormat::NV12, PixelFormat::BGRA}) {
          SCOPED_TRACE(::testing::Message() << sz << " s=" << s << " mode=" << static_cast<int>(mode)
                                            << " format=" << static_cast<int>(f));
          HostFrame guide(f, sz.width, sz.height, 3);
          guide.fill_random(300 + s);
          cv::Mat depth = random_depth(sz.width, sz.height, 301 + s);
          const BilateralParams p = scaled(5, 3.f, 14.f, mode, s);
          const cv::Mat expected = coarse_definition(p, s, guide, depth);
          EXPECT_TRUE(bit_equal(filter(p, guide, depth), expected));
          bilateral_filter_cpu(p, guide.view(), as_const(depth_view_of(depth)), depth_view_of(depth));
          EXPECT_TRUE(bit_equal(depth, expected));
        }
}

// Scale 0 at 4K is step 4; below 2160 rows it is the full-resolution filter
// itself, so the defaults of every picture up to 1080p did not change.
TEST(BilateralScale, AutomaticIsStepFourAt4KAndFullResolutionBelow) {
  {
    HostFrame guide(PixelFormat::NV12, 1920, 1080, 0);
    guide.fill_random(310);
    const cv::Mat depth = random_depth(1920, 1080, 311);
    EXPECT_TRUE(bit_equal(filter(scaled(5, 3.f, 12.f, kDefaultFilterMode, 0), guide, depth),
                          filter(scaled(5, 3.f, 12.f, kDefaultFilterMode, 1), guide, depth)));
  }
  HostFrame guide(PixelFormat::NV12, 3840, 2160, 0);
  guide.fill_random(312);
  const cv::Mat depth = random_depth(3840, 2160, 313);
  const cv::Mat automatic = filter(default_filter_params(), guide, depth);
  EXPECT_TRUE(bit_equal(automatic, filter(scaled(5, 3.f, 12.f, kDefaultFilterMode, 4), guide, depth)));
  EXPECT_FALSE(bit_equal(automatic, filter(scaled(5, 3.f, 12.f, kDefaultFilterMode, 2), guide, depth)));
  EXPECT_FALSE(bit_equal(automatic, filter(scaled(5, 3.f, 12.f, kDefaultFilterMode, 1), guide, depth)));
}

// What the step keeps: a constant map stays constant; a depth step that
// lies on a cell border and on a guide edge stays where it is, sharp (the
// range weight across the edge is exp(-160^2 / 32) = 0 in float); and
// radius 0 is the identity (no cells) at every step.
TEST(BilateralScale, KeepsConstantsCellAlignedEdgesAndTheIdentity) {
  const int w = 48, h = 20;
  const HostFrame guide = luma_guide(step_image<uint8_t>(w, h, CV_8UC1, 40, 200));
  const cv::Mat step = step_image<float>(w, h, CV_32FC1, 0.2f, 0.8f);
  const cv::Mat flat(h, w, CV_32FC1, cv::Scalar(0.375f));
  for (const int s : {2, 3, 4, 8})
    for (const BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable}) {
      SCOPED_TRACE(::testing::Message() << "s=" << s << " mode=" << static_cast<int>(mode));
      EXPECT_EQ(cv::norm(filter(scaled(5, 3.f, 12.f, mode, s), guide, flat), flat, cv::NORM_INF), 0.0);
      ASSERT_EQ(w / 2 % s, 0);
      EXPECT_LE(cv::norm(filter(scaled(5, 3.f, 4.f, mode, s), guide, step), step, cv::NORM_INF), 1e-6);
      const cv::Mat random = random_depth(w, h, 320 + s);
      EXPECT_TRUE(bit_equal(filter(scaled(0, 3.f, 12.f, mode, s), guide, random), random));
    }
}

}  // namespace
}  // namespace p3d
