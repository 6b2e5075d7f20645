// The view channel of a session file: a frame's model and the view's set-up
// come back as they went in (floats to float precision, colours to 1/255),
// and a message that is not what the schema says is refused by name.
#include <catch2/catch.hpp>
#include <cstring>
#include <string>
#include <vector>

#include "haptel/view/view_record.hpp"

using namespace haptel;
using namespace haptel::view;

namespace {

ViewFrame SomeFrame() {
  ViewFrame f;
  std::snprintf(f.model.overlay.interface_name, sizeof f.model.overlay.interface_name,
                "cockpit-hud");
  std::snprintf(f.model.overlay.message, sizeof f.model.overlay.message, "grasp the wheel");
  f.model.overlay.t_s = 12.25;
  f.model.overlay.lap_time_s = 3.5;
  f.model.overlay.gates_passed = 2;
  f.model.overlay.gates_total = 5;
  f.model.overlay.hud = true;
  f.model.overlay.speed_mps = 0.42;
  f.model.overlay.turn_right = true;
  f.model.overlay.guidance_ttc_s = -1.0;
  f.model.gaze.tracked = true;
  f.model.gaze.look_pan = 0.3;
  f.model.prediction.shown = true;
  f.model.prediction.outline_count = 3;
  f.model.prediction.outline[2] = {0.25f, 0.75f};
  f.model.prediction.path_count = 1;
  f.model.prediction.path[0] = {{0.1f, 0.2f}, {0.3f, 0.4f}};
  f.model.prediction.map_path_count = 2;
  f.model.prediction.map_path[1] = {1.5f, -2.0f, 0.5f, 0.0f};
  f.model.prediction.predicted = {1.0f, 2.0f, 3.0f, 0.0f};
  f.model.tiles.count = 2;
  std::snprintf(f.model.tiles.tile[1].name, sizeof f.model.tiles.tile[1].name, "robot-b");
  f.model.tiles.tile[1].state = TileState::kDone;
  std::snprintf(f.model.tiles.line, sizeof f.model.tiles.line, "driving robot-a");
  Shape palm;
  palm.kind = ShapeKind::kBox;
  palm.position = {0.1, -0.2, 0.3};
  palm.orientation = {0.5, 0.5, 0.5, 0.5};
  palm.size = {0.04, 0.05, 0.01};
  palm.color = {0.93f, 0.76f, 0.64f, 0.4f};
  Shape tip = palm;
  tip.kind = ShapeKind::kCapsule;
  tip.position = {0.2, 0.0, 0.25};
  f.model.shapes = {palm, tip};
  f.view_t_s = 7.125;
  f.copies = 2;
  f.video_capture_wall_ns = 1'700'000'000'123'456'789;
  f.video_id = 41;
  f.video_stale = true;
  return f;
}

}  // namespace

TEST_CASE("a view frame comes back from its CDR as it was drawn") {
  const ViewFrame in = SomeFrame();
  std::vector<uint8_t> bytes;
  EncodeViewFrame(in, bytes);
  REQUIRE(bytes.size() > 4);
  CHECK(bytes[0] == 0x00);
  CHECK(bytes[1] == 0x01);  // CDR little endian
  ViewFrame out;
  out.model.shapes.resize(9);  // reused, not appended to
  DecodeViewFrame(bytes.data(), bytes.size(), out);

  CHECK(std::string(out.model.overlay.interface_name) == "cockpit-hud");
  CHECK(std::string(out.model.overlay.message) == "grasp the wheel");
  CHECK(out.model.overlay.t_s == 12.25);
  CHECK(out.model.overlay.gates_passed == 2);
  CHECK(out.model.overlay.hud);
  CHECK(out.model.overlay.turn_right);
  CHECK_FALSE(out.model.overlay.turn_left);
  CHECK(out.model.overlay.speed_mps == 0.42);
  CHECK(out.model.gaze.tracked);
  CHECK(out.model.gaze.look_pan == 0.3);
  CHECK(out.model.prediction.outline_count == 3);
  CHECK(out.model.prediction.outline[2].v == 0.75f);
  CHECK(out.model.prediction.path_count == 1);
  CHECK(out.model.prediction.path[0].b.u == 0.3f);
  CHECK(out.model.prediction.map_path[1].y == -2.0f);
  CHECK(out.model.prediction.predicted.heading == 3.0f);
  CHECK(out.model.tiles.count == 2);
  CHECK(std::string(out.model.tiles.tile[1].name) == "robot-b");
  CHECK(out.model.tiles.tile[1].state == TileState::kDone);
  CHECK(std::string(out.model.tiles.line) == "driving robot-a");
  REQUIRE(out.model.shapes.size() == 2);
  const Shape& tip = out.model.shapes[1];
  CHECK(tip.kind == ShapeKind::kCapsule);
  CHECK(tip.position[0] == Approx(0.2).epsilon(1e-6));
  CHECK(tip.position[2] == Approx(0.25).epsilon(1e-6));
  CHECK(tip.orientation[3] == Approx(0.5).epsilon(1e-6));
  CHECK(tip.size[1] == Approx(0.05).epsilon(1e-6));
  CHECK(tip.color.r == Approx(0.93f).margin(0.5 / 255));
  CHECK(tip.color.a == Approx(0.4f).margin(0.5 / 255));
  CHECK(out.view_t_s == 7.125);
  CHECK(out.copies == 2);
  CHECK(out.video_capture_wall_ns == 1'700'000'000'123'456'789);
  CHECK(out.video_id == 41);
  CHECK(out.video_stale);
}

TEST_CASE("the view's set-up comes back with its map, and without one") {
  ViewSetup in;
  in.width = 640;
  in.height = 360;
  in.record_fps = 25.0;
  in.title = "Haptel - lap";
  in.screen = DirectViewScreen();
  auto map = std::make_shared<TrackMap>();
  map->walls.push_back({0, 0, 4, 0});
  map->gates.push_back({1, -0.5, 1, 0.5});
  map->start = {0, -1, 0, 1};
  map->posts.push_back({1, 0.5, 0.05, TrackMap::PostKind::kRight});
  map->labels.push_back({2, 2, "1.0-3.0 m"});
  in.map = map;
  std::vector<uint8_t> bytes;
  EncodeViewSetup(in, bytes);
  const ViewSetup out = DecodeViewSetup(bytes.data(), bytes.size());
  CHECK(out.width == 640);
  CHECK(out.height == 360);
  CHECK(out.record_fps == 25.0);
  CHECK(out.title == "Haptel - lap");
  CHECK(out.screen.centre == DirectViewScreen().centre);
  CHECK(out.screen.width == DirectViewScreen().width);
  REQUIRE(out.map != nullptr);
  CHECK(out.map->walls.size() == 1);
  CHECK(out.map->walls[0].bx == 4);
  CHECK(out.map->start.ay == -1);
  REQUIRE(out.map->posts.size() == 1);
  CHECK(out.map->posts[0].kind == TrackMap::PostKind::kRight);
  REQUIRE(out.map->labels.size() == 1);
  CHECK(out.map->labels[0].text == "1.0-3.0 m");

  in.map = nullptr;
  EncodeViewSetup(in, bytes);
  CHECK(DecodeViewSetup(bytes.data(), bytes.size()).map == nullptr);
}

TEST_CASE("a view message that is not what its schema says is refused, naming the byte") {
  std::vector<uint8_t> bytes;
  EncodeViewFrame(SomeFrame(), bytes);
  ViewFrame out;
  // Cut short.
  CHECK_THROWS_WITH(
      DecodeViewFrame(bytes.data(), bytes.size() - 3, out),
      Catch::Contains("haptel::view::ViewFrame") && Catch::Contains("the message ends early"));
  // Not CDR little endian.
  std::vector<uint8_t> big = bytes;
  big[1] = 0x00;
  CHECK_THROWS_WITH(DecodeViewFrame(big.data(), big.size(), out),
                    Catch::Contains("encapsulation header"));
  // A tile count past the IDL's bound of 9 (the tiles' sequence follows the
  // prediction: find it by encoding a frame with none, then 200).
  ViewFrame none = SomeFrame();
  none.model.tiles.count = 0;
  std::vector<uint8_t> a;
  EncodeViewFrame(none, a);
  ViewFrame one = none;
  one.model.tiles.count = 1;
  std::vector<uint8_t> b;
  EncodeViewFrame(one, b);
  size_t at = 0;
  while (at < a.size() && a[at] == b[at]) ++at;
  REQUIRE(at < a.size());
  a[at] = 200;
  CHECK_THROWS_WITH(DecodeViewFrame(a.data(), a.size(), out),
                    Catch::Contains("a count of tiles up to 9, not 200"));
}

TEST_CASE("the view channel's tap passes each frame on encoded, with the picture's stamp") {
  std::vector<uint8_t> got;
  ViewFrameEncoder tap([&](const uint8_t* data, size_t size) { got.assign(data, data + size); });
  ViewFrame f = SomeFrame();
  f.model.video.image = std::make_shared<const cv::Mat>(2, 2, CV_8UC3);
  f.model.video.id = 7;
  f.model.video.capture_wall_ns = 99;
  tap.OnFrame(f.model, 1.5, 3);
  CHECK(tap.frames() == 1);
  ViewFrame out;
  DecodeViewFrame(got.data(), got.size(), out);
  CHECK(out.view_t_s == 1.5);
  CHECK(out.copies == 3);
  CHECK(out.video_capture_wall_ns == 99);
  CHECK(out.video_id == 7);
  CHECK(out.model.shapes.size() == 2);
}
