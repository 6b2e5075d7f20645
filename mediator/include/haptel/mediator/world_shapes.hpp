#pragma once
/// @file The mediator world as the view draws it: shapes for the proxy hands,
/// the tracked hands, the cockpit's wheel and lever, and the gesture wall,
/// with the sizes the physics world gives them (so what the person sees is
/// what their fingers touch). Device frame, metres. Allocation-free once the
/// vector has room (the view reserves it).
#include <vector>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/types.hpp"
#include "haptel/interfaces/cockpit_logic.hpp"
#include "haptel/physics/cockpit_controls.hpp"
#include "haptel/physics/proxy_hand.hpp"
#include "haptel/view/view_model.hpp"

namespace haptel::mediator {

/// The proxy hand: the palm box (its centre half a palm ahead of the wrist,
/// as ProxyHand builds it) and each phalanx's capsule. A finger whose servo
/// force is above 0.5 N turns its tip orange (the person feels it there).
void AppendProxyHand(std::vector<view::Shape>& shapes, const physics::HandPoses& poses,
                     const ProxyHandConfig& hand, haptics::Side side);

/// A tracked hand without a world: the palm box at the wrist pose.
void AppendTrackedHand(std::vector<view::Shape>& shapes, const haptics::HandSample& sample,
                       const ProxyHandConfig& hand);

/// The wheel (rim segments, spokes and column, turned by the controls' angle
/// about the axis pointing at the driver) and the throttle lever (knob on its
/// rail). Held controls are lit; a contact turns the rim red while it shakes.
void AppendCockpit(std::vector<view::Shape>& shapes, const CockpitConfig& cockpit,
                   const physics::ControlsBodyConfig& bodies,
                   const interfaces::CockpitControls& controls, bool contact);

/// The gesture interface's wall while it pushes back: a translucent red slab
/// on its plane, facing along its normal.
void AppendWall(std::vector<view::Shape>& shapes, const haptics::ForceField& field);

/// What a device that bends the hand's motion shows of it (the mouse's
/// pseudo-haptics): a translucent ghost where the input alone would put the
/// hand (blue while held, grey while free) and, once the two are more than
/// 5 mm apart, a thin line from the ghost to the hand: the bend.
void AppendPseudoHaptics(std::vector<view::Shape>& shapes,
                         const haptics::PseudoHapticReport& report);

/// The force on a hand as an arrow from `at` along it: 1 cm a newton, at
/// most 15 cm; none under 0.05 N.
void AppendForceArrow(std::vector<view::Shape>& shapes, const haptics::Vec3d& at,
                      const haptics::Vec3d& force);

/// Moves the shapes from index `first` on by `offset` (a hand's shake).
void ShiftShapes(std::vector<view::Shape>& shapes, size_t first, const haptics::Vec3d& offset);

}  // namespace haptel::mediator
