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
/// The thesis's own format (Appendix I: "The Haptic Scene file format", its
/// DTD and example; tests/config/data/thesis_appendix_i.xml is that example):
///
/// ```xml
/// <?xml version="1.0" encoding="ISO-8859-1" ?>
/// <!DOCTYPE MHAPTIC:scene SYSTEM "HapticScene.dtd">
/// <MHAPTIC:scene xmlns:MHAPTIC="http://vrlab.epfl.ch/~reno">
///   <MHAPTIC:object type="Dynamic">              <!-- Static | Dynamic -->
///     <MHAPTIC:name>cup</MHAPTIC:name>
///     <MHAPTIC:position> <float>x</float> <float>y</float> <float>z</float> </MHAPTIC:position>
///     <MHAPTIC:rotation> 9 numbers, row by row </MHAPTIC:rotation>
///     <MHAPTIC:shape type="Box">                 <!-- Plane | Sphere | Box | Capsule -->
///       <MHAPTIC:position> 3 numbers </MHAPTIC:position>   <!-- in the object frame -->
///       <MHAPTIC:rotation> 9 numbers </MHAPTIC:rotation>
///       <MHAPTIC:mass> 1 number </MHAPTIC:mass>  <!-- or <MHAPTIC:density> -->
///       <MHAPTIC:materialparams> restitution, static, dynamic friction </MHAPTIC:materialparams>
///       <MHAPTIC:boxparams> half sides: 3 numbers </MHAPTIC:boxparams>
///     </MHAPTIC:shape>
///   </MHAPTIC:object>
/// </MHAPTIC:scene>
/// ```
///
/// - XML through tinyxml2. The `<?xml …?>` declaration may say UTF-8 or
///   ISO-8859-1 (transcoded); the DOCTYPE must name MHAPTIC:scene and is not
///   fetched; comments anywhere. Names are matched exactly as the DTD spells
///   them, `MHAPTIC:` prefix included; the root needs its `xmlns:MHAPTIC`.
/// - A number is an element `<float>`, `<double>` or `<integer>` holding one
///   finite number (an integer for `<integer>`); position, rotation, mass,
///   density, materialparams and the *params elements hold only those.
/// - Scene: at least one object (the DTD allows none; an empty scene is
///   refused, as in YAML). Object: `type` attribute, then name (unique,
///   non-empty), position, rotation and one or more shapes. Shape: `type` attribute, position,
///   rotation, mass or density, materialparams, and the parameters of its
///   type. Each child at most once; order free (the DTD's order is the one
///   written); unknown elements, attributes and text are errors.
/// - Mass (PhysX 2 NxShapeDesc, per shape): `mass` > 0 is the shape's mass;
///   `mass` ≤ 0 means density × volume with the default density 1 kg/m³;
///   `density` (kg/m³) × volume otherwise. A dynamic object's shape needs
///   exactly one of them; on a static object they are optional and ignored.
///   The object's mass is the sum; SceneShape::density keeps each shape's share.
/// - Parameters: `planeparams` a b c d for ax + by + cz = d (normal out of the
///   solid; static objects only); `sphereparams` radius; `boxparams` half
///   sides; `capsuleparams` radius and length, the length being the full
///   distance between the two hemisphere centres (PhysX 2's
///   NxCapsuleShapeDesc::height; overall extent length + 2·radius) along the
///   shape's local y axis. `trimeshparams`/type Trimesh: "not supported"
///   (the thesis marks it so too).
/// - `materialparams` (not in the DTD; the example writes it in the shape):
///   restitution, static friction, dynamic friction. Haptel has one material
///   per object: the shapes of an object that give one must agree; none gives
///   Material{}.
/// - Frame: the file is in the thesis's world frame (y up, x to the
///   operator's right, z towards the operator); the importer converts every
///   pose and parameter to the device frame of this header (MhapticToDevice).
///   Rotations are read row by row (the thesis does not say; its example
///   has only identities).
/// - Errors: ConfigError "file:line: <element>: what was expected", one line.
///
/// A run may move a loaded scene (either format) by a placement
/// (RunConfig::scene_placement, PlaceScene).
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

/// Imports a scene in the thesis's MHaptic XML format (above), converted to
/// the device frame. Throws ConfigError "file:line: <element>: …".
Scene ImportMhapticXml(const std::filesystem::path& file);

/// The rotation taking the MHaptic file frame (y up) to the device frame
/// (z up): v_device = MhapticToDevice() · v_file. Derivation in scene_xml.cpp.
Eigen::Matrix3d MhapticToDevice();

/// A scene file of either format: `.xml` is imported as MHaptic XML, anything
/// else is read as YAML.
Scene LoadSceneFile(const std::filesystem::path& file);

/// Where a run puts a scene in the device frame: every object's pose p, R
/// becomes position + rotation·p, rotation·R.
struct ScenePlacement {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      ///< m
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< proper rotation
  bool IsIdentity() const;

  /// Throws ConfigFieldError unless the position is within ±100 m and the
  /// rotation is a proper rotation (orthonormal, determinant 1).
  void ValidateOrThrow() const;
};

/// The rotation of roll, pitch, yaw in degrees about the fixed x, y, z axes,
/// applied in that order: Rz(yaw)·Ry(pitch)·Rx(roll).
Eigen::Matrix3d RotationFromRpyDeg(const Eigen::Vector3d& rpy_deg);

/// The scene moved by `placement`.
Scene PlaceScene(Scene scene, const ScenePlacement& placement);

/// An axis-aligned box in the scene's (device) frame.
struct Aabb {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
};
/// The tight box around one shape of `object` in the world; nullopt for a
/// plane (unbounded).
std::optional<Aabb> ShapeBounds(const SceneObject& object, const SceneShape& shape);
/// The box around every bounded shape of the scene; nullopt when there is
/// none (only planes).
std::optional<Aabb> SceneBounds(const Scene& scene);

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
