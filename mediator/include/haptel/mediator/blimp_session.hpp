#pragma once
/// @file A blimp flight: the session for a blimp vehicle (RunSession calls
/// it when the setup has a blimp course). The same parts as the robot's
/// session — the haptic side, the operator, the vehicle link, the recorder —
/// with the blimp gesture cockpit as the interface, the blimp's own lap
/// timer (3-D gates, a crash, the landing) and the automatic pilot.
///
/// Not yet: a view of its own (the blimp's flight runs with --view none).
#include <atomic>

#include "haptel/mediator/session.hpp"

namespace haptel::mediator {

/// Flies the course once (or until the cap, a crash, a lost vehicle or
/// device, or `interrupted`). `setup.course` and `setup.blimp_interface`
/// must be set. Throws for parts that cannot be set up.
SessionResult RunBlimpSession(const SessionSetup& setup, const std::atomic<bool>& interrupted);

}  // namespace haptel::mediator
