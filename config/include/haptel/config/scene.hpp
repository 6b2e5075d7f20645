#pragma once
/// @file The haptic scene description (config/scenes/*.yaml, or the original
/// MHaptic XML format): the touchable objects of the mediator world, each a
/// rigid body made of primitive shapes with a material. Pure data and maths;
/// the physics world builds its bodies from it (mass properties: see
/// mass_properties.hpp).
///
/// Frames and units: SI, world z up. An object's pose (position, rotation)
/// places its frame in the world; each shape's pose places the shape in the
/// object frame. Mass properties are expressed in the object frame.
///
/// ## YAML format (LoadScene)
///
/// ```yaml
/// objects:                          # required, at least one
///   - name: floor                   # required, unique
///     type: static                  # static | dynamic
///     position: [0, 0, 0]           # m, default [0, 0, 0]
///     material: carpet              # a preset name, or a mapping (below)
///     shapes:                       # required, at least one
///       - {type: plane, normal: [0, 0, 1], offset: 0}
///   - name: cube
///     type: dynamic
///     position: [0, 0, 0.8]
///     quaternion_wxyz: [0.9659258, 0, 0, 0.2588190]   # or rotation: 9 numbers
///     mass: 0.5                     # kg; or density: kg/m³ (exactly one of them)
///     material: {restitution: 0.4, static_friction: 0.5, dynamic_friction: 0.35}
///     shapes:
///       - {type: box, size: [0.1, 0.1, 0.1]}
/// ```
///
/// Object keys: `name`, `type`, `position`, at most one of `rotation` (a 3×3
/// rotation matrix as 9 numbers, row by row) and `quaternion_wxyz` (unit
/// quaternion [w, x, y, z]); identity when neither. `mass` or `density`:
/// exactly one on a dynamic object, neither on a static one (static objects do
/// not move). `material`: optional (default Material{}), either a preset name
/// (MaterialPresetNames()) or a mapping with all of `restitution` [0, 1],
/// `static_friction` and `dynamic_friction` [0, 2].
///
/// Shape keys: `type` and the type's dimensions, plus an optional local pose
/// `position` / `rotation` / `quaternion_wxyz` in the object frame:
/// - `box`: `half_extents: [hx, hy, hz]` or `size: [sx, sy, sz]` (full edge
///   lengths = 2 × half extents), exactly one of them;
/// - `sphere`: `radius`;
/// - `capsule`: `radius` and `length` (the cylinder between the two hemisphere
///   centres, along the local z axis; overall extent length + 2·radius);
/// - `plane`: `normal` (normalised on load, the offset with it) and `offset`:
///   the half-space n·x ≤ offset is solid (static objects only);
/// - `convex`: `points: [[x, y, z], ...]`, 4 to 64 points spanning a volume;
///   the shape is their convex hull (points need not all be hull vertices).
///
/// ## MHaptic XML format (ImportMhapticXml)
///
/// Reconstructed from the thesis' description (no original file was
/// available). Accepted subset:
///
/// ```xml
/// <?xml version="1.0" encoding="UTF-8"?>
/// <!-- comments anywhere -->
/// <MHAPTIC:scene>
///   <object type="Dynamic" name="cup">
///     <position>x y z</position>
///     <rotation>r00 r01 r02 r10 r11 r12 r20 r21 r22</rotation>
///     <shape type="Box" boxparams="hx hy hz"/>
///     <shape type="Sphere" sphereparams="r" position="x y z"/>
///     <shape type="Capsule" capsuleparams="r h"/>
///     <shape type="Plane" planeparams="nx ny nz d"/>
///     <density>500</density>            (or <mass>0.2</mass>)
///     <materialparams restitution="0.5" staticfriction="0.6" dynamicfriction="0.4"/>
///   </object>
/// </MHAPTIC:scene>
/// ```
///
/// - Syntax: elements, attributes ("…" or '…'), text, comments, CDATA, the
///   `<?xml …?>` declaration; entities &lt; &gt; &amp; &quot; &apos; and
///   numeric &#N; / &#xH;. No DOCTYPE, no namespace processing (`MHAPTIC:` is
///   part of the root's name).
/// - Names of elements and attributes and the values of `type` are matched
///   case-insensitively (`Dynamic`, `dynamic`; `staticFriction`).
/// - Every value (position, rotation, boxparams, density, mass, the material
///   coefficients, name, type) may be an attribute of its element or a child
///   element holding it as text — not both. `materialparams` may also be text:
///   "restitution staticfriction dynamicfriction".
/// - Number lists are separated by blanks and/or commas; every number must
///   parse completely and be finite ("1.0x" is an error).
/// - Conventions taken from AGEIA PhysX, which MHaptic ran on: `boxparams`
///   are half extents; `capsuleparams` = "radius height", height between the
///   hemisphere centres along the shape's local **y** axis (the importer turns
///   it onto this format's z axis by a local rotation); `planeparams` =
///   "nx ny nz d" with n·x = d; rotations are row-major.
/// - `name` optional (default "object<N>", 1-based); names must be unique.
///   `mass`/`density` on a static object are accepted and ignored; a dynamic
///   object needs exactly one. Planes only on static objects. Unknown elements
///   and attributes are errors naming file:line and the element (`xmlns…`
///   attributes are ignored).
#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace haptel {

/// Surface properties of one object. Contact pairs combine by average
/// (CombineMaterials), as in the original.
struct Material {
  double restitution = 0.3;       ///< [0, 1]
  double static_friction = 0.5;   ///< Coulomb coefficient, [0, 2]
  double dynamic_friction = 0.4;  ///< Coulomb coefficient, [0, 2]
  bool operator==(const Material&) const = default;
};

/// The named presets: wood, marble, brick, steel, aluminium, glass, carpet,
/// ice (values and sources in scene.cpp). nullopt for any other name.
std::optional<Material> MaterialPreset(const std::string& name);
/// The preset names, in the order above.
const std::vector<std::string>& MaterialPresetNames();
/// The coefficients of a contact between a and b: the average of each.
Material CombineMaterials(const Material& a, const Material& b);

enum class ShapeKind { kBox, kSphere, kCapsule, kPlane, kConvex };

/// "box", "sphere", "capsule", "plane", "convex".
const char* ShapeKindName(ShapeKind kind);

/// One primitive of an object, posed in the object frame. Only the fields of
/// its kind are meaningful.
struct SceneShape {
  ShapeKind kind = ShapeKind::kBox;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< m, object frame
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();  ///< box: half edge lengths, m
  double radius = 0.0;                                     ///< sphere, capsule: m
  double length = 0.0;  ///< capsule: cylinder length between hemisphere centres, local z, m
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< plane: unit normal (shape frame)
  double offset = 0.0;  ///< plane: n·x = offset on the surface, n·x < offset inside, m
  std::vector<Eigen::Vector3d> points;  ///< convex: the points whose hull is the shape
  /// kg/m³. > 0: this shape's own density (the XML format gives a mass or
  /// density per shape), which sets its share of the object's mass; 0: the
  /// object's (ComputeMassProperties).
  double density = 0.0;
};

struct SceneObject {
  std::string name;
  bool dynamic = false;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      ///< m, world
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< object → world
  std::vector<SceneShape> shapes;
  /// Dynamic objects: exactly one of mass (kg) and density (kg/m³) is > 0;
  /// the other is 0. Static objects: both 0.
  double mass = 0.0;
  double density = 0.0;
  Material material;
};

struct Scene {
  std::filesystem::path file;
  std::vector<SceneObject> objects;  ///< in file order
};

/// Loads and validates a YAML scene. Throws ConfigError naming the file, the
/// line and the key. Dynamic objects are checked to have a valid mass,
/// centre of mass and inertia.
Scene LoadScene(const std::filesystem::path& file);

/// Imports a scene in the original MHaptic XML format (subset above). Throws
/// ConfigError "file:line: element <name>…: …".
Scene ImportMhapticXml(const std::filesystem::path& file);

/// A scene file of either format: `.xml` is imported as MHaptic XML, anything
/// else is read as YAML.
Scene LoadSceneFile(const std::filesystem::path& file);

/// The haptic scene's node order: every object becomes a node; dynamic nodes
/// come first, static ones last (each group in file order), so synchronising
/// poses for the view walks the nodes and stops at the first static node
/// (SyncPoses).
struct SceneNodeOrder {
  std::vector<std::size_t> objects;  ///< indices into Scene::objects, node order
  std::size_t dynamic_count = 0;     ///< objects[0 .. dynamic_count) are dynamic

  std::span<const std::size_t> Dynamic() const { return {objects.data(), dynamic_count}; }
  std::span<const std::size_t> Static() const {
    return {objects.data() + dynamic_count, objects.size() - dynamic_count};
  }
};
SceneNodeOrder OrderNodes(const Scene& scene);

/// Pose synchronisation over nodes held in node order: calls sync(node) for
/// each node from the first while is_dynamic(node), and stops at the first
/// static node (static nodes never move, so nothing after it is visited).
/// Returns the number of nodes synchronised. Allocates nothing.
template <typename Node, typename IsDynamic, typename Sync>
std::size_t SyncPoses(std::span<Node> nodes, IsDynamic&& is_dynamic, Sync&& sync) {
  std::size_t count = 0;
  for (Node& node : nodes) {
    if (!is_dynamic(node)) break;
    sync(node);
    ++count;
  }
  return count;
}

}  // namespace haptel
