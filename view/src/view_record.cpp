#include "haptel/view/view_record.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace haptel::view {

const char* const kViewRecordIdl =
    R"idl(// haptel/view/view_record.hpp: the operator's view, as haptel replay draws it again.
module haptel {
  module view {
    // Device frame: x forward, y left, z up; m. kind: 0 box (size = half
    // extents), 1 sphere (size[0] = radius), 2 capsule, 3 cylinder (size[0] =
    // radius, size[1] = half length, along local x). rgba: 0..255.
    struct Shape {
      octet kind;
      float position[3];
      float orientation[4];  // w, x, y, z
      float size[3];
      octet rgba[4];
    };
    struct Overlay {
      string interface_name;
      string operator_name;
      double t_s;
      double lap_time_s;
      double time_left_s;
      long gates_passed;
      long gates_total;
      long obstacles_touched;
      string last_contact;
      boolean contact_now;
      boolean hud;
      double speed_mps;
      double speed_max_mps;
      boolean turn_left;
      boolean turn_right;
      boolean throttle_locked;
      string message;
      string status;
      boolean controls_shown;
      boolean guidance_shown;
      double guidance_forward_n;
      double guidance_left_n;
      double guidance_max_n;
      double guidance_ttc_s;
    };
    struct Gaze {
      boolean tracked;
      double look_pan;
      double look_tilt;
      double screen_pan;
      double screen_tilt;
    };
    struct PicturePoint {
      float u;
      float v;
    };
    struct PictureSegment {
      PicturePoint a;
      PicturePoint b;
    };
    struct MapPose {
      float x;
      float y;
      float heading;
      float z;
    };
    struct Prediction {
      boolean shown;
      sequence<PicturePoint, 64> outline;
      sequence<PictureSegment, 48> path;
      MapPose reported;
      MapPose predicted;
      sequence<MapPose, 48> map_path;
      float body_radius;
      float one_way_delay_s;
      boolean heights;
    };
    struct Tile {
      string name;
      octet state;  // 0 driven, 1 held, 2 done, 3 lost
      double lap_time_s;
      long gates_passed;
      long gates_total;
    };
    struct Tiles {
      sequence<Tile, 9> tile;
      string line;
    };
    struct ViewFrame {
      Overlay overlay;
      Gaze gaze;
      Prediction prediction;
      Tiles tiles;
      sequence<Shape> shapes;
      double view_t_s;                  // the view's clock when drawn (s)
      long copies;                      // the live MP4's frames it stands for
      long long video_capture_wall_ns;  // the picture on the screen (video channel's stamp)
      unsigned long long video_id;
      boolean video_stale;              // shown marked stale (waiting for a key frame)
    };
    struct Line {
      double ax;
      double ay;
      double bx;
      double by;
    };
    struct Post {
      double x;
      double y;
      double radius;
      octet kind;  // 0 left, 1 right, 2 obstacle, 3 landing
    };
    struct Label {
      double x;
      double y;
      string text;
    };
    struct TrackMap {
      sequence<Line> walls;
      sequence<Line> gates;
      Line start;
      sequence<Post> posts;
      sequence<Label> labels;
    };
    struct ViewSetup {
      long width;
      long height;
      double rate_hz;
      double record_fps;
      string title;
      double screen_centre[3];
      double screen_width;
      boolean has_map;
      TrackMap map;
    };
  };
};
)idl";

namespace {

constexpr size_t kHeader = 4;  // the encapsulation: CDR_LE, no options

/// Writes CDR: each primitive aligned to its size from the end of the header.
class CdrOut {
 public:
  explicit CdrOut(std::vector<uint8_t>& out) : out_(out) {
    out_.assign(kHeader, 0);
    out_[1] = 0x01;
  }
  template <typename T>
  void Prim(T value) {
    static_assert(std::is_arithmetic_v<T>);
    const size_t at = kHeader + (out_.size() - kHeader + sizeof(T) - 1) / sizeof(T) * sizeof(T);
    Append(at, &value, sizeof(T));
  }
  void Bool(bool& b) { Prim<uint8_t>(b ? 1 : 0); }
  void Octet(uint8_t& v) { Prim(v); }
  void Long(int& v) { Prim<int32_t>(v); }
  void Int64(int64_t& v) { Prim(v); }
  void Uint64(uint64_t& v) { Prim(v); }
  void Double(double& v) { Prim(v); }
  void Float(float& v) { Prim(v); }
  void Float(double& v) { Prim(static_cast<float>(v)); }
  void Unit8(float& v) {
    Prim(static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)));
  }
  void Text(char* text, size_t capacity) {
    const size_t length = strnlen(text, capacity);
    Prim<uint32_t>(static_cast<uint32_t>(length + 1));
    Append(out_.size(), text, length);
    out_.push_back(0);
  }
  void String(std::string& s) {
    Prim<uint32_t>(static_cast<uint32_t>(s.size() + 1));
    Append(out_.size(), s.data(), s.size());
    out_.push_back(0);
  }
  /// A sequence's length; `count` as it is.
  void Count(size_t& count, size_t /*bound*/, const char* /*what*/) {
    Prim<uint32_t>(static_cast<uint32_t>(count));
  }
  static constexpr bool kReading = false;

 private:
  /// `size` bytes at `at` (past the end: the gap zeroed, CDR's padding).
  void Append(size_t at, const void* data, size_t size) {
    out_.resize(at + size, 0);
    if (size > 0) std::memcpy(out_.data() + at, data, size);
  }
  std::vector<uint8_t>& out_;
};

/// Reads what CdrOut wrote; a short or malformed message throws
/// ViewRecordError naming the type and the byte.
class CdrIn {
 public:
  CdrIn(const uint8_t* data, size_t size, const char* type)
      : data_(data), size_(size), type_(type) {
    if (size < kHeader || data[0] != 0x00 || data[1] != 0x01) {
      Fail(0, "the CDR little-endian encapsulation header (00 01 00 00)");
    }
    pos_ = kHeader;
  }
  template <typename T>
  T Prim() {
    const size_t align = sizeof(T);
    while ((pos_ - kHeader) % align != 0) ++pos_;
    if (pos_ + sizeof(T) > size_) Fail(pos_, "more bytes (the message ends early)");
    T value;
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  void Bool(bool& b) { b = Prim<uint8_t>() != 0; }
  void Octet(uint8_t& v) { v = Prim<uint8_t>(); }
  void Long(int& v) { v = Prim<int32_t>(); }
  void Int64(int64_t& v) { v = Prim<int64_t>(); }
  void Uint64(uint64_t& v) { v = Prim<uint64_t>(); }
  void Double(double& v) { v = Prim<double>(); }
  void Float(float& v) { v = Prim<float>(); }
  void Float(double& v) { v = Prim<float>(); }
  void Unit8(float& v) { v = static_cast<float>(Prim<uint8_t>()) / 255.0f; }
  void Text(char* text, size_t capacity) {
    const size_t start = pos_;
    const std::string_view s = Bytes();
    if (s.size() >= capacity) Fail(start, "a string of at most " + std::to_string(capacity - 1));
    std::memcpy(text, s.data(), s.size());
    text[s.size()] = '\0';
  }
  void String(std::string& s) { s = Bytes(); }
  void Count(size_t& count, size_t bound, const char* what) {
    const size_t at = pos_;
    count = Prim<uint32_t>();
    if (count > bound || count > size_ - pos_) {
      Fail(at, std::string("a count of ") + what + " up to " +
                   std::to_string(std::min(bound, size_ - pos_)) + ", not " +
                   std::to_string(count));
    }
  }
  static constexpr bool kReading = true;

 private:
  std::string_view Bytes() {
    const size_t at = pos_;
    const auto length = Prim<uint32_t>();
    if (length == 0 || length > size_ - pos_ || data_[pos_ + length - 1] != 0)
      Fail(at, "a string with its terminating zero");
    const std::string_view s(reinterpret_cast<const char*>(data_ + pos_), length - 1);
    pos_ += length;
    return s;
  }
  [[noreturn]] void Fail(size_t at, const std::string& expected) const {
    throw ViewRecordError(std::string("view record: a ") + type_ + " message of " +
                          std::to_string(size_) + " bytes is not what its schema says: at byte " +
                          std::to_string(at) + " expected " + expected);
  }
  const uint8_t* data_;
  size_t size_;
  const char* type_;
  size_t pos_ = 0;
};

template <typename A, typename T, size_t N>
void Floats(A& a, std::array<T, N>& values) {
  for (T& v : values) a.Float(v);
}

template <typename A>
void Visit(A& a, Shape& s) {
  auto kind = static_cast<uint8_t>(s.kind);
  a.Octet(kind);
  if constexpr (A::kReading) s.kind = static_cast<ShapeKind>(std::min<uint8_t>(kind, 3));
  Floats(a, s.position);
  Floats(a, s.orientation);
  Floats(a, s.size);
  a.Unit8(s.color.r);
  a.Unit8(s.color.g);
  a.Unit8(s.color.b);
  a.Unit8(s.color.a);
}

template <typename A>
void Visit(A& a, Overlay& o) {
  a.Text(o.interface_name, sizeof o.interface_name);
  a.Text(o.operator_name, sizeof o.operator_name);
  a.Double(o.t_s);
  a.Double(o.lap_time_s);
  a.Double(o.time_left_s);
  a.Long(o.gates_passed);
  a.Long(o.gates_total);
  a.Long(o.obstacles_touched);
  a.Text(o.last_contact, sizeof o.last_contact);
  a.Bool(o.contact_now);
  a.Bool(o.hud);
  a.Double(o.speed_mps);
  a.Double(o.speed_max_mps);
  a.Bool(o.turn_left);
  a.Bool(o.turn_right);
  a.Bool(o.throttle_locked);
  a.Text(o.message, sizeof o.message);
  a.Text(o.status, sizeof o.status);
  a.Bool(o.controls_shown);
  a.Bool(o.guidance_shown);
  a.Double(o.guidance_forward_n);
  a.Double(o.guidance_left_n);
  a.Double(o.guidance_max_n);
  a.Double(o.guidance_ttc_s);
}

template <typename A>
void Visit(A& a, Gaze& g) {
  a.Bool(g.tracked);
  a.Double(g.look_pan);
  a.Double(g.look_tilt);
  a.Double(g.screen_pan);
  a.Double(g.screen_tilt);
}

template <typename A>
void Visit(A& a, PicturePoint& p) {
  a.Float(p.u);
  a.Float(p.v);
}

template <typename A>
void Visit(A& a, MapPose& p) {
  a.Float(p.x);
  a.Float(p.y);
  a.Float(p.heading);
  a.Float(p.z);
}

/// A bounded sequence kept in a fixed array with its count.
template <typename A, typename T, size_t N, typename Each>
void Sequence(A& a, int& count, std::array<T, N>& items, const char* what, Each each) {
  size_t n = static_cast<size_t>(std::clamp(count, 0, static_cast<int>(N)));
  a.Count(n, N, what);
  count = static_cast<int>(n);
  for (size_t i = 0; i < n; ++i) each(items[i]);
}

template <typename A>
void Visit(A& a, Prediction& p) {
  a.Bool(p.shown);
  Sequence(a, p.outline_count, p.outline, "outline points", [&](PicturePoint& q) { Visit(a, q); });
  Sequence(a, p.path_count, p.path, "path segments", [&](PictureSegment& s) {
    Visit(a, s.a);
    Visit(a, s.b);
  });
  Visit(a, p.reported);
  Visit(a, p.predicted);
  Sequence(a, p.map_path_count, p.map_path, "map path poses", [&](MapPose& q) { Visit(a, q); });
  a.Float(p.body_radius);
  a.Float(p.one_way_delay_s);
  a.Bool(p.heights);
}

template <typename A>
void Visit(A& a, Tiles& t) {
  Sequence(a, t.count, t.tile, "tiles", [&](Tiles::Tile& tile) {
    a.Text(tile.name, sizeof tile.name);
    auto state = static_cast<uint8_t>(tile.state);
    a.Octet(state);
    if constexpr (A::kReading) tile.state = static_cast<TileState>(std::min<uint8_t>(state, 3));
    a.Double(tile.lap_time_s);
    a.Long(tile.gates_passed);
    a.Long(tile.gates_total);
  });
  a.Text(t.line, sizeof t.line);
}

/// An unbounded sequence held in a vector.
template <typename A, typename T, typename Each>
void Sequence(A& a, std::vector<T>& items, const char* what, Each each) {
  size_t n = items.size();
  a.Count(n, SIZE_MAX, what);
  if constexpr (A::kReading) items.resize(n);
  for (T& item : items) each(item);
}

template <typename A>
void Visit(A& a, ViewFrame& f) {
  Visit(a, f.model.overlay);
  Visit(a, f.model.gaze);
  Visit(a, f.model.prediction);
  Visit(a, f.model.tiles);
  Sequence(a, f.model.shapes, "shapes", [&](Shape& s) { Visit(a, s); });
  a.Double(f.view_t_s);
  a.Long(f.copies);
  a.Int64(f.video_capture_wall_ns);
  a.Uint64(f.video_id);
  a.Bool(f.video_stale);
}

template <typename A>
void Visit(A& a, TrackMap::Line& l) {
  a.Double(l.ax);
  a.Double(l.ay);
  a.Double(l.bx);
  a.Double(l.by);
}

template <typename A>
void Visit(A& a, TrackMap& m) {
  Sequence(a, m.walls, "walls", [&](TrackMap::Line& l) { Visit(a, l); });
  Sequence(a, m.gates, "gates", [&](TrackMap::Line& l) { Visit(a, l); });
  Visit(a, m.start);
  Sequence(a, m.posts, "posts", [&](TrackMap::Post& p) {
    a.Double(p.x);
    a.Double(p.y);
    a.Double(p.radius);
    auto kind = static_cast<uint8_t>(p.kind);
    a.Octet(kind);
    if constexpr (A::kReading) p.kind = static_cast<TrackMap::PostKind>(std::min<uint8_t>(kind, 3));
  });
  Sequence(a, m.labels, "labels", [&](TrackMap::Label& l) {
    a.Double(l.x);
    a.Double(l.y);
    a.String(l.text);
  });
}

template <typename A>
void Visit(A& a, ViewSetup& s, TrackMap& map) {
  a.Long(s.width);
  a.Long(s.height);
  a.Double(s.rate_hz);
  a.Double(s.record_fps);
  a.String(s.title);
  for (double& c : s.screen.centre) a.Double(c);
  a.Double(s.screen.width);
  bool has_map = s.map != nullptr;
  a.Bool(has_map);
  Visit(a, map);
  if constexpr (A::kReading) {
    if (has_map) s.map = std::make_shared<const TrackMap>(map);
  }
}

}  // namespace

void EncodeViewSetup(const ViewSetup& setup, std::vector<uint8_t>& out) {
  CdrOut a(out);
  ViewSetup copy = setup;
  TrackMap map = setup.map ? *setup.map : TrackMap{};
  Visit(a, copy, map);
}

ViewSetup DecodeViewSetup(const uint8_t* data, size_t size) {
  CdrIn a(data, size, kViewSetupSchemaName);
  ViewSetup setup;
  TrackMap map;
  Visit(a, setup, map);
  return setup;
}

void EncodeViewFrame(const ViewFrame& frame, std::vector<uint8_t>& out) {
  CdrOut a(out);
  // The visitor reads and writes through one signature; encoding reads only.
  Visit(a, const_cast<ViewFrame&>(frame));
}

void DecodeViewFrame(const uint8_t* data, size_t size, ViewFrame& frame) {
  CdrIn a(data, size, kViewFrameSchemaName);
  Visit(a, frame);
}

void ViewFrameEncoder::OnFrame(const ViewModel& model, double t_s, int copies) {
  // The fields the channel carries; the pictures stay with the view.
  frame_.model.shapes = model.shapes;  // reuses the capacity
  frame_.model.overlay = model.overlay;
  frame_.model.gaze = model.gaze;
  frame_.model.prediction = model.prediction;
  frame_.model.tiles = model.tiles;
  frame_.view_t_s = t_s;
  frame_.copies = copies;
  frame_.video_capture_wall_ns = model.video.image ? model.video.capture_wall_ns : 0;
  frame_.video_id = model.video.image ? model.video.id : 0;
  frame_.video_stale = model.video.image && model.video.stale;
  EncodeViewFrame(frame_, bytes_);
  ++frames_;
  sink_(bytes_.data(), bytes_.size());
}

std::unique_ptr<ViewFrameEncoder> StartViewRecord(ViewOptions& options,
                                                  std::shared_ptr<const TrackMap> map,
                                                  const ViewFrameEncoder::Sink& write_setup,
                                                  ViewFrameEncoder::Sink write_frame) {
  ViewSetup setup;
  setup.width = options.width;
  setup.height = options.height;
  setup.rate_hz = options.rate_hz;
  setup.record_fps = options.record_fps;
  setup.title = options.title;
  setup.screen = options.screen;
  setup.map = std::move(map);
  std::vector<uint8_t> bytes;
  EncodeViewSetup(setup, bytes);
  write_setup(bytes.data(), bytes.size());
  auto tap = std::make_unique<ViewFrameEncoder>(std::move(write_frame));
  options.tap = tap.get();
  return tap;
}

}  // namespace haptel::view
