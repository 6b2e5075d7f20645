#include "video_bench.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/config/paths.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/testing/lap_frames.hpp"
#include "haptel/video/codec.hpp"
#include "haptel/video/h264_codec.hpp"
#include "haptel/video/image_quality.hpp"
#include "plot.hpp"
#include "smoke.hpp"
#include "video_cameras.hpp"
#include "video_schedule.hpp"

namespace haptel::bench {
namespace {

struct CodecPoint {
  CameraCodec codec = CameraCodec::kJpeg;
  int setting = 0;  ///< JPEG quality, or H.264 kbit/s
  double bitrate_kbps = 0.0;
  double ssim = 0.0;
  double psnr_db = 0.0;
  double encode_ms = 0.0;
  double decode_ms = 0.0;
  bool pareto = false;
  bool is_default = false;
  bool ok = true;  ///< every frame encoded and decoded
};

/// Encodes and decodes every frame at one setting; the quality figures are
/// means over the frames, the CPU figures per frame.
CodecPoint Measure(CameraCodec codec, int setting, const CameraConfig& camera,
                   const std::vector<cv::Mat>& frames) {
  CodecPoint p;
  p.codec = codec;
  p.setting = setting;
  CameraConfig c = camera;
  c.codec = codec;
  if (codec == CameraCodec::kJpeg) {
    c.jpeg_quality = setting;
  } else {
    c.bitrate_kbps = setting;
  }
  const std::unique_ptr<video::VideoEncoder> encoder = video::MakeVideoEncoder(c);
  const std::unique_ptr<video::VideoDecoder> decoder = video::MakeVideoDecoder(codec);
  std::vector<uint8_t> bytes;
  cv::Mat picture;
  double encode_s = 0.0, decode_s = 0.0, ssim = 0.0, psnr = 0.0;
  size_t total_bytes = 0;
  uint64_t seq = 0;
  for (const cv::Mat& frame : frames) {
    const double e0 = ThreadCpuSeconds();
    const bool encoded = encoder->Encode(frame, bytes);
    encode_s += ThreadCpuSeconds() - e0;
    if (!encoded) {
      p.ok = false;
      continue;
    }
    total_bytes += bytes.size();
    const double d0 = ThreadCpuSeconds();
    const video::DecodeResult result = decoder->DecodeFrame(
        {bytes.data(), bytes.size(), ++seq, encoder->last_was_key_frame()}, picture);
    decode_s += ThreadCpuSeconds() - d0;
    if (result != video::DecodeResult::kPicture) {
      p.ok = false;
      continue;
    }
    ssim += video::Ssim(frame, picture);
    psnr +=
        std::min(100.0, video::PsnrDb(frame, picture));  // identical pictures: capped, not infinite
  }
  const double n = static_cast<double>(frames.size());
  p.bitrate_kbps = static_cast<double>(total_bytes) * 8.0 / (n / camera.rate_hz) / 1000.0;
  p.ssim = ssim / n;
  p.psnr_db = psnr / n;
  p.encode_ms = encode_s / n * 1e3;
  p.decode_ms = decode_s / n * 1e3;
  return p;
}

std::string SettingText(const CodecPoint& p) {
  return p.codec == CameraCodec::kJpeg ? "quality " + std::to_string(p.setting)
                                       : std::to_string(p.setting) + " kbit/s";
}

/// Part 3's table: per phase and camera.
void PrintTwoCameras(const TwoCameraResult& two, const std::filesystem::path& dir) {
  std::printf("  %9s  %-12s %6s %9s %9s %9s %9s %9s %9s %9s\n", "capacity", "camera", "fps",
              "kbit/s", "settled", "share", "lat p50", "lat p95", "aim p50", "aim p95");
  for (const TwoCameraPhase& p : two.phases) {
    for (const auto& [name, f] :
         {std::pair{"pilot", p.pilot}, std::pair{"surveillance", p.surveillance}}) {
      const bool aimed = std::string(name) == "surveillance" && p.aims_shown > 0;
      std::printf("  %9.0f  %-12s %6.1f %9.0f %9.0f %9.0f %9.1f %9.1f %9s %9s\n", p.capacity_kbps,
                  name, f.fps, f.kbps, f.settled_kbps, f.target_kbps, f.latency_ms_p50,
                  f.latency_ms_p95,
                  aimed ? std::to_string(p.aim_latency_ms_p50).substr(0, 6).c_str() : "",
                  aimed ? std::to_string(p.aim_latency_ms_p95).substr(0, 6).c_str() : "");
    }
  }
  std::printf(
      "  (kbit/s over the phase and its second half; share: the vehicle's target for the "
      "camera; latency capture to decoded, aim: pan/tilt/zoom command to picture, ms)\n"
      "  pan/tilt/zoom command to picture: p50 %.1f ms, p95 %.1f ms (%d of %d aims shown); "
      "wrote %s/video_cameras.csv, _trace.csv, .png\n",
      two.aim_latency_ms_p50, two.aim_latency_ms_p95, two.aims_shown, two.aims, dir.c_str());
  for (const auto& [name, h] :
       {std::pair{"mouse", two.head_mouse}, std::pair{"gamepad", two.head_gamepad}}) {
    std::printf(
        "  pilot's head by %-7s to picture: p50 %.1f ms, p95 %.1f ms (%d of %d motions shown)\n",
        name, h.ms_p50, h.ms_p95, h.shown, h.moves);
  }
}

/// Part 3's JSON members: "cameras":[...],"aim_latency_ms_p50":...
std::string TwoCamerasJson(const TwoCameraResult& two) {
  std::ostringstream o;
  o << "\"cameras\":[";
  bool first = true;
  for (const TwoCameraPhase& p : two.phases) {
    for (const auto& [name, f] :
         {std::pair{"pilot", p.pilot}, std::pair{"surveillance", p.surveillance}}) {
      o << (first ? "" : ",") << "{\"camera\":\"" << name
        << "\",\"capacity_kbps\":" << JsonNumber(p.capacity_kbps)
        << ",\"fps\":" << JsonNumber(f.fps) << ",\"kbps\":" << JsonNumber(f.kbps)
        << ",\"settled_kbps\":" << JsonNumber(f.settled_kbps)
        << ",\"share_kbps\":" << JsonNumber(f.target_kbps)
        << ",\"latency_ms_p50\":" << JsonNumber(f.latency_ms_p50)
        << ",\"latency_ms_p95\":" << JsonNumber(f.latency_ms_p95) << "}";
      first = false;
    }
  }
  o << "],\"aim_latency_ms_p50\":"
    << (two.aims_shown > 0 ? JsonNumber(two.aim_latency_ms_p50) : std::string("null"))
    << ",\"aim_latency_ms_p95\":"
    << (two.aims_shown > 0 ? JsonNumber(two.aim_latency_ms_p95) : std::string("null"))
    << ",\"aims\":" << two.aims << ",\"aims_shown\":" << two.aims_shown;
  for (const auto& [name, h] :
       {std::pair{"head_mouse", two.head_mouse}, std::pair{"head_gamepad", two.head_gamepad}}) {
    o << ",\"" << name
      << "\":{\"ms_p50\":" << (h.shown > 0 ? JsonNumber(h.ms_p50) : std::string("null"))
      << ",\"ms_p95\":" << (h.shown > 0 ? JsonNumber(h.ms_p95) : std::string("null"))
      << ",\"moves\":" << h.moves << ",\"shown\":" << h.shown << "}";
  }
  return o.str();
}

}  // namespace

int BenchVideoMain(int argc, const char* const* argv) {
  bool json = false, smoke = false;
  VehicleConfig vehicle;
  std::unique_ptr<Track> track;
  std::string track_file;
  ScheduleOptions schedule;
  std::vector<CameraCodec> schedule_codecs;
  TwoCameraOptions two_cameras;
  bool run_two_cameras = true;
  bool cameras_only = false;
  try {
    const Args args(argc, argv, {"vehicle", "track", "phase-s", "schedule", "domain", "cameras"},
                    {"json", kSmokeFlag, "cameras-only"});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    vehicle = LoadVehicle(
        args.Value("vehicle").value_or(ShippedFile("config/vehicles/sim-robot.yaml").string()));
    track_file =
        args.Value("track").value_or(ShippedFile("config/tracks/grand-prix.yaml").string());
    track = std::make_unique<Track>(LoadTrack(track_file));
    schedule.phase_s = args.Number("phase-s", 1.0, 600.0).value_or(smoke ? 3.0 : 25.0);
    // A domain of the bench's own, away from a default installation's 0 and the link bench's.
    schedule.domain = args.Int("domain", 0, 232).value_or(150 + static_cast<int>(getpid() % 30));
    // The schedule for the vehicle file's codec, then (full run) the other beside it.
    const std::string which = args.Value("schedule").value_or(smoke ? "default" : "both");
    const CameraCodec other =
        vehicle.camera.codec == CameraCodec::kJpeg ? CameraCodec::kH264 : CameraCodec::kJpeg;
    if (which == "default") {
      schedule_codecs = {vehicle.camera.codec};
    } else if (which == "both") {
      schedule_codecs = {vehicle.camera.codec, other};
    } else if (which == "jpeg" || which == "h264") {
      schedule_codecs = {which == "jpeg" ? CameraCodec::kJpeg : CameraCodec::kH264};
    } else if (which == "off") {
      schedule_codecs = {};
    } else {
      throw UsageError("option --schedule: expected default, both, jpeg, h264 or off, got '" +
                       which + "'");
    }
    // Part 3: two cameras sharing the link (the blimp's pilot and surveillance cameras).
    const std::string cameras = args.Value("cameras").value_or(
        ShippedFile("config/vehicles/sim-blimp-surveillance.yaml").string());
    run_two_cameras = cameras != "off";
    if (run_two_cameras) two_cameras.vehicle_file = cameras;
    two_cameras.domain = schedule.domain == 232 ? 231 : schedule.domain + 1;
    cameras_only = args.Flag("cameras-only");
    if (cameras_only && !run_two_cameras)
      throw UsageError("option --cameras-only: not with --cameras off");
    if (smoke) {
      two_cameras.capacities_kbps = {3000.0, 800.0};
      two_cameras.phase_s = 3.0;
    } else {
      two_cameras.phase_s = args.Number("phase-s", 1.0, 600.0).value_or(15.0);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench video: %s\n", e.what());
    return 2;
  }
  if (cameras_only) {
    // Part 3 alone: the codec table and the single camera's schedule take
    // minutes of CPU the two cameras' figures do not need.
    two_cameras.out_dir = OutputDir(smoke);
    std::printf("haptel bench video --cameras-only (%s): the link's rate steps",
                two_cameras.vehicle_file.filename().c_str());
    for (const double c : two_cameras.capacities_kbps) std::printf(" %.2f", c / 1000.0);
    std::printf(" Mbit/s, %.0f s each; the surveillance camera re-aimed every 0.5 s\n",
                two_cameras.phase_s);
    std::fflush(stdout);
    const TwoCameraResult two = RunTwoCameraSchedule(two_cameras);
    if (!two.ok) std::fprintf(stderr, "haptel bench video: two cameras: %s\n", two.error.c_str());
    PrintTwoCameras(two, two_cameras.out_dir);
    if (json) {
      // Appended, not "{" + … + "}": GCC 12 warns falsely of an overlap there (-Wrestrict).
      std::string line = TwoCamerasJson(two);
      line.insert(line.begin(), '{');
      line.push_back('}');
      std::printf("%s\n", JsonLine(line, smoke).c_str());
    }
    return two.ok ? 0 : 1;
  }
  const CameraConfig& camera = vehicle.camera;
  const int clips = smoke ? 1 : 4;
  const int frames_per_clip = smoke ? 15 : static_cast<int>(std::lround(2.5 * camera.rate_hz));
  PrintSmokeNote("video", smoke, "%d frames, 2 JPEG and 2 H.264 settings and the default",
                 clips * frames_per_clip);
  const auto dir = OutputDir(smoke);
  const std::vector<cv::Mat> frames = testing::LapFrames(*track, camera, clips, frames_per_clip);
  std::printf(
      "haptel bench video: %zu frames of %dx%d at %.0f fps (%d clips along %s), vehicle %s\n\n",
      frames.size(), camera.width, camera.height, camera.rate_hz, clips,
      track->config().name.c_str(), vehicle.file.c_str());

  const std::vector<int> qualities =
      smoke ? std::vector<int>{20, 80} : std::vector<int>{20, 30, 40, 50, 60, 70, 80, 90, 95};
  const std::vector<int> rates =
      smoke ? std::vector<int>{250, 2000}
            : std::vector<int>{250, 375, 500, 750, 1000, 1500, 2000, 3000, 4000, 6000, 8000};
  std::vector<CodecPoint> points;
  for (int q : qualities) points.push_back(Measure(CameraCodec::kJpeg, q, camera, frames));
  for (int r : rates) points.push_back(Measure(CameraCodec::kH264, r, camera, frames));
  const int default_setting =
      camera.codec == CameraCodec::kJpeg ? camera.jpeg_quality : camera.bitrate_kbps;
  bool default_found = false;
  for (CodecPoint& p : points) {
    if (p.codec == camera.codec && p.setting == default_setting)
      p.is_default = default_found = true;
  }
  if (!default_found) {
    points.push_back(Measure(camera.codec, default_setting, camera, frames));
    points.back().is_default = true;
  }
  for (CodecPoint& p : points) {
    p.pareto = p.ok;
    for (const CodecPoint& o : points) {
      const bool better = o.ok && o.bitrate_kbps <= p.bitrate_kbps && o.ssim >= p.ssim &&
                          (o.bitrate_kbps < p.bitrate_kbps || o.ssim > p.ssim);
      if (better) p.pareto = false;
    }
  }

  std::printf("  %-6s %-14s %12s %8s %9s %10s %10s %6s\n", "codec", "setting", "kbit/s", "SSIM",
              "PSNR dB", "encode ms", "decode ms", "front");
  std::ofstream csv(dir / "video_codecs.csv");
  csv << "codec,setting,bitrate_kbps,ssim,psnr_db,encode_ms,decode_ms,pareto,default,ok\n";
  Series jpeg{"JPEG (quality 20..95)", {}, {}}, h264{"H.264 (0.25..8 Mbit/s)", {}, {}},
      front{"Pareto front", {}, {}};
  const CodecPoint* shipped = nullptr;
  for (const CodecPoint& p : points) {
    std::printf("  %-6s %-14s %12.0f %8.4f %9.2f %10.2f %10.2f %6s%s%s\n", CameraCodecName(p.codec),
                SettingText(p).c_str(), p.bitrate_kbps, p.ssim, p.psnr_db, p.encode_ms, p.decode_ms,
                p.pareto ? "yes" : "", p.is_default ? "  <- shipped default" : "",
                p.ok ? "" : "  (frames failed)");
    csv << CameraCodecName(p.codec) << ',' << p.setting << ',' << p.bitrate_kbps << ',' << p.ssim
        << ',' << p.psnr_db << ',' << p.encode_ms << ',' << p.decode_ms << ',' << p.pareto << ','
        << p.is_default << ',' << p.ok << '\n';
    Series& s = p.codec == CameraCodec::kJpeg ? jpeg : h264;
    s.x.push_back(std::log10(p.bitrate_kbps));
    s.y.push_back(p.ssim);
    if (p.is_default) shipped = &p;
  }
  std::vector<const CodecPoint*> on_front;
  for (const CodecPoint& p : points) {
    if (p.pareto) on_front.push_back(&p);
  }
  std::sort(on_front.begin(), on_front.end(), [](const CodecPoint* a, const CodecPoint* b) {
    return a->bitrate_kbps < b->bitrate_kbps;
  });
  for (const CodecPoint* p : on_front) {
    front.x.push_back(std::log10(p->bitrate_kbps));
    front.y.push_back(p->ssim);
  }
  // The series are sorted by bitrate for the lines (JPEG's by quality already is).
  PlotLines(dir / "video_codecs.png", {jpeg, h264, front},
            {"video codecs: bitrate against SSIM (synthetic camera, grand prix)",
             "log10 bitrate, kbit/s", "mean SSIM", false});
  const bool all_ok =
      std::all_of(points.begin(), points.end(), [](const CodecPoint& p) { return p.ok; });
  std::printf(
      "\n  shipped default: %s at %s: %s the Pareto front; every frame coded: %s\n  wrote "
      "%s/video_codecs.csv, "
      "video_codecs.png\n",
      CameraCodecName(camera.codec), SettingText(*shipped).c_str(),
      shipped->pareto ? "on" : "NOT on", all_ok ? "yes" : "NO", dir.c_str());

  // Part 2: the capacity schedule through a real vehicle process.
  schedule.out_dir = dir;
  schedule.track_file = track_file;
  std::vector<ScheduleResult> schedules;
  bool schedules_ok = true;
  for (const CameraCodec codec : schedule_codecs) {
    std::printf("\n  capacity schedule, %s: the link's rate steps", CameraCodecName(codec));
    for (const double c : schedule.capacities_kbps) std::printf(" %.2f", c / 1000.0);
    std::printf(" Mbit/s, %.0f s each (haptel-vehicle playing the frames above, looped)\n",
                schedule.phase_s);
    std::fflush(stdout);
    schedules.push_back(RunCapacitySchedule(vehicle, codec, frames, schedule));
    const ScheduleResult& r = schedules.back();
    if (!r.ok) {
      std::fprintf(stderr, "haptel bench video: capacity schedule (%s): %s\n",
                   CameraCodecName(codec), r.error.c_str());
      schedules_ok = false;
      continue;
    }
    std::printf("  %9s %9s %9s %7s %6s %9s %9s %6s %7s %10s %8s\n", "capacity", "video", "target",
                "SSIM", "fps", "lat p50", "lat p95", "lost", "stale s", "cmd p99 ms", "adapt s");
    for (const SchedulePhase& p : r.phases) {
      std::printf("  %9.0f %9.0f %9.0f %7.4f %6.1f %9.1f %9.1f %6llu %7.2f %10.2f %8s\n",
                  p.capacity_kbps, p.video_kbps, p.target_kbps, p.ssim, p.fps, p.latency_ms_p50,
                  p.latency_ms_p95, static_cast<unsigned long long>(p.frames_lost), p.stale_s,
                  p.command_rtt_ms_p99,
                  p.step_down ? std::to_string(p.adapt_s).substr(0, 5).c_str() : "");
    }
    std::printf(
        "  (kbit/s; latency capture to decoded, ms) adapt_s %.2f (target <= 2); wrote "
        "%s/video_schedule_%s.csv, "
        "_trace.csv, .png\n",
        r.adapt_s, dir.c_str(), CameraCodecName(codec));
    std::fflush(stdout);
  }

  TwoCameraResult two;
  bool two_ok = true;
  if (run_two_cameras) {
    two_cameras.out_dir = dir;
    std::printf("\n  two cameras (%s): the link's rate steps",
                two_cameras.vehicle_file.filename().c_str());
    for (const double c : two_cameras.capacities_kbps) std::printf(" %.2f", c / 1000.0);
    std::printf(" Mbit/s, %.0f s each; the surveillance camera re-aimed every 0.5 s\n",
                two_cameras.phase_s);
    std::fflush(stdout);
    two = RunTwoCameraSchedule(two_cameras);
    if (!two.ok) {
      std::fprintf(stderr, "haptel bench video: two cameras: %s\n", two.error.c_str());
      two_ok = false;
    }
    PrintTwoCameras(two, dir);
    std::fflush(stdout);
  }

  if (json) {
    std::ostringstream o;
    o << "{\"codecs\":[";
    for (size_t i = 0; i < points.size(); ++i) {
      const CodecPoint& p = points[i];
      o << (i ? "," : "") << "{\"codec\":\"" << CameraCodecName(p.codec)
        << "\",\"setting\":" << p.setting << ",\"bitrate_kbps\":" << JsonNumber(p.bitrate_kbps)
        << ",\"ssim\":" << JsonNumber(p.ssim) << ",\"psnr_db\":" << JsonNumber(p.psnr_db)
        << ",\"encode_ms\":" << JsonNumber(p.encode_ms)
        << ",\"decode_ms\":" << JsonNumber(p.decode_ms)
        << ",\"pareto\":" << (p.pareto ? "true" : "false") << "}";
    }
    o << "],\"default\":{\"codec\":\"" << CameraCodecName(camera.codec)
      << "\",\"setting\":" << default_setting
      << ",\"on_pareto_front\":" << (shipped->pareto ? "true" : "false") << "},\"schedule\":[";
    // The rows of every codec run, each naming its codec; adapt_s is the
    // shipped default's (the first run), adapt_s_by_codec each one's.
    bool first = true;
    for (const ScheduleResult& r : schedules) {
      for (const SchedulePhase& p : r.phases) {
        o << (first ? "" : ",") << "{\"codec\":\"" << CameraCodecName(r.codec)
          << "\",\"capacity_kbps\":" << JsonNumber(p.capacity_kbps)
          << ",\"video_kbps\":" << JsonNumber(p.video_kbps)
          << ",\"target_kbps\":" << JsonNumber(p.target_kbps)
          << ",\"ssim\":" << (std::isfinite(p.ssim) ? JsonNumber(p.ssim) : std::string("null"))
          << ",\"fps\":" << JsonNumber(p.fps)
          << ",\"latency_ms_p50\":" << JsonNumber(p.latency_ms_p50)
          << ",\"latency_ms_p95\":" << JsonNumber(p.latency_ms_p95)
          << ",\"frames_lost\":" << p.frames_lost << ",\"stale_s\":" << JsonNumber(p.stale_s)
          << ",\"command_rtt_ms_p99\":" << JsonNumber(p.command_rtt_ms_p99) << "}";
        first = false;
      }
    }
    o << "],\"adapt_s\":";
    if (!schedules.empty() && schedules.front().ok) {
      o << JsonNumber(schedules.front().adapt_s);
    } else {
      o << "null";
    }
    o << ",\"adapt_s_by_codec\":{";
    first = true;
    for (const ScheduleResult& r : schedules) {
      if (!r.ok) continue;
      o << (first ? "" : ",") << "\"" << CameraCodecName(r.codec) << "\":" << JsonNumber(r.adapt_s);
      first = false;
    }
    o << "},";
    o << TwoCamerasJson(two) << "}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return all_ok && schedules_ok && two_ok ? 0 : 1;
}

}  // namespace haptel::bench
