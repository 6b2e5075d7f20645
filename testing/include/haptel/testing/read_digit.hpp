#pragma once
/// @file Reading a gate's number off a picture, as a person would by its
/// shape (issue 38: a zoomed-in surveillance picture shows a number the wide
/// view cannot): each digit drawn in the gate labels' font (Hershey simplex,
/// thickness 4 at scale 2), at scales from 0.5 to 3, slid over the
/// picture's white pixels; the best overlap wins. Header only (OpenCV).
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

namespace haptel::testing {

/// Pixels white enough to be a gate number's fill (the sky never is): 0/255.
inline cv::Mat WhiteMask(const cv::Mat& bgr) {
  cv::Mat white;
  cv::inRange(bgr, cv::Scalar(236, 236, 236), cv::Scalar(255, 255, 255), white);
  return white;
}

struct DigitReading {
  int digit = -1;
  double score = 0.0;  ///< intersection over union of the template and the picture's white
};

/// The digit `white` (0/255, WhiteMask) shows best, and how well.
inline DigitReading ReadDigit(const cv::Mat& white) {
  cv::Mat picture;
  white.convertTo(picture, CV_32F, 1.0 / 255.0);
  cv::Mat sums;
  cv::integral(picture, sums, CV_64F);
  DigitReading best;
  for (int digit = 0; digit <= 9; ++digit) {
    const std::string text = std::to_string(digit);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 2.0, 4, &baseline);
    cv::Mat glyph = cv::Mat::zeros(size.height + 8, size.width + 8, CV_8UC1);
    cv::putText(glyph, text, cv::Point(4, 4 + size.height), cv::FONT_HERSHEY_SIMPLEX, 2.0,
                cv::Scalar(255), 4, cv::LINE_AA);
    cv::threshold(glyph, glyph, 127, 255, cv::THRESH_BINARY);
    glyph = glyph(cv::boundingRect(glyph)).clone();
    for (double scale = 0.5; scale <= 3.0; scale += 0.1) {
      cv::Mat t;
      cv::resize(glyph, t, cv::Size(), scale, scale, cv::INTER_NEAREST);
      if (t.rows >= picture.rows || t.cols >= picture.cols) continue;
      cv::Mat tf;
      t.convertTo(tf, CV_32F, 1.0 / 255.0);
      const double glyph_pixels = cv::sum(tf)[0];
      cv::Mat overlap;
      cv::matchTemplate(picture, tf, overlap, cv::TM_CCORR);
      for (int y = 0; y < overlap.rows; ++y) {
        for (int x = 0; x < overlap.cols; ++x) {
          const double both = overlap.at<float>(y, x);
          if (both < 0.3 * glyph_pixels) continue;
          const double window = sums.at<double>(y + t.rows, x + t.cols) -
                                sums.at<double>(y, x + t.cols) - sums.at<double>(y + t.rows, x) +
                                sums.at<double>(y, x);
          const double iou = both / (glyph_pixels + window - both);
          if (iou > best.score) best = {digit, iou};
        }
      }
    }
  }
  return best;
}

}  // namespace haptel::testing
