#pragma once
/// @file How close a decoded picture is to its source: SSIM and PSNR, as
/// codec comparisons report them.
#include <opencv2/core.hpp>

namespace haptel::video {

/// Mean structural similarity (Wang et al. 2004: an 11x11 Gaussian window of
/// sigma 1.5, K1 = 0.01, K2 = 0.03, L = 255) of the two images' luma (BT.601
/// grey); 1 for identical images. Both CV_8UC3 BGR (or CV_8UC1) of one size;
/// throws std::invalid_argument otherwise.
double Ssim(const cv::Mat& reference, const cv::Mat& picture);

/// Peak signal-to-noise ratio over all channels, dB (255 peak); +infinity
/// for identical images. Same requirements as Ssim.
double PsnrDb(const cv::Mat& reference, const cv::Mat& picture);

}  // namespace haptel::video
