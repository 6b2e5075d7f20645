#include "ghost_layer.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace haptel::view::layers {
namespace {

/// Draws the prediction's ghost and path into `ghost` (BGRA, the picture's
/// size; transparent where nothing is). Returns the rectangle it drew in
/// (empty: nothing in sight).
cv::Rect DrawGhost(cv::Mat& ghost, const Prediction& p) {
  const double w = ghost.cols, h = ghost.rows;
  const int thickness = std::max(3, ghost.cols / 160);  // 4 px in a 640-pixel picture
  double x0 = w, y0 = h, x1 = 0, y1 = 0;
  const auto at = [&](const PicturePoint& q) {
    const double x = q.u * w, y = q.v * h;
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
    return Fixed(x - 0.5, y - 0.5);  // OpenCV's coordinates are pixel centres
  };
  // The ghost's body see-through, the path over it (it runs on under the
  // ghost, on the floor the body hides), the ghost's outline last.
  const int n = std::clamp(p.outline_count, 0, Prediction::kOutlineMax);
  std::array<cv::Point, Prediction::kOutlineMax> pts;
  for (int i = 0; i < n; ++i) pts[static_cast<size_t>(i)] = at(p.outline[static_cast<size_t>(i)]);
  if (n >= 3) cv::fillConvexPoly(ghost, pts.data(), n, kGhostFill, cv::LINE_AA, kShift);
  for (int i = 0; i < std::clamp(p.path_count, 0, Prediction::kPathMax); ++i) {
    const cv::Point a = at(p.path[static_cast<size_t>(i)].a);
    const cv::Point b = at(p.path[static_cast<size_t>(i)].b);
    cv::line(ghost, a, b, kGhostLine, thickness, cv::LINE_AA, kShift);
  }
  if (n >= 3) {
    const cv::Point* poly = pts.data();
    cv::polylines(ghost, &poly, &n, 1, true, kGhostLine, thickness, cv::LINE_AA, kShift);
  }
  if (x1 < x0 || y1 < y0) return {};
  const int pad = thickness + 2;
  const cv::Rect drawn(
      cv::Point(static_cast<int>(std::floor(x0)) - pad, static_cast<int>(std::floor(y0)) - pad),
      cv::Point(static_cast<int>(std::ceil(x1)) + pad, static_cast<int>(std::ceil(y1)) + pad));
  return drawn & cv::Rect(0, 0, ghost.cols, ghost.rows);
}

}  // namespace

GhostLayer::GhostLayer(const VideoScreen& screen, const TexturedQuads& quads)
    : screen_(screen), quads_(quads), texture_(MakeTexture()) {}

GhostLayer::~GhostLayer() { glDeleteTextures(1, &texture_); }

void GhostLayer::Draw(const ViewModel& model, const Frame& frame) {
  const Prediction& pr = model.prediction;
  if (!pr.shown || screen_.picture_cols <= 0) return;
  glBindTexture(GL_TEXTURE_2D, texture_);
  if (ghost_.cols != screen_.picture_cols || ghost_.rows != screen_.picture_rows) {
    ghost_ = cv::Mat(screen_.picture_rows, screen_.picture_cols, CV_8UC4, cv::Scalar(0, 0, 0, 0));
    drawn_ = {};
    UploadBgra(ghost_);
  }
  ghost_(drawn_).setTo(cv::Scalar(0, 0, 0, 0));
  drawn_ = DrawGhost(ghost_, pr);
  const cv::Rect& r = drawn_;
  if (r.empty()) return;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, ghost_.cols);
  glTexSubImage2D(GL_TEXTURE_2D, 0, r.x, r.y, r.width, r.height, GL_BGRA, GL_UNSIGNED_BYTE,
                  ghost_.ptr(r.y, r.x));
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  // Only the rectangle holding the ghost, on the screen's own plane (the
  // unit quad's y and z run from the picture's left and top edges, +1, to
  // its right and bottom, -1), pulled a hair towards the eye so that it
  // wins the depth test against the picture and still loses it to a hand
  // in front of the screen.
  const double u0 = static_cast<double>(r.x) / ghost_.cols,
               u1 = static_cast<double>(r.x + r.width) / ghost_.cols;
  const double v0 = static_cast<double>(r.y) / ghost_.rows,
               v1 = static_cast<double>(r.y + r.height) / ghost_.rows;
  Eigen::Affine3f part = Eigen::Affine3f::Identity();
  part.translate(Eigen::Vector3f(0.0f, static_cast<float>(1.0 - (u0 + u1)),
                                 static_cast<float>(1.0 - (v0 + v1))));
  part.scale(Eigen::Vector3f(1.0f, static_cast<float>(u1 - u0), static_cast<float>(v1 - v0)));
  quads_.BeginInWorld();
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(-1.0f, -1.0f);
  quads_.DrawScreenQuad(frame.view_projection * (screen_.QuadModel() * part.matrix()),
                        {static_cast<float>(u0), static_cast<float>(v0),
                         static_cast<float>(u1 - u0), static_cast<float>(v1 - v0)});
  glDisable(GL_POLYGON_OFFSET_FILL);
}

}  // namespace haptel::view::layers
