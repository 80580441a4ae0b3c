// PSNR and SSIM of 8-bit images (common/metrics.h).
#include "metrics.h"

#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

namespace p3d {

namespace {

void check_pair(const cv::Mat &a, const cv::Mat &b) {
  CV_Assert(a.depth() == CV_8U && a.type() == b.type() && a.size() == b.size());
}

}  // namespace

// MSE over every channel of the counted pixels; 10 log10(255^2 / MSE).
// An all-zero mask counts no pixel: nothing differs, so +infinity, like
// identical images.
double psnr(const cv::Mat &a, const cv::Mat &b, const cv::Mat &mask) {
  check_pair(a, b);
  if (!mask.empty()) CV_Assert(mask.type() == CV_8UC1 && mask.size() == a.size());
  const double pixels = mask.empty() ? static_cast<double>(a.total()) : cv::countNonZero(mask);
  const double samples = pixels * a.channels();
  const double sse = samples > 0 ? cv::norm(a, b, cv::NORM_L2SQR, mask) : 0.0;
  if (sse == 0.0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 * samples / sse);
}

// Wang et al.'s SSIM map from Gaussian-weighted local statistics, in double
// so that identical images give exactly 1. Borders: OpenCV's default
// reflection (BORDER_REFLECT_101), so every pixel has a full window and the
// map covers the whole image; the result is the mean of the map over pixels
// and channels.
double ssim(const cv::Mat &a, const cv::Mat &b) {
  check_pair(a, b);
  if (a.empty()) return 1.0;
  // Scalar::all: a bare double added to a multi-channel MatExpr is ambiguous
  // in OpenCV (issue 16739).
  const cv::Scalar C1 = cv::Scalar::all((0.01 * 255) * (0.01 * 255));
  const cv::Scalar C2 = cv::Scalar::all((0.03 * 255) * (0.03 * 255));
  const cv::Size win(11, 11);
  constexpr double kSigma = 1.5;
  cv::Mat x, y;
  a.convertTo(x, CV_64F);
  b.convertTo(y, CV_64F);
  auto blur = [&](const cv::Mat &m) {
    cv::Mat o;
    cv::GaussianBlur(m, o, win, kSigma, kSigma);
    return o;
  };
  const cv::Mat mu_x = blur(x), mu_y = blur(y);
  const cv::Mat mu_xx = mu_x.mul(mu_x), mu_yy = mu_y.mul(mu_y), mu_xy = mu_x.mul(mu_y);
  const cv::Mat s_xx = blur(x.mul(x)) - mu_xx;
  const cv::Mat s_yy = blur(y.mul(y)) - mu_yy;
  const cv::Mat s_xy = blur(x.mul(y)) - mu_xy;
  const cv::Mat num = (2 * mu_xy + C1).mul(2 * s_xy + C2);
  const cv::Mat den = (mu_xx + mu_yy + C1).mul(s_xx + s_yy + C2);
  cv::Mat map;
  cv::divide(num, den, map);
  const cv::Scalar per_channel = cv::mean(map);
  double sum = 0.0;
  for (int c = 0; c < a.channels(); ++c) sum += per_channel[c];
  return sum / a.channels();
}

}  // namespace p3d
