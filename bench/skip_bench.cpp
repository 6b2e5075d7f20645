#include "skip_bench.hpp"

#include <time.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/physics/cockpit_controls.hpp"
#include "haptel/physics/scene_builder.hpp"
#include "haptel/physics/world.hpp"
#include "haptel/testing/vec_math.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/codec.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

using haptics::Side;

constexpr double kWarmupS = 2.5;  ///< Bullet: asleep after 2 s at rest
constexpr double kBoxHalf = 0.05;
/// m, device frame: a floor under the controls (the rim's bottom is at
/// −0.13 m, the knob's at −0.075 m).
constexpr double kFloorZ = -0.4;

struct Result {
  std::string name;
  std::string description;
  bool world = false;
  int boxes = 0;
  int boxes_asleep = 0;
  int boxes_parked = 0;  ///< of those asleep, out of the Bullet world (PhysicsWorld::BodyParked)
  long steps = 0;
  double sim_s = 0.0;
  double cpu_s = 0.0;
  int max_wheel_contacts = 0;               ///< hand bodies on the rim, at most, while timed
  double wheel_min = 0.0, wheel_max = 0.0;  ///< rad, wheel angle range while timed
  double cpu_per_sim_s() const { return sim_s > 0.0 ? cpu_s / sim_s : 0.0; }
};

/// The floor under the cockpit and `n` 10 cm boxes resting on it: the cells
/// of a 0.3 m grid outside the cockpit's footprint, nearest first, each
/// jittered and turned. Dynamic boxes fall asleep; static ones never move.
Scene FloorScene(int n, bool dynamic) {
  Scene scene;
  SceneObject floor;
  floor.name = "floor";
  SceneShape plane;
  plane.kind = ShapeKind::kPlane;
  plane.normal = Eigen::Vector3d::UnitZ();
  plane.offset = kFloorZ;
  floor.shapes.push_back(plane);
  scene.objects.push_back(floor);

  struct Cell {
    double x, y;
  };
  std::vector<Cell> cells;
  const double pitch = 0.3;
  for (int i = -40; i <= 40; ++i) {
    for (int j = -40; j <= 40; ++j) {
      const double x = i * pitch, y = j * pitch;
      if (std::abs(x) < 0.8 && std::abs(y) < 0.6) continue;  // under and next to the controls
      cells.push_back({x, y});
    }
  }
  std::stable_sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) {
    return a.x * a.x + a.y * a.y < b.x * b.x + b.y * b.y;
  });
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  for (int k = 0; k < n && k < static_cast<int>(cells.size()); ++k) {
    SceneObject o;
    o.name = "floor_box_" + std::to_string(k);
    o.dynamic = dynamic;
    o.mass = dynamic ? 0.5 : 0.0;
    o.position = {cells[k].x + jitter(rng), cells[k].y + jitter(rng), kFloorZ + kBoxHalf};
    o.rotation = Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    SceneShape s;
    s.kind = ShapeKind::kBox;
    s.half_extents = Eigen::Vector3d::Constant(kBoxHalf);
    o.shapes.push_back(s);
    scene.objects.push_back(std::move(o));
  }
  return scene;
}

/// The operator at the controls: the right palm resting on the top of the rim
/// (3 mm into it, ≈ 9 N at the shipped coupling), fingers open over it, turning
/// the wheel ±0.2 rad at 0.5 Hz; the left hand hovering 3 cm over the throttle
/// knob, moving 2 cm at 0.5 Hz.
struct Operator {
  const CockpitConfig& cockpit;
  const PhysicsConfig& physics;

  haptics::HandSample Right(double t) const {
    const auto& hub = cockpit.wheel_hub;
    const double rim = physics::ControlsBodyConfig{}.rim_radius;
    const double press = 0.003;
    const double above = cockpit.wheel_radius + rim + physics.hand.phalanx_radius - press;
    // Palm down, the rim under the metacarpals (as tests/physics/test_cockpit_controls.cpp).
    const double x = hub[0] - 0.115;
    const double angle = 0.2 * std::sin(M_PI * t);  // about −x: + = left
    const double c = std::cos(angle), sn = std::sin(angle);
    return haptics::TrackedHand({x, hub[1] + sn * above, hub[2] + c * above},
                                {std::cos(0.5 * angle), -std::sin(0.5 * angle), 0.0, 0.0});
  }

  haptics::HandSample Left(double t) const {
    const auto& knob = cockpit.throttle_centre;
    const physics::ControlsBodyConfig body;
    const double gap = 0.03;
    const double z = knob[2] + body.knob_half_extents[2] + physics.hand.palm_half_extents[2] + gap;
    const double w = M_PI;  // 0.5 Hz
    return haptics::TrackedHand(
        {knob[0] - physics.hand.palm_half_extents[0] + 0.02 * std::sin(w * t),
         knob[1] + 0.02 * std::cos(w * t), z});
  }
};

/// Steps for `seconds`; with `timed`, adds the thread CPU time of the stepping
/// (blocks of 10 steps) to it and samples the controls between blocks, untimed
/// (Read walks every contact manifold, the floor boxes' too).
void Run(physics::PhysicsWorld& world, physics::CockpitControlsBody& controls, const Operator& op,
         double& t, double seconds, Result* timed) {
  const double h = world.config().step_s;
  const long steps = std::lround(seconds / h);
  constexpr long kBlock = 10;
  for (long i = 0; i < steps;) {
    const double cpu0 = ThreadCpuSeconds();
    for (const long end = std::min(steps, i + kBlock); i < end; ++i) {
      world.hand(Side::kRight)->SetTracked(op.Right(t));
      world.hand(Side::kLeft)->SetTracked(op.Left(t));
      world.Step();
      t += h;
    }
    if (timed == nullptr) continue;
    timed->cpu_s += ThreadCpuSeconds() - cpu0;
    const physics::ControlsState s = controls.Read();
    timed->max_wheel_contacts = std::max(timed->max_wheel_contacts, s.wheel_contacts);
    timed->wheel_min = std::min(timed->wheel_min, s.wheel_angle);
    timed->wheel_max = std::max(timed->wheel_max, s.wheel_angle);
  }
}

/// The cockpit's world: both proxy hands, the wheel and the throttle, and
/// `scene` (nothing, or a floor with boxes).
Result MeasureCockpit(const PhysicsConfig& config, const CockpitConfig& cockpit, const Scene& scene,
                      double seconds, const std::string& name, const std::string& description) {
  Result r;
  r.name = name;
  r.description = description;
  auto world = physics::PhysicsWorld::CreateIfNeeded(config, physics::NeedsOf(scene, true));
  r.world = world != nullptr;
  world->AddHand(Side::kLeft);
  world->AddHand(Side::kRight);
  physics::CockpitControlsBody controls(*world, cockpit);
  const physics::BuiltScene built = physics::BuildScene(*world, scene);
  const Operator op{cockpit, config};
  double t = 0.0;
  Run(*world, controls, op, t, kWarmupS, nullptr);
  const long steps_before = static_cast<long>(world->Counters().steps);
  Run(*world, controls, op, t, seconds, &r);
  r.steps = static_cast<long>(world->Counters().steps) - steps_before;
  r.sim_s = static_cast<double>(r.steps) * config.step_s;
  for (const physics::SceneBody& node : built.nodes) {
    if (scene.objects[node.object].name.rfind("floor_box_", 0) != 0) continue;
    ++r.boxes;
    if (node.dynamic && world->BodySleeping(node.body)) ++r.boxes_asleep;
    if (node.dynamic && world->BodyParked(node.body)) ++r.boxes_parked;
  }
  return r;
}

}  // namespace

/// CPU share of one core that decoding the vehicle's video takes for a
/// session with `view`: 0 when the session does not decode (DecodesVideo),
/// else the thread CPU time of decoding `seconds` of 640×480 JPEG frames at
/// 30 fps, per wall second of video.
double VideoDecodeShare(mediator::ViewKind view, double seconds) {
  if (!mediator::DecodesVideo(view)) return 0.0;
  // A camera-like image: gradients, edges and text, as JPEG at the camera's quality.
  cv::Mat image(480, 640, CV_8UC3);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      image.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uint8_t>(x * 255 / 640), static_cast<uint8_t>(y * 255 / 480),
                    static_cast<uint8_t>((x ^ y) & 0xff));
    }
  }
  cv::rectangle(image, {100, 120}, {300, 360}, {40, 200, 40}, cv::FILLED);
  cv::putText(image, "haptel 640x480", {320, 240}, cv::FONT_HERSHEY_SIMPLEX, 1.2, {255, 255, 255},
              2);
  std::vector<uint8_t> jpeg;
  video::JpegEncoder(80).Encode(image, jpeg);
  video::JpegDecoder decoder;
  cv::Mat out;
  const int frames = static_cast<int>(30.0 * seconds);
  const double cpu0 = ThreadCpuSeconds();
  for (int i = 0; i < frames; ++i) decoder.Decode(jpeg.data(), jpeg.size(), out);
  return (ThreadCpuSeconds() - cpu0) / seconds;
}

namespace {

/// What the vehicle's camera loop costs per frame with the synthetic camera:
/// render (Grab) and JPEG encode, thread CPU time each, and the wall time of
/// both, over `seconds` of frames at `camera.rate_hz` (not paced: back to
/// back), the camera driven once round the track's centre line.
struct CameraCost {
  int width = 0, height = 0;
  double rate_hz = 0.0;
  int frames = 0;
  double render_cpu_s = 0.0, encode_cpu_s = 0.0, wall_s = 0.0;
  double jpeg_bytes = 0.0;
  double per_frame_ms(double s) const { return frames > 0 ? 1e3 * s / frames : 0.0; }
  double frame_cpu_ms() const { return per_frame_ms(render_cpu_s + encode_cpu_s); }
  /// Share of one core the camera loop needs at rate_hz.
  double cpu_share() const { return frame_cpu_ms() * 1e-3 * rate_hz; }
};

CameraCost MeasureSyntheticCamera(const CameraConfig& camera, const Track& track, double seconds) {
  CameraCost c;
  c.width = camera.width;
  c.height = camera.height;
  c.rate_hz = camera.rate_hz;
  c.frames = std::max(30, static_cast<int>(std::lround(camera.rate_hz * seconds)));
  const auto source = video::MakeCameraSource(camera, &track, "bench");
  video::JpegEncoder encoder(camera.jpeg_quality);
  cv::Mat image;
  std::vector<uint8_t> jpeg;
  const auto pose = [&](int i) {
    const double s = track.length() * i / c.frames;
    const Vec2 p = track.PointAt(s);
    const Vec2 t = track.TangentAt(s);
    return video::CameraPose{p.x(), p.y(), std::atan2(t.y(), t.x())};
  };
  for (int i = 0; i < 5; ++i) {  // warm-up: buffers, libjpeg tables
    source->Grab(pose(i), image);
    encoder.Encode(image, jpeg);
  }
  const int64_t wall0 = MonotonicNs();
  for (int i = 0; i < c.frames; ++i) {
    const double cpu0 = ThreadCpuSeconds();
    source->Grab(pose(i), image);
    const double cpu1 = ThreadCpuSeconds();
    encoder.Encode(image, jpeg);
    c.encode_cpu_s += ThreadCpuSeconds() - cpu1;
    c.render_cpu_s += cpu1 - cpu0;
    c.jpeg_bytes += static_cast<double>(jpeg.size());
  }
  c.wall_s = static_cast<double>(MonotonicNs() - wall0) * 1e-9;
  c.jpeg_bytes /= c.frames;
  return c;
}

}  // namespace

int BenchSkipMain(int argc, const char* const* argv) {
  double seconds = 2.0;
  bool json = false, smoke = false;
  PhysicsConfig config;
  CockpitConfig cockpit;
  VehicleConfig vehicle;
  std::unique_ptr<Track> track;
  try {
    const Args args(argc, argv, {"physics", "seconds"}, {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    if (smoke)
      seconds = 0.2;  // every kind of world, after the same warm-up (the boxes must fall asleep)
    if (auto v = args.Number("seconds", 0.1, 60)) seconds = *v;
    config =
        LoadPhysics(args.Value("physics").value_or(ShippedFile("config/physics.yaml").string()));
    cockpit = LoadCockpit(ShippedFile("config/interfaces/cockpit.yaml"));
    vehicle = LoadVehicle(ShippedFile("config/vehicles/sim-robot.yaml"));
    track = std::make_unique<Track>(LoadTrack(vehicle.world));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench skip: %s\n", e.what());
    return 2;
  }
  config.realtime_priority = 0;  // stepped on this thread, never started
  PrintSmokeNote(
      "skip", smoke,
      "%.2g simulated s per world, video and camera; 10 and 100 floor boxes for 100 and 1000",
      seconds);

  std::vector<Result> results;  // the JSON's entries, in its order
  {                             // gesture: no physical controls, no scene bodies.
    Result r;
    r.name = "gesture";
    r.description = "no controls, no bodies: no world";
    const auto world =
        physics::PhysicsWorld::CreateIfNeeded(config, physics::NeedsOf(Scene{}, false));
    r.world = world != nullptr;
    if (r.world) {
      std::fprintf(stderr, "haptel bench skip: the gesture interface got a physics world\n");
      return 1;
    }
    results.push_back(r);
  }
  results.push_back(
      MeasureCockpit(config, cockpit, Scene{}, seconds, "cockpit", "hands + wheel + throttle"));
  // Floor boxes: a smoke run has a tenth of them (the warm-up, while they
  // are awake, is most of its time).
  const std::vector<int> box_counts =
      smoke ? std::vector<int>{0, 10, 100} : std::vector<int>{0, 100, 1000};
  const int most = box_counts.back();
  for (const int n : box_counts) {
    results.push_back(MeasureCockpit(config, cockpit, FloorScene(n, true), seconds,
                                     "cockpit_sleeping_" + std::to_string(n),
                                     "cockpit + floor + " + std::to_string(n) + " dynamic boxes"));
  }
  // For comparison (table and CSV, and outside cpu_per_sim_s in the JSON):
  // the same `most` boxes made static, which Bullet neither integrates nor
  // pairs with the (static) floor nor puts in its simulation islands.
  const Result statics = MeasureCockpit(
      config, cockpit, FloorScene(most, false), seconds, "cockpit_static_" + std::to_string(most),
      "cockpit + floor + " + std::to_string(most) + " static boxes");
  std::vector<Result> rows = results;
  rows.push_back(statics);
  const double base = results[2].cpu_per_sim_s();

  std::printf(
      "haptel bench skip: %.1f simulated s per world after %.1f s of warm-up, step %.4g s\n",
      seconds, kWarmupS, config.step_s);
  std::printf(
      "  cockpit = both proxy hands + the wheel and throttle of %s; the right palm rests on\n"
      "  the rim turning it +-0.2 rad, the left hand hovers over the knob; floor %.2f m below the "
      "hub\n\n",
      cockpit.file.filename().c_str(), -kFloorZ);
  std::printf("%-22s %-38s %6s %9s %7s %10s %12s %9s %13s\n", "world", "what", "world", "asleep",
              "parked", "us/step", "cpu s/sim s", "x slp_0", "rim contacts");
  for (const Result& r : rows) {
    const bool dynamic = r.name.rfind("cockpit_sleeping_", 0) == 0;
    const std::string asleep = dynamic && r.boxes > 0
                                   ? std::to_string(r.boxes_asleep) + "/" + std::to_string(r.boxes)
                                   : "-";
    const std::string parked = dynamic && r.boxes > 0 ? std::to_string(r.boxes_parked) : "-";
    const std::string contacts = r.world ? std::to_string(r.max_wheel_contacts) : "-";
    const double us_per_step = r.steps > 0 ? 1e6 * r.cpu_s / static_cast<double>(r.steps) : 0.0;
    std::printf("%-22s %-38s %6s %9s %7s %10.1f %12.4f %9.2f %13s\n", r.name.c_str(),
                r.description.c_str(), r.world ? "yes" : "no", asleep.c_str(), parked.c_str(),
                us_per_step, r.cpu_per_sim_s(), base > 0.0 ? r.cpu_per_sim_s() / base : 0.0,
                contacts.c_str());
  }
  std::printf(
      "\n  cpu s/sim s: thread CPU time spent stepping per simulated second (the share of\n"
      "  one core the physics thread needs); x slp_0: ratio to cockpit_sleeping_0 in this run;\n"
      "  asleep: floor boxes Bullet had put to sleep at the end; parked: of those, how many the\n"
      "  world had taken out of Bullet's (put back when something comes near); rim contacts:\n"
      "  most hand bodies touching the rim at once (the wheel turned %.2f..%.2f rad in the\n"
      "  cockpit run).\n",
      results[1].wheel_min, results[1].wheel_max);

  const double decode_none = VideoDecodeShare(mediator::ViewKind::kNone, seconds);
  const double decode_view = VideoDecodeShare(mediator::ViewKind::kWindow, seconds);
  std::printf(
      "\n  video decode (640x480 JPEG at 30 fps), share of one core: --view none without --record "
      "%.4f "
      "(not decoded), with a view or --record %.4f\n",
      decode_none, decode_view);

  // The vehicle side's camera loop: the shipped camera (synthetic, its size
  // and rate), and the same at 320x240 (the default before 640x480) for scale.
  std::vector<CameraCost> cameras;
  cameras.push_back(MeasureSyntheticCamera(vehicle.camera, *track, seconds));
  {
    CameraConfig small = vehicle.camera;
    small.width = 320;
    small.height = 240;
    cameras.push_back(MeasureSyntheticCamera(small, *track, seconds));
  }
  std::printf("\n  vehicle camera loop (%s, synthetic, JPEG quality %d), thread CPU per frame:\n",
              vehicle.file.filename().c_str(), vehicle.camera.jpeg_quality);
  std::printf("  %-9s %7s %7s %10s %10s %10s %11s %9s %13s\n", "size", "rate", "frames",
              "render ms", "encode ms", "total ms", "wall ms", "JPEG kB", "core at rate");
  for (const CameraCost& c : cameras) {
    const std::string size = std::to_string(c.width) + "x" + std::to_string(c.height);
    std::printf("  %-9s %7.1f %7d %10.2f %10.2f %10.2f %11.2f %9.1f %13.3f\n", size.c_str(),
                c.rate_hz, c.frames, c.per_frame_ms(c.render_cpu_s), c.per_frame_ms(c.encode_cpu_s),
                c.frame_cpu_ms(), c.per_frame_ms(c.wall_s), c.jpeg_bytes / 1e3, c.cpu_share());
  }
  const CameraCost& shipped = cameras.front();
  std::printf(
      "  the shipped camera %s: %.2f ms of CPU per frame against a %.1f ms period (%.3f of a "
      "core%s)\n",
      shipped.cpu_share() < 1.0 ? "keeps up" : "CANNOT keep up", shipped.frame_cpu_ms(),
      1e3 / shipped.rate_hz, shipped.cpu_share(),
      shipped.cpu_share() < 1.0 ? "" : ": lower camera.rate_hz or the size");

  const auto dir = OutputDir(smoke);
  {
    std::ofstream csv(dir / "skip_camera.csv");
    csv << "width,height,rate_hz,frames,render_ms,encode_ms,frame_cpu_ms,wall_ms,jpeg_bytes,cpu_"
           "share\n";
    for (const CameraCost& c : cameras) {
      csv << c.width << "," << c.height << "," << c.rate_hz << "," << c.frames << ","
          << c.per_frame_ms(c.render_cpu_s) << "," << c.per_frame_ms(c.encode_cpu_s) << ","
          << c.frame_cpu_ms() << "," << c.per_frame_ms(c.wall_s) << "," << c.jpeg_bytes << ","
          << c.cpu_share() << "\n";
    }
  }
  {
    std::ofstream csv(dir / "skip.csv");
    csv << "world,has_world,boxes,boxes_asleep,steps,sim_s,cpu_s,cpu_per_sim_s,ratio_to_sleeping_0,"
           "max_rim_contacts,wheel_min_rad,wheel_max_rad,boxes_parked\n";
    for (const Result& r : rows) {
      csv << r.name << "," << (r.world ? 1 : 0) << "," << r.boxes << "," << r.boxes_asleep << ","
          << r.steps << "," << r.sim_s << "," << r.cpu_s << "," << r.cpu_per_sim_s() << ","
          << (base > 0.0 ? r.cpu_per_sim_s() / base : 0.0) << "," << r.max_wheel_contacts << ","
          << r.wheel_min << "," << r.wheel_max << "," << r.boxes_parked << "\n";
    }
  }
  std::printf("\n  wrote %s and %s\n", (dir / "skip.csv").c_str(),
              (dir / "skip_camera.csv").c_str());

  if (json) {
    std::ostringstream o;
    o << "{\"cpu_per_sim_s\":{";
    for (size_t i = 0; i < results.size(); ++i) {
      o << (i ? "," : "") << "\"" << results[i].name
        << "\":" << JsonNumber(results[i].cpu_per_sim_s());
    }
    o << "},\"cpu_per_sim_s_static_" << most << "\":" << JsonNumber(statics.cpu_per_sim_s())
      << ",\"video_decode_cpu_share\":{\"view_none\":" << JsonNumber(decode_none)
      << ",\"view\":" << JsonNumber(decode_view) << "}"
      << ",\"vehicle_camera\":{\"width\":" << shipped.width << ",\"height\":" << shipped.height
      << ",\"rate_hz\":" << JsonNumber(shipped.rate_hz)
      << ",\"render_ms\":" << JsonNumber(shipped.per_frame_ms(shipped.render_cpu_s))
      << ",\"encode_ms\":" << JsonNumber(shipped.per_frame_ms(shipped.encode_cpu_s))
      << ",\"cpu_share\":" << JsonNumber(shipped.cpu_share()) << "}}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return 0;
}

}  // namespace haptel::bench
