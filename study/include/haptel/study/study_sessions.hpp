#pragma once
/// @file The sessions a study runs (haptel study run): each trial's, as
/// `haptel run` would drive it with the study's options, and a person's
/// practice lap before their first trial.
#include <filesystem>
#include <string>

#include "haptel/config/study.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/study/console.hpp"
#include "haptel/study/store.hpp"

namespace haptel::study {

/// The session of one trial, shared by `haptel study run` and `haptel
/// study power` so both run a trial alike: what `haptel run` would drive
/// with these options (its track, interface, the condition's device
/// (`--device`), operator, a person's window, the cap on the lap's clock,
/// the study's link; a synthetic participant's driver profile and
/// `experience` trials done before), in simulated time when asked (`haptel
/// run --simulated-time`: one simulated clock for the whole process, so one
/// such trial at a time per process). No practice aids: the camera on its
/// screen, the interfaces' controls, no third-person view. Throws
/// ConfigError/UsageError as `haptel run`.
mediator::SessionSetup TrialSetup(const StudyConfig& config, const PlannedTrial& trial,
                                  const std::filesystem::path& database, const std::string& domain,
                                  bool verbose, int experience, bool simulated_time);

/// Whether a person can drive `trial` (a TrialSetup): with keys or a game
/// controller, or with their hands on a device they can move (the mouse, a
/// force-feedback joystick or wheel, the arms) — not on the simulated
/// device, whose arms nobody can move (its trials run to the cap).
bool PersonCanDrive(const mediator::SessionSetup& trial);

/// The condition's input device as the console shows and checks it before
/// its trial starts (haptics::DeviceUnavailable). Empty (nothing to show or
/// check) when the condition has none set.
TrialDevice DeviceOf(const StudyCondition& condition);

/// Makes `setup` a person's practice lap (the thesis's): the camera's
/// picture filling the window, the keyboard alone (nothing else drawn over
/// the picture, no switching), the participant in the window's title, and
/// for a simulated robot the third-person view beside the camera's picture
/// (SessionSetup::third_person).
void MakePracticeLap(mediator::SessionSetup& setup, const std::string& participant);

/// A person's practice lap on the study's track with the keyboard, recorded
/// as a run but not as a trial (needs a display: its keys are read in the
/// view's window).
mediator::SessionSetup PracticeSetup(const StudyConfig& config,
                                     const std::filesystem::path& database,
                                     const std::string& domain, bool verbose,
                                     const std::string& participant);

}  // namespace haptel::study
