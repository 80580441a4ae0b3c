// PSNR and SSIM: known answers, masks, channels, small sizes.
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "metrics.h"
#include "test_data.h"

namespace p3d {
namespace {

cv::Mat random_image(int w, int h, int type, uint64_t seed) {
  cv::Mat m(h, w, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

cv::Mat with_noise(const cv::Mat &img, double sigma, uint64_t seed) {
  cv::Mat noise(img.size(), CV_32FC(img.channels()));
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  cv::Mat f, out;
  img.convertTo(f, CV_32F);
  cv::Mat(f + noise).convertTo(out, CV_8U);  // saturating
  return out;
}

TEST(MetricsPsnr, IdenticalIsPlusInfinity) {
  const cv::Mat a = random_image(33, 17, CV_8UC3, 1);
  const double v = psnr(a, a.clone());
  EXPECT_TRUE(std::isinf(v) && v > 0) << v;
  const cv::Mat one = random_image(1, 1, CV_8UC1, 2);
  EXPECT_TRUE(std::isinf(psnr(one, one)));
}

TEST(MetricsPsnr, KnownMseGivesKnownPsnr) {
  const cv::Mat a(20, 30, CV_8UC3, cv::Scalar(100, 50, 200));
  // Every sample off by 1: MSE 1, PSNR = 20 log10(255) = 48.1308 dB.
  EXPECT_NEAR(psnr(a, a + cv::Scalar(1, 1, 1)), 48.1308, 1e-4);
  EXPECT_NEAR(psnr(a, a - cv::Scalar(1, 1, 1)), 48.1308, 1e-4);
  // Off by 2: MSE 4, 6.0206 dB less.
  EXPECT_NEAR(psnr(a, a + cv::Scalar(2, 2, 2)), 42.1102, 1e-4);
  // One channel of three off by 3: MSE 9 / 3 = 3.
  EXPECT_NEAR(psnr(a, a + cv::Scalar(0, 3, 0)), 10 * std::log10(255.0 * 255.0 / 3.0), 1e-9);
  // Half the pixels off by 4 (grey): MSE 8.
  cv::Mat g(10, 10, CV_8UC1, cv::Scalar(60)), h = g.clone();
  h(cv::Rect(0, 0, 5, 10)) += 4;
  EXPECT_NEAR(psnr(g, h), 10 * std::log10(255.0 * 255.0 / 8.0), 1e-9);
}

TEST(MetricsPsnr, MaskIsRespected) {
  const cv::Mat a(16, 16, CV_8UC3, cv::Scalar(10, 20, 30));
  cv::Mat b = a.clone();
  cv::Mat mask = cv::Mat::zeros(16, 16, CV_8UC1);
  mask(cv::Rect(0, 0, 8, 16)).setTo(255);
  b(cv::Rect(8, 0, 8, 16)).setTo(cv::Scalar(200, 200, 200));  // outside the mask only
  EXPECT_TRUE(std::isinf(psnr(a, b, mask)));
  EXPECT_LT(psnr(a, b), 20.0);
  b(cv::Rect(0, 0, 8, 16)) += cv::Scalar(2, 2, 2);  // inside: MSE 4
  EXPECT_NEAR(psnr(a, b, mask), 42.1102, 1e-4);
  mask.setTo(1);  // any non-zero value counts
  EXPECT_LT(psnr(a, b, mask), 20.0);
  // Nothing counted: nothing differs.
  EXPECT_TRUE(std::isinf(psnr(a, b, cv::Mat::zeros(16, 16, CV_8UC1))));
}

TEST(MetricsSsim, IdenticalIsOne) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  EXPECT_DOUBLE_EQ(ssim(aloe, aloe.clone()), 1.0);
  const cv::Mat r = random_image(37, 23, CV_8UC4, 3);
  EXPECT_DOUBLE_EQ(ssim(r, r), 1.0);
  for (const cv::Size sz : {cv::Size(1, 1), cv::Size(3, 2)}) {
    const cv::Mat s = random_image(sz.width, sz.height, CV_8UC1, 4);
    EXPECT_DOUBLE_EQ(ssim(s, s), 1.0) << sz;
  }
}

TEST(MetricsSsim, ConstantImagesGiveTheLuminanceTerm) {
  // No variance anywhere: SSIM = (2 a b + C1) / (a^2 + b^2 + C1), C1 = (0.01*255)^2.
  const cv::Mat a(20, 20, CV_8UC1, cv::Scalar(100)), b(20, 20, CV_8UC1, cv::Scalar(110));
  const double c1 = 2.55 * 2.55;
  EXPECT_NEAR(ssim(a, b), (2 * 100.0 * 110.0 + c1) / (100.0 * 100.0 + 110.0 * 110.0 + c1), 1e-9);
}

TEST(MetricsSsim, DecreasesWithNoise) {
  const cv::Mat full = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(full.empty());
  const cv::Mat aloe = full(cv::Rect(150, 120, 301, 211));  // a textured part keeps the test fast
  double previous = ssim(aloe, aloe);
  for (double sigma : {2.0, 8.0, 25.0, 60.0}) {
    const double v = ssim(aloe, with_noise(aloe, sigma, 99));
    EXPECT_LT(v, previous) << "noise sigma " << sigma;
    EXPECT_GT(v, -1.0);
    previous = v;
  }
  EXPECT_LT(previous, 0.5);  // sigma 60 wrecks the picture
}

TEST(MetricsSsim, IsTheMeanOverChannels) {
  const cv::Mat a = random_image(40, 30, CV_8UC3, 5), b = with_noise(a, 20, 6);
  cv::Mat ca[3], cb[3];
  cv::split(a, ca);
  cv::split(b, cb);
  const double mean = (ssim(ca[0], cb[0]) + ssim(ca[1], cb[1]) + ssim(ca[2], cb[2])) / 3.0;
  EXPECT_NEAR(ssim(a, b), mean, 1e-12);
  EXPECT_TRUE(std::isfinite(ssim(a, b)));
}

TEST(MetricsSsim, MismatchedImagesThrow) {
  const cv::Mat a(10, 10, CV_8UC3, cv::Scalar::all(0)), b(10, 11, CV_8UC3, cv::Scalar::all(0));
  EXPECT_THROW(ssim(a, b), cv::Exception);
  EXPECT_THROW(psnr(a, b), cv::Exception);
}

}  // namespace
}  // namespace p3d
