#include "screen_layer.hpp"

namespace haptel::view::layers {

std::array<double, 3> VideoScreen::AboutEyeOf(const std::array<double, 3>& point) const {
  return AboutEye(turn, point);
}

Eigen::Matrix4f VideoScreen::QuadModel() const {
  const double hw = placement.width / 2.0;
  return Model(Centre(), Orientation(),
               {1.0f, static_cast<float>(hw), static_cast<float>(hw * aspect)});
}

ScreenLayer::ScreenLayer(VideoScreen& screen, const TexturedQuads& quads)
    : screen_(screen), quads_(quads), texture_(MakeTexture()) {
  const uint8_t grey[3] = {40, 40, 40};  // no video yet: a dark screen
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, 1, 1, 0, GL_BGR, GL_UNSIGNED_BYTE, grey);
}

ScreenLayer::~ScreenLayer() { glDeleteTextures(1, &texture_); }

void ScreenLayer::Draw(const ViewModel& model, const Frame& frame) {
  quads_.BeginInWorld();  // the picture is opaque: blending leaves it as it is
  glBindTexture(GL_TEXTURE_2D, texture_);
  const cv::Mat* image = model.video.image.get();
  if (image != nullptr && !image->empty() && image->type() == CV_8UC3 &&
      model.video.id != shown_id_) {
    UploadBgr(*image, screen_.picture_cols, screen_.picture_rows);
    screen_.aspect = static_cast<double>(screen_.picture_rows) / screen_.picture_cols;
    shown_id_ = model.video.id;
  }
  quads_.DrawScreenQuad(frame.view_projection * screen_.QuadModel());
}

}  // namespace haptel::view::layers
