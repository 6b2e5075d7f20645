#include "haptel/video/image_quality.hpp"

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace haptel::video {
namespace {

void CheckPair(const cv::Mat& a, const cv::Mat& b, const char* what) {
  if (a.empty() || a.size() != b.size() || a.type() != b.type() ||
      (a.type() != CV_8UC3 && a.type() != CV_8UC1)) {
    throw std::invalid_argument(std::string(what) +
                                ": two 8-bit images of one size and type expected");
  }
}

cv::Mat LumaAsFloat(const cv::Mat& image) {
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = image;
  }
  cv::Mat out;
  grey.convertTo(out, CV_32F);
  return out;
}

}  // namespace

double Ssim(const cv::Mat& reference, const cv::Mat& picture) {
  CheckPair(reference, picture, "Ssim");
  constexpr double kC1 = (0.01 * 255) * (0.01 * 255);
  constexpr double kC2 = (0.03 * 255) * (0.03 * 255);
  const cv::Mat x = LumaAsFloat(reference);
  const cv::Mat y = LumaAsFloat(picture);
  const cv::Size window(11, 11);
  constexpr double kSigma = 1.5;
  cv::Mat mu_x, mu_y, xx, yy, xy;
  cv::GaussianBlur(x, mu_x, window, kSigma);
  cv::GaussianBlur(y, mu_y, window, kSigma);
  cv::GaussianBlur(x.mul(x), xx, window, kSigma);
  cv::GaussianBlur(y.mul(y), yy, window, kSigma);
  cv::GaussianBlur(x.mul(y), xy, window, kSigma);
  const cv::Mat mu_xx = mu_x.mul(mu_x);
  const cv::Mat mu_yy = mu_y.mul(mu_y);
  const cv::Mat mu_xy = mu_x.mul(mu_y);
  const cv::Mat sigma_xx = xx - mu_xx;
  const cv::Mat sigma_yy = yy - mu_yy;
  const cv::Mat sigma_xy = xy - mu_xy;
  cv::Mat numerator = (2 * mu_xy + kC1).mul(2 * sigma_xy + kC2);
  cv::Mat denominator = (mu_xx + mu_yy + kC1).mul(sigma_xx + sigma_yy + kC2);
  cv::Mat map;
  cv::divide(numerator, denominator, map);
  return cv::mean(map)[0];
}

double PsnrDb(const cv::Mat& reference, const cv::Mat& picture) {
  CheckPair(reference, picture, "PsnrDb");
  const double squared = cv::norm(reference, picture, cv::NORM_L2SQR);
  if (squared == 0.0) return std::numeric_limits<double>::infinity();
  const double mse = squared / static_cast<double>(reference.total() * reference.channels());
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

}  // namespace haptel::video
