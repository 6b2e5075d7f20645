#pragma once
/// @file Each vehicle kind's factory: how a vehicle node opens the kind's
/// adapter (and its own camera, where it has one), kept beside the kind's
/// row in config's table (config/vehicle_kinds.hpp). `haptel-vehicle` opens
/// any kind through OpenVehicle and runs it in the one VehicleNodeOf of its
/// family; nothing else tells kinds apart.
///
/// A new robot-like kind is one adapter file (a VehicleAdapter and its
/// factory), its registration (a row in each table, or RegisterKind at
/// start-up) and a vehicle file: docs/vehicles.md shows one.
#include <functional>
#include <memory>
#include <string>

#include "haptel/config/vehicle.hpp"
#include "haptel/config/vehicle_kinds.hpp"
#include "haptel/vehicles/families.hpp"
#include "haptel/vehicles/vehicle_node.hpp"
#include "haptel/video/camera_source.hpp"

namespace haptel::vehicles {

/// What a kind's factory opens.
template <class Family>
struct KindParts {
  std::unique_ptr<typename Family::Adapter> adapter;  ///< never null
  /// The kind's own camera (a ROS 2 robot's image topic); null: the one the
  /// vehicle file's `camera` section describes.
  std::unique_ptr<video::CameraSource> camera;
  /// More for the start-up line (", ROS 2 robot on domain 3 …"); may be empty.
  std::string detail;
  /// What the kind reports on a topic of its own, over its adapter (the CAN
  /// robot's bus log); null: nothing beyond the family's state.
  std::unique_ptr<KindReport> report;
};

/// Opens a kind's hardware (or simulator) for a validated `config` in its
/// world (a track, a blimp course). Set-up errors throw (ConfigError,
/// UsageError, CanUnavailable, a serial port's error): the program exits 2.
template <class Family>
using KindFactory =
    std::function<KindParts<Family>(const VehicleConfig&, const typename Family::World&)>;

/// The factory of `kind` in `Family`, or null.
template <class Family>
const KindFactory<Family>* FindKindFactory(const std::string& kind);

/// Registers a kind at start-up, both halves in one call: its row in
/// config's table (info.family is set to the Family's) and its factory.
/// Throws std::invalid_argument when the name is taken or malformed.
template <class Family>
void RegisterKind(VehicleKindInfo info, KindFactory<Family> factory);

/// A vehicle ready to run: its world loaded, then its hardware opened, then
/// its camera — so a bus or port that cannot open stops the program before a
/// camera or any DDS participant exists. Nothing is on DDS yet.
struct OpenedVehicle {
  /// "track 'grand prix', camera synthetic 640x480 at 30 Hz", for the start-up line.
  std::string description;
  /// Builds the node (joins DDS). Call once.
  std::function<std::unique_ptr<Node>()> make_node;
};

/// Opens the vehicle `config` (validated; read from `file`) describes, by
/// its kind's factory in its family. Throws as the factory does, and
/// ConfigError when `config.world` is not set.
OpenedVehicle OpenVehicle(const VehicleConfig& config, const std::string& file);

}  // namespace haptel::vehicles
