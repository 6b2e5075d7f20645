#include "tiles_layer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace haptel::view {

namespace {

const char* TileStateText(TileState state) {
  return state == TileState::kDriven ? "DRIVEN"
         : state == TileState::kHeld ? "held"
         : state == TileState::kDone ? "done"
                                     : "LOST";
}

/// The tiles' text at 576 px high, and its two lines' height under the picture.
constexpr double kTileTextScale = 0.40;
constexpr int kTileTextHeight = 34;

}  // namespace

std::string TileText(const Tiles::Tile& tile) {
  const TileLabel label = TileLabelFor(tile, 1 << 20, 576);
  return label.lines[0] + "  " + label.lines[1];
}

TileLabel TileLabelFor(const Tiles::Tile& tile, int tile_width, int view_height) {
  TileLabel label;
  char text[64];
  std::snprintf(text, sizeof text, "%s %s", tile.name, TileStateText(tile.state));
  label.lines[0] = text;
  std::snprintf(text, sizeof text, "lap %.1f s  %d/%d", tile.lap_time_s, tile.gates_passed,
                tile.gates_total);
  label.lines[1] = text;
  const double base = kTileTextScale * view_height / 576.0;
  const int room = std::max(1, tile_width - 2 * label.margin);
  int widest = 1, base_line = 0;
  for (const std::string& line : label.lines) {
    widest = std::max(widest,
                      cv::getTextSize(line, cv::FONT_HERSHEY_SIMPLEX, base, 1, &base_line).width);
  }
  // Text width is proportional to the scale; floor so rounding never spills.
  label.scale = widest <= room ? base : std::floor(base * room / widest * 100.0) / 100.0;
  label.line_height = std::max(1, kTileTextHeight * view_height / 576 / 2);
  return label;
}

TileBox TileRect(int index, int count, int width, int height) {
  // Up to four at 18% of the width; more shrink so the column still fits.
  const int gap = 6;
  const int line_h = static_cast<int>(kTileTextHeight * height / 576.0);
  int tile_w = static_cast<int>(0.18 * width);
  const int n = std::max(count, 1);
  const int room = height - 16 - (n - 1) * gap;
  if (n * (tile_w * 3 / 4 + line_h) > room) tile_w = (room / n - line_h) * 4 / 3;
  const int tile_h = tile_w * 3 / 4 + line_h;
  return {width - tile_w - 8, 8 + index * (tile_h + gap), tile_w, tile_h};
}

namespace layers {
namespace {
const cv::Scalar kFrameColour = Bgra(kTileFrameBgr[0], kTileFrameBgr[1], kTileFrameBgr[2]);
}  // namespace

TilesLayer::TilesLayer(const TexturedQuads& quads)
    : quads_(quads), line_texture_(MakeTexture()), column_texture_(MakeTexture()) {}

TilesLayer::~TilesLayer() {
  glDeleteTextures(1, &line_texture_);
  glDeleteTextures(1, &column_texture_);
}

void TilesLayer::Draw(const ViewModel& model, const Frame& frame) {
  const int count = std::clamp(model.tiles.count, 0, Tiles::kMax);
  if (count == 0) return;
  quads_.BeginOverWorld();
  if (model.tiles.line[0] != '\0') DrawLine(model.tiles, frame);
  DrawColumn(model, count, frame);
}

void TilesLayer::DrawLine(const Tiles& tiles, const Frame& frame) {
  // Bottom left, above the person's message.
  glBindTexture(GL_TEXTURE_2D, line_texture_);
  if (line_shown_ != tiles.line) {
    line_shown_ = tiles.line;
    const double scale = 0.55 * frame.height / 576.0;
    const int line_h = static_cast<int>(26 * frame.height / 576.0);
    int base = 0;
    const cv::Size ts = cv::getTextSize(tiles.line, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base);
    const cv::Point at(16, frame.height - 24 - 2 * line_h);
    const cv::Rect box(at.x - 8, at.y - ts.height - 8, ts.width + 16, ts.height + 16);
    line_box_ = box & cv::Rect(0, 0, frame.width, frame.height);
    line_ = cv::Mat(line_box_.size(), CV_8UC4, Bgra(0, 0, 0, 160));
    cv::putText(line_, tiles.line, at - line_box_.tl(), cv::FONT_HERSHEY_SIMPLEX, scale,
                kFrameColour, 1, cv::LINE_AA);
    UploadBgra(line_);
  }
  quads_.DrawPixels(line_box_, frame.width, frame.height);
}

void TilesLayer::DrawColumn(const ViewModel& model, int count, const Frame& frame) {
  const TileBox first = TileRect(0, count, frame.width, frame.height);
  const TileBox last = TileRect(count - 1, count, frame.width, frame.height);
  const cv::Rect column(first.x, first.y, first.width, last.y + last.height - first.y);
  std::string key;
  for (int i = 0; i < count; ++i) {
    key += TileText(model.tiles.tile[static_cast<size_t>(i)]);
    key += '#' + std::to_string(model.tile_video[static_cast<size_t>(i)].id) + '\n';
  }
  glBindTexture(GL_TEXTURE_2D, column_texture_);
  if (key != column_key_ || column_.size() != column.size()) {
    column_key_ = key;
    RasteriseColumn(model, count, column, frame);
    UploadBgra(column_);
  }
  quads_.DrawPixels(column, frame.width, frame.height);
}

void TilesLayer::RasteriseColumn(const ViewModel& model, int count, const cv::Rect& column,
                                 const Frame& frame) {
  if (column_.size() != column.size()) column_ = cv::Mat(column.height, column.width, CV_8UC4);
  column_.setTo(cv::Scalar(0, 0, 0, 0));
  for (int i = 0; i < count; ++i) {
    const Tiles::Tile& tile = model.tiles.tile[static_cast<size_t>(i)];
    const TileBox box = TileRect(i, count, frame.width, frame.height);
    const cv::Rect at(box.x - column.x, box.y - column.y, box.width, box.height);
    const int picture_h = box.width * 3 / 4;
    const cv::Rect picture(at.x, at.y, at.width, picture_h);
    cv::rectangle(column_, at, Bgra(0, 0, 0, 190), cv::FILLED);
    const cv::Mat* image = model.tile_video[static_cast<size_t>(i)].image.get();
    if (image != nullptr && !image->empty() && image->type() == CV_8UC3) {
      cv::resize(*image, tile_picture_, picture.size(), 0, 0, cv::INTER_AREA);
      cv::cvtColor(tile_picture_, column_(picture), cv::COLOR_BGR2BGRA);
    } else {
      cv::rectangle(column_, picture, Bgra(40, 40, 40), cv::FILLED);
    }
    if (tile.state == TileState::kLost) {
      // Its last picture is stale: crossed out.
      cv::line(column_, picture.tl(), picture.br(), Bgra(0, 0, 255), 3, cv::LINE_AA);
      cv::line(column_, cv::Point(picture.x + picture.width, picture.y),
               cv::Point(picture.x, picture.y + picture.height), Bgra(0, 0, 255), 3, cv::LINE_AA);
    }
    const TileLabel label = TileLabelFor(tile, box.width, frame.height);
    for (size_t line = 0; line < label.lines.size(); ++line) {
      const int baseline = at.y + picture_h + static_cast<int>(line + 1) * label.line_height - 3;
      cv::putText(column_, label.lines[line], cv::Point(at.x + label.margin, baseline),
                  cv::FONT_HERSHEY_SIMPLEX, label.scale, Bgra(255, 255, 255), 1, cv::LINE_AA);
    }
    if (tile.state == TileState::kDriven) cv::rectangle(column_, at, kFrameColour, 4);
  }
}

}  // namespace layers
}  // namespace haptel::view
