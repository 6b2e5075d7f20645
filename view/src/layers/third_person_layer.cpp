#include "third_person_layer.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace haptel::view {

TileBox ThirdPersonLabelRect(int width, int height) {
  const double k = height / 576.0;
  // Under the overlay's text panel (five lines at most), above the message
  // line at the bottom.
  const int top = static_cast<int>(158 * k);
  const int line_h = static_cast<int>(22 * k);
  const int room = height - top - line_h - static_cast<int>(60 * k);
  const int picture_w = std::max(4, std::min(static_cast<int>(0.30 * width), room * 4 / 3));
  return {8, top, picture_w, line_h};
}

TileBox ThirdPersonRect(int width, int height) {
  const TileBox label = ThirdPersonLabelRect(width, height);
  return {label.x, label.y + label.height, label.width, label.width * 3 / 4};
}

namespace layers {

ThirdPersonLayer::ThirdPersonLayer(int width, int height, const TexturedQuads& quads)
    : quads_(quads) {
  const TileBox label = ThirdPersonLabelRect(width, height);
  const TileBox picture = ThirdPersonRect(width, height);
  picture_rect_ = cv::Rect(picture.x, picture.y, picture.width, picture.height);
  frame_rect_ = cv::Rect(label.x - 3, label.y, label.width + 6, label.height + picture.height + 3) &
                cv::Rect(0, 0, width, height);
  // The frame, dark, and the label on it; the picture goes over the frame.
  cv::Mat frame(frame_rect_.size(), CV_8UC4, Bgra(0, 0, 0, 200));
  cv::putText(frame, kThirdPersonLabel,
              cv::Point(label.x + 4 - frame_rect_.x, label.y + label.height - 6 - frame_rect_.y),
              cv::FONT_HERSHEY_SIMPLEX, 0.5 * height / 576.0, Bgra(255, 255, 255), 1, cv::LINE_AA);
  frame_texture_ = MakeTexture();
  UploadBgra(frame);
  picture_texture_ = MakeTexture();  // its storage comes with the first picture
}

ThirdPersonLayer::~ThirdPersonLayer() {
  glDeleteTextures(1, &frame_texture_);
  glDeleteTextures(1, &picture_texture_);
}

void ThirdPersonLayer::Draw(const ViewModel& model, const Frame& frame) {
  const cv::Mat* picture = model.third_person.image.get();
  if (picture == nullptr || picture->empty() || picture->type() != CV_8UC3) return;
  quads_.BeginOverWorld();
  glBindTexture(GL_TEXTURE_2D, frame_texture_);
  quads_.DrawPixels(frame_rect_, frame.width, frame.height);
  glBindTexture(GL_TEXTURE_2D, picture_texture_);
  if (model.third_person.id != shown_id_ || picture->cols != picture_cols_ ||
      picture->rows != picture_rows_) {
    UploadBgr(*picture, picture_cols_, picture_rows_);
    shown_id_ = model.third_person.id;
  }
  quads_.DrawPixels(picture_rect_, frame.width, frame.height);
}

}  // namespace layers
}  // namespace haptel::view
