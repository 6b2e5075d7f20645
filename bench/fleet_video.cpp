#include "fleet_video.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <thread>

#include "haptel/config/paths.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/mediator/session_view.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "video_source.hpp"

namespace haptel::bench {

namespace {

constexpr double kSsimPerSecond = 3.0;  ///< pictures compared with their source, per vehicle
constexpr double kUpBound_s = 60.0;     ///< every vehicle's first picture, on a loaded machine

/// A vehicle's figures over the measurement.
struct Tally {
  uint64_t last_id = 0;
  uint64_t pictures = 0;
  int64_t next_ssim_ns = 0;
  double target_min = 1e300;
};

}  // namespace

FleetVideoCount MeasureFleetVideo(int count, const std::vector<cv::Mat>& frames,
                                  const FleetVideoOptions& options) {
  FleetVideoCount result;
  result.vehicles = count;
  try {
    const VehicleConfig base = LoadVehicle(options.vehicle_file);
    const std::filesystem::path source = options.out_dir / "fleet_video_source.mkv";
    const std::filesystem::path vehicle_file = options.out_dir / "fleet_video_vehicle.yaml";
    if (!std::filesystem::exists(source)) WriteLosslessSource(source, frames, base.camera.rate_hz);
    WriteVehicleFileWithSource(base, base.camera.codec, source, vehicle_file);

    std::vector<std::unique_ptr<mediator::VehicleLink>> links;
    for (int i = 0; i < count; ++i) {
      mediator::VehicleLinkOptions lo;
      lo.vehicle = LoadVehicle(vehicle_file);
      lo.vehicle.name = "fleet-video-" + std::to_string(i + 1);
      lo.link = lo.vehicle.link;
      lo.link.domain_id = options.domain;
      lo.track_file = options.track_file;
      lo.program = ProgramDirectory() / "haptel-vehicle";
      lo.decode_video = true;
      links.push_back(std::make_unique<mediator::VehicleLink>(lo));
    }
    const int64_t up_until = MonotonicNs() + SToNs(kUpBound_s);
    const auto all_up = [&] {
      return std::all_of(links.begin(), links.end(),
                         [](const auto& l) { return l->video().Latest().id != 0; });
    };
    while (!all_up() && MonotonicNs() < up_until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      for (const auto& l : links) {
        if (!l->ProcessAlive())
          throw std::runtime_error("haptel-vehicle " + l->name() +
                                   " ended: " + l->ExitDescription());
      }
    }
    if (!all_up()) throw std::runtime_error("not every vehicle's video came within 60 s");

    // The fleet's view, as haptel run --fleet draws it: the first on the
    // big screen, every vehicle on its tile.
    haptics::Hal hal;
    std::vector<mediator::SessionView::Parts> parts(static_cast<size_t>(count));
    for (int i = 0; i < count; ++i) {
      parts[static_cast<size_t>(i)].hal = &hal;
      parts[static_cast<size_t>(i)].hands = {false, false};
      parts[static_cast<size_t>(i)].video = &links[static_cast<size_t>(i)]->video();
    }
    view::ViewOptions view_options;
    view_options.mode =
        view::View::DisplayAvailable() ? view::ViewMode::kWindow : view::ViewMode::kOffscreen;
    view_options.title = "Haptel - bench fleet";
    result.view_mode = view_options.mode == view::ViewMode::kWindow ? "window" : "offscreen";
    interfaces::InputBox input;
    mediator::SessionView view(view_options, parts, input);
    view.Show(0);
    view::Tiles tiles;
    tiles.count = count > 1 ? count : 0;
    for (int i = 0; i < count && count > 1; ++i) {
      view::Tiles::Tile& tile = tiles.tile[static_cast<size_t>(i)];
      std::snprintf(tile.name, sizeof tile.name, "%s",
                    links[static_cast<size_t>(i)]->name().c_str());
      tile.state = i == 0 ? view::TileState::kDriven : view::TileState::kHeld;
    }
    std::snprintf(tiles.line, sizeof tiles.line, "driving %s", links[0]->name().c_str());
    view.Publish(tiles);
    for (int i = 0; i < count; ++i)
      links[static_cast<size_t>(i)]->video().ShowAsTile(i > 0 && options.previews);
    std::this_thread::sleep_for(std::chrono::duration<double>(options.warm_up_s));

    std::vector<std::unique_ptr<SsimWorker>> ssim;
    std::vector<Tally> tally(static_cast<size_t>(count));
    std::vector<video::VideoStats> before;
    for (int i = 0; i < count; ++i) {
      const auto& l = links[static_cast<size_t>(i)];
      ssim.push_back(
          std::make_unique<SsimWorker>(frames, base.camera.rate_hz, 1, SsimWorker::Size::kPicture));
      before.push_back(l->video().Stats());
      tally[static_cast<size_t>(i)].last_id = l->video().Latest().id;
    }
    const int64_t start = MonotonicNs();
    const int64_t end = start + SToNs(options.seconds);
    int64_t next_sample = start;
    while (MonotonicNs() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      const int64_t now = MonotonicNs();
      const bool sample = now >= next_sample;
      if (sample) next_sample += SToNs(0.1);
      for (int i = 0; i < count; ++i) {
        Tally& t = tally[static_cast<size_t>(i)];
        const video::VideoReceiver& video = links[static_cast<size_t>(i)]->video();
        const video::Frame latest = video.Latest();
        if (latest.id != t.last_id && !latest.stale && latest.image) {
          t.last_id = latest.id;
          ++t.pictures;
          if (now >= t.next_ssim_ns &&
              ssim[static_cast<size_t>(i)]->Offer(latest.image, latest.capture_wall_ns, 0)) {
            t.next_ssim_ns = now + static_cast<int64_t>(1e9 / kSsimPerSecond);
          }
        }
        if (sample) t.target_min = std::min(t.target_min, video.Stats().target_kbps);
      }
    }
    const double seconds = NsToS(MonotonicNs() - start);
    for (int i = 0; i < count; ++i) {
      const auto& l = links[static_cast<size_t>(i)];
      const video::VideoStats after = l->video().Stats();
      const video::Frame latest = l->video().Latest();
      FleetVideoVehicle v;
      v.name = l->name();
      v.driven = i == 0;
      v.kbps = static_cast<double>(after.bytes - before[static_cast<size_t>(i)].bytes) * 8.0 /
               seconds / 1000.0;
      v.target_kbps = after.target_kbps;
      v.target_kbps_min = tally[static_cast<size_t>(i)].target_min;
      v.rate_cuts = after.rate_cuts - before[static_cast<size_t>(i)].rate_cuts;
      v.fps = static_cast<double>(tally[static_cast<size_t>(i)].pictures) / seconds;
      if (latest.image) v.width = latest.image->cols, v.height = latest.image->rows;
      const auto [mean, samples] = ssim[static_cast<size_t>(i)]->Phase(0);
      v.ssim = mean;
      v.ssim_samples = samples;
      result.vehicle.push_back(v);
      if (!l->ProcessAlive())
        throw std::runtime_error("haptel-vehicle " + l->name() + " ended: " + l->ExitDescription());
    }
    view.Stop();
    result.view_fps = view.Stats().fps;
    for (auto& l : links) l->Stop();
    result.ran = std::all_of(result.vehicle.begin(), result.vehicle.end(),
                             [](const FleetVideoVehicle& v) { return v.fps > 0.0; });
    if (!result.ran) result.error = "a vehicle whose video stopped";
  } catch (const std::exception& e) {
    result.error = e.what();
  }
  return result;
}

}  // namespace haptel::bench
