#pragma once
/// @file What the mediator knows of the blimp at one instant: its reported
/// state as the link delivers it (the simulator's or the real blimp's).
#include <Eigen/Core>
#include <cstdint>

namespace haptel::mediator {

struct BlimpObservation {
  double t_s = 0.0;  ///< s, any monotonic origin
  Eigen::Vector3d position =
      Eigen::Vector3d::Zero();  ///< centre of gravity, world (x east, y north, z up), m
  double yaw = 0.0;             ///< rad, counter-clockwise from +x
  double pitch = 0.0;           ///< rad, nose up positive
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< ground velocity, world, m/s
  double airspeed = 0.0;                               ///< m/s
  bool contact = false;                                ///< touching the ground or a building
  /// Contact onsets so far, as the vehicle counts them: a contact that
  /// begins and ends between two observations still counts.
  uint32_t contacts = 0;
  /// m/s: the normal closing speed at the onset of the latest contact.
  double impact_speed = 0.0;
};

}  // namespace haptel::mediator
