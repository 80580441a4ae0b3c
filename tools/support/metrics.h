// Image quality metrics on 8-bit images (any channel count; alpha is the
// caller's business: pass 3-channel images to leave it out).
#pragma once

#include <opencv2/core.hpp>

namespace p3d {

// PSNR in dB over all channels; `mask` (CV_8U, non-zero = counted) optional.
// Identical images give +infinity.
double psnr(const cv::Mat &a, const cv::Mat &b, const cv::Mat &mask = cv::Mat());

// Mean SSIM (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 0.01,
// K2 0.03, L 255) over all channels.
double ssim(const cv::Mat &a, const cv::Mat &b);

}  // namespace p3d
