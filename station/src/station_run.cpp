#include "haptel/station/station_run.hpp"

#include <chrono>
#include <memory>
#include <thread>

#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/process_identity.hpp"
#include "haptel/station/camera_control.hpp"
#include "haptel/station/station_view.hpp"
#include "haptel/view/sdl_input.hpp"
#include "haptel/view/view_record.hpp"

namespace haptel::station {

const char* ToString(StationOutcome outcome) {
  switch (outcome) {
    case StationOutcome::kEnded:
      return "ended";
    case StationOutcome::kTimeLimit:
      return "time limit";
    case StationOutcome::kInterrupted:
      return "interrupted";
    case StationOutcome::kRefused:
      return "refused";
    case StationOutcome::kNoCamera:
      return "no camera";
    case StationOutcome::kNoVehicle:
      return "no vehicle";
  }
  return "?";
}

int ExitCode(const StationResult& result) {
  if (!result.view.record_error.empty()) return cli::kExitOutputFailed;
  if (!result.session_file.file.empty() && !result.session_file.saved)
    return cli::kExitOutputFailed;
  switch (result.outcome) {
    case StationOutcome::kEnded:
    case StationOutcome::kTimeLimit:
    case StationOutcome::kInterrupted:
      return cli::kExitOk;
    default:
      return cli::kExitFailed;
  }
}

namespace {

/// The station's loop rate: the person's input and the screen's lines.
constexpr double kLoopRate_hz = 50.0;
/// How long a camera that cannot be steered (none of that name, the
/// driver's, a fixed one) is waited on before the station ends: the
/// vehicle's status may be one from before its cameras were all up.
constexpr double kNoCameraAfter_s = 3.0;
/// How often `--view none` says the vehicle and the camera on stderr.
constexpr double kLogEvery_s = 5.0;
/// How long the vehicle's first status is waited for.
constexpr double kNoVehicleAfter_s = 20.0;

bool Steerable(Role role) {
  return role == Role::kFree || role == Role::kHolding || role == Role::kRefused;
}

/// The view channels of a session file (as `haptel run`'s): the view's
/// set-up once, then each frame the view draws, so `haptel replay` draws
/// the control room again.
std::unique_ptr<view::ViewFrameEncoder> TapView(record::SessionRecorder& file,
                                                view::ViewOptions& options) {
  const int setup_channel =
      file.AddOwnChannel(view::kViewSetupTopic, view::kViewSetupSchemaName, view::kViewRecordIdl);
  const int frame_channel =
      file.AddOwnChannel(view::kViewFrameTopic, view::kViewFrameSchemaName, view::kViewRecordIdl);
  if (setup_channel < 0 || frame_channel < 0) return nullptr;  // its report says why
  return view::StartViewRecord(
      options, nullptr,
      [&file, setup_channel](const uint8_t* data, size_t size) {
        file.OnSample(setup_channel, MonotonicNs(), nullptr, data, size);
      },
      [&file, frame_channel](const uint8_t* data, size_t size) {
        file.OnSample(frame_channel, MonotonicNs(), nullptr, data, size);
      });
}

}  // namespace

StationResult RunStation(const StationSetup& setup, const std::atomic<bool>& stop) {
  StationResult result;
  const std::string& vehicle = setup.station.vehicle;
  const std::string& camera_name = setup.station.camera;
  const int domain = setup.station.link.domain_id;

  std::unique_ptr<record::SessionRecorder> file;
  if (!setup.session_file.file.empty())
    file = std::make_unique<record::SessionRecorder>(setup.session_file);
  StationOptions options = setup.station;
  options.tap = file.get();
  const bool drawn = setup.view == ViewChoice::kWindow || !setup.record.empty();
  options.decode = drawn || file != nullptr;
  auto station_owner = std::make_unique<CameraStation>(options);
  CameraStation& station = *station_owner;

  interfaces::InputBox input;
  haptics::PointerBox pointer;
  std::unique_ptr<view::SdlInput> sink;
  std::unique_ptr<view::ViewFrameEncoder> view_tap;
  StationView screen(station.video());
  std::unique_ptr<view::View> view;
  if (drawn) {
    view::ViewOptions v;
    v.mode =
        setup.view == ViewChoice::kWindow ? view::ViewMode::kWindow : view::ViewMode::kOffscreen;
    v.record = setup.record;
    v.title = "Haptel station - " + camera_name + " of " + vehicle;
    v.screen = view::DirectViewScreen();
    if (file) view_tap = TapView(*file, v);
    if (v.mode == view::ViewMode::kWindow) sink = std::make_unique<view::SdlInput>(input, pointer);
    view = std::make_unique<view::View>(v, screen, sink.get());
    result.view_shown = true;
  }

  const std::string person = UserName();
  CameraControl control({}, 60.0, {});
  bool aimed = false;
  Role said = Role::kWaiting;
  const int64_t t0 = MonotonicNs();
  int64_t unsteerable_since = 0;
  int64_t next_log_ns = 0;
  const auto period = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / kLoopRate_hz));
  auto next = std::chrono::steady_clock::now();
  for (;;) {
    next += period;
    std::this_thread::sleep_until(next);
    const int64_t now_ns = MonotonicNs();
    const double t = NsToS(now_ns - t0);
    const CameraNow now = station.Now();
    result.camera = now;

    // Said once per change of hands (the person reads it on the screen too).
    if (now.role != said) {
      said = now.role;
      result.holder_line = HolderLine(now, vehicle, camera_name, domain);
      if (setup.progress || now.role == Role::kRefused) {
        if (now.role == Role::kRefused) {
          log::Warn(result.holder_line);
        } else {
          log::Info(result.holder_line);
        }
      }
      if (file) {
        file->InterfaceEvent(record::SessionEvent::Make(now_ns, t, "camera", -1, 255, 0.0,
                                                        result.holder_line.c_str()));
      }
    }
    if (now.role == Role::kHolding) result.held = true;

    if (Steerable(now.role)) {
      control.SetCamera(now.range, now.widest_fov_deg);
      if (!aimed) {
        // From where the camera points now (or --aim): the station takes
        // over the camera without jerking it round.
        control.Set(setup.aim.value_or(now.applied));
        aimed = true;
      }
      unsteerable_since = 0;
    } else if (now.role != Role::kWaiting) {
      if (unsteerable_since == 0) unsteerable_since = now_ns;
    }
    const interfaces::InputState person_input = input.Load();
    station.Aim(control.Step(person_input, pointer.Load(), 1.0 / kLoopRate_hz));

    const bool holding = now.role == Role::kHolding || now.role == Role::kFree;
    const link::VehicleGlance glance = station.Vehicle();
    if (glance.seq != 0) result.vehicle = glance;
    const std::string vehicle_line = VehicleText(vehicle, glance);
    const std::string camera_line =
        now.role == Role::kWaiting ? std::string() : StatusText(now.applied);
    screen.Publish(StationOverlay(camera_name, person, t, camera_line,
                                  holding                      ? std::string(kStationHelp)
                                  : now.role == Role::kRefused ? "REFUSED: " + HeldByText(now)
                                                               : result.holder_line,
                                  vehicle_line));
    // Without a window, a line now and then says what the screen would.
    if (setup.view == ViewChoice::kNone && setup.progress && !vehicle_line.empty() &&
        now_ns >= next_log_ns) {
      next_log_ns = now_ns + SToNs(kLogEvery_s);
      log::Info(vehicle_line + "; camera " + camera_name + " " + camera_line + " (" +
                ToString(now.role) + ")");
    }

    if (stop.load()) {
      result.outcome = StationOutcome::kInterrupted;
      result.message = "interrupted";
      break;
    }
    if (person_input.quit) {
      result.outcome = StationOutcome::kEnded;
      result.message = "the view was closed";
      break;
    }
    if (unsteerable_since != 0 && NsToS(now_ns - unsteerable_since) >= kNoCameraAfter_s) {
      result.outcome = StationOutcome::kNoCamera;
      result.message = result.holder_line;
      break;
    }
    if (now.role == Role::kWaiting && t >= kNoVehicleAfter_s) {
      result.outcome = StationOutcome::kNoVehicle;
      result.message = "vehicle '" + vehicle + "' did not say its cameras within " +
                       std::to_string(static_cast<int>(kNoVehicleAfter_s)) + " s on domain " +
                       std::to_string(domain);
      break;
    }
    if (setup.time_limit_s > 0 && t >= setup.time_limit_s) {
      result.outcome = StationOutcome::kTimeLimit;
      result.message =
          "time limit of " + std::to_string(static_cast<int>(setup.time_limit_s)) + " s reached";
      break;
    }
  }
  if (!result.held && result.camera.role == Role::kRefused &&
      result.outcome != StationOutcome::kNoCamera) {
    result.outcome = StationOutcome::kRefused;
    result.message = result.holder_line;
  }
  station.Release();
  result.duration_s = NsToS(MonotonicNs() - t0);
  result.figures = station.Figures();
  result.video = station.video().Stats();
  if (view) {
    view->Stop();  // finishes the MP4
    result.view = view->Stats();
    view.reset();
  }
  // Off the link before the file closes: no sample reaches a closed file.
  station_owner.reset();
  if (file) {
    file->InterfaceEvent(record::SessionEvent::Make(MonotonicNs(), result.duration_s, "end", -1,
                                                    255, 0.0, ToString(result.outcome)));
    result.session_file = file->Close();
  }
  return result;
}

}  // namespace haptel::station
