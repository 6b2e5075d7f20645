#pragma once
/// @file `haptel scene FILE [--json] [--config RUN.yaml]`: loads a haptic
/// scene (YAML, or the thesis's MHaptic XML) and prints what the run would
/// touch, in the device frame (x forward, y left, z up): each object (name,
/// static or dynamic, position, mass, material) with its shapes and their
/// parameters, the total mass of the dynamic objects, and the axis-aligned
/// bounding box of the bounded shapes (planes are unbounded and left out).
/// With --config, the run configuration's scene_placement is applied first.
/// --json prints the same as one JSON line.
#include <iosfwd>

namespace haptel::app {

/// argv[0] is "scene". Returns the exit code: 0 with the report on `out`, or
/// 2 with one line on `err` (a bad scene: "haptel: file:line: <element>: …").
int SceneCommand(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace haptel::app
