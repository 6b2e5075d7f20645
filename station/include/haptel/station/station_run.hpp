#pragma once
/// @file What `haptel station` does, apart from its command line: the
/// camera station (camera_station.hpp) on the link, the person's mouse,
/// keys and controller steering it (camera_control.hpp) in the control
/// room's window (station_view.hpp), the view recorded to MP4 and the
/// whole station into a session file, until the person ends it, the time
/// limit passes or a signal comes; then the camera released and the
/// figures.
#include <atomic>
#include <filesystem>
#include <optional>
#include <string>

#include "haptel/record/session_recorder.hpp"
#include "haptel/station/camera_station.hpp"
#include "haptel/video/video_receiver.hpp"
#include "haptel/view/view.hpp"

namespace haptel::station {

enum class ViewChoice {
  kWindow,  ///< a window on $DISPLAY (the person steers in it)
  kNone,    ///< no window: offscreen when an MP4 is recorded, else nothing drawn
};

struct StationSetup {
  StationOptions station;
  ViewChoice view = ViewChoice::kWindow;
  std::filesystem::path record;             ///< the control room's view as MP4 (empty: none)
  record::SessionFileOptions session_file;  ///< file empty: no session file
  std::optional<CameraAim> aim;             ///< where to point once the camera is known (--aim)
  double time_limit_s = 0.0;                ///< 0: until the person ends it
  bool progress = true;                     ///< say the camera's changes of hands on stderr
};

/// How the station ended.
enum class StationOutcome {
  kEnded,        ///< the person closed the window (or Escape)
  kTimeLimit,    ///< --time-limit passed
  kInterrupted,  ///< a signal
  kRefused,      ///< it never held the camera: another station held it all along
  kNoCamera,     ///< the vehicle has no such camera, or it cannot be steered
  kNoVehicle,    ///< the vehicle never said what cameras it has
};
const char* ToString(StationOutcome outcome);

struct StationResult {
  StationOutcome outcome = StationOutcome::kEnded;
  std::string message;          ///< one line: why it ended
  std::string holder_line;      ///< the camera's holder as last said (HolderLine)
  bool held = false;            ///< the vehicle named this station the holder at some time
  CameraNow camera;             ///< the camera as the vehicle last said it
  link::VehicleGlance vehicle;  ///< the vehicle as its last state said (seq 0: none came)
  StationFigures figures;
  video::VideoStats video;
  view::ViewStats view;
  bool view_shown = false;
  record::SessionFileReport session_file;
  double duration_s = 0.0;
};

/// The exit code: 0 ended, time limit or signal with the camera held;
/// 1 refused, no camera, no vehicle; 5 an MP4 or session file asked for
/// that was not written whole.
int ExitCode(const StationResult& result);

/// Runs the station until it ends (the person, the time limit, `stop`).
/// Throws view::ViewError when the window or the MP4 cannot be opened,
/// std::runtime_error when DDS or the session file refuses.
StationResult RunStation(const StationSetup& setup, const std::atomic<bool>& stop);

}  // namespace haptel::station
