// The haptic scene description: the shipped YAML and XML examples load to
// the same scene; every kind of bad YAML file is a ConfigError naming the
// file, the line and the key (XML: test_scene_xml.cpp); material presets;
// node order; placement and bounds.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/geometry/mass_properties.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using haptel::ConfigError;
using haptel::ImportMhapticXml;
using haptel::LoadScene;
using haptel::Material;
using haptel::Scene;
using haptel::ShapeKind;

namespace {

// This process's scratch folder, removed when the tests end.
struct ScratchFolder {
  fs::path dir = haptel::test::ScratchDir("test_scene");
  ~ScratchFolder() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

const fs::path& Scratch() {
  static const ScratchFolder folder;
  return folder.dir;
}

fs::path Write(const std::string& name, const std::string& text) {
  return haptel::test::WriteFile(Scratch() / name, text);
}

// The ConfigError message of loading `text` (as YAML or XML by the name's
// extension); fails the test when it loads.
std::string ErrorOf(const std::string& name, const std::string& text) {
  const fs::path file = Write(name, text);
  try {
    if (file.extension() == ".xml") {
      ImportMhapticXml(file);
    } else {
      LoadScene(file);
    }
  } catch (const ConfigError& e) {
    return e.what();
  }
  FAIL("'" << name << "' loaded without an error");
  return "";
}

void RequireNearV(const Vector3d& a, const Vector3d& b, double tol = 1e-9) {
  INFO(a.transpose() << " vs " << b.transpose());
  REQUIRE((a - b).cwiseAbs().maxCoeff() <= tol);
}

void RequireNearM(const Matrix3d& a, const Matrix3d& b, double tol = 1e-6) {
  INFO(a << "\nvs\n" << b);
  REQUIRE((a - b).cwiseAbs().maxCoeff() <= tol);
}

void RequireSameScene(const Scene& a, const Scene& b) {
  REQUIRE(a.objects.size() == b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) {
    const auto& x = a.objects[i];
    const auto& y = b.objects[i];
    INFO("object " << i << " '" << x.name << "'");
    REQUIRE(x.name == y.name);
    REQUIRE(x.dynamic == y.dynamic);
    RequireNearV(x.position, y.position);
    RequireNearM(x.rotation, y.rotation);
    REQUIRE(x.mass == Approx(y.mass));
    REQUIRE(x.density == Approx(y.density));
    REQUIRE(x.material == y.material);
    if (x.dynamic) {
      const auto p = haptel::ComputeMassProperties(x);
      const auto q = haptel::ComputeMassProperties(y);
      REQUIRE(p.mass == Approx(q.mass));
      RequireNearV(p.com, q.com);
      RequireNearM(p.inertia, q.inertia, 1e-12);
    }
    REQUIRE(x.shapes.size() == y.shapes.size());
    for (size_t j = 0; j < x.shapes.size(); ++j) {
      const auto& s = x.shapes[j];
      const auto& t = y.shapes[j];
      INFO("shape " << j);
      REQUIRE(s.kind == t.kind);
      RequireNearV(s.position, t.position);
      RequireNearM(s.rotation, t.rotation);
      RequireNearV(s.half_extents, t.half_extents);
      REQUIRE(s.radius == Approx(t.radius));
      REQUIRE(s.length == Approx(t.length));
      RequireNearV(s.normal, t.normal);
      REQUIRE(s.offset == Approx(t.offset));
      REQUIRE(s.points.size() == t.points.size());
    }
  }
}

// "file:LINE:" or "file:LINE: " at the start of a message.
void RequireLocated(const std::string& message, const fs::path& file, int line) {
  INFO(message);
  REQUIRE_THAT(message, Contains(file.string() + ":" + std::to_string(line) + ":"));
}

const char* const kGoodObjects = R"(objects:
  - name: ground
    type: static
    shapes:
      - {type: plane, normal: [0, 0, 1], offset: 0}
)";

}  // namespace

TEST_CASE("the shipped table scene loads from YAML and from XML (y up) to the same scene",
          "[scene]") {
  const Scene yaml = LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  const Scene xml = ImportMhapticXml(haptel::ShippedFile("config/scenes/table.xml"));
  RequireSameScene(yaml, xml);

  REQUIRE(yaml.objects.size() == 3);
  const auto& floor = yaml.objects[0];
  REQUIRE(floor.name == "floor");
  REQUIRE_FALSE(floor.dynamic);
  REQUIRE(floor.shapes.size() == 1);
  REQUIRE(floor.shapes[0].kind == ShapeKind::kPlane);
  RequireNearV(floor.shapes[0].normal, Vector3d::UnitZ());
  REQUIRE(floor.material == *haptel::MaterialPreset("carpet"));

  const auto& table = yaml.objects[1];
  REQUIRE_FALSE(table.dynamic);
  REQUIRE(table.shapes.size() == 5);
  RequireNearV(table.shapes[0].half_extents, Vector3d(0.6, 0.4, 0.02));
  RequireNearV(table.shapes[0].position + Vector3d(0, 0, 0.02), Vector3d(0, 0, 0.75));  // top face
  RequireNearV(table.shapes[1].half_extents, Vector3d(0.025, 0.025, 0.355));            // size / 2
  REQUIRE(table.material == *haptel::MaterialPreset("wood"));
  REQUIRE(table.mass == 0.0);
  REQUIRE(table.density == 0.0);

  const auto& box = yaml.objects[2];
  REQUIRE(box.dynamic);
  REQUIRE(box.mass == 0.5);
  REQUIRE(box.density == 0.0);
  RequireNearM(box.rotation,
               Eigen::AngleAxisd(std::numbers::pi / 6, Vector3d::UnitZ()).toRotationMatrix());
  REQUIRE(box.material == Material{0.4, 0.5, 0.35});
  // Resting on the table top: its bottom face at the top's height.
  REQUIRE(box.position.z() - box.shapes[0].half_extents.z() == Approx(0.75));
  const auto mass = haptel::ComputeMassProperties(box);
  REQUIRE(mass.mass == Approx(0.5));
  REQUIRE(mass.inertia(0, 0) == Approx(0.5 / 6 * 0.01));  // m a² / 6 for a cube of edge a
}

TEST_CASE("node order: dynamic objects first, static last; pose sync stops at the first static",
          "[scene]") {
  Scene scene;
  const bool dynamic[] = {false, true, false, true, true};
  for (int i = 0; i < 5; ++i) {
    haptel::SceneObject o;
    o.name = "o";
    o.name += std::to_string(i);  // (not "o" + …: GCC 12 -Wrestrict false positive)
    o.dynamic = dynamic[i];
    scene.objects.push_back(o);
  }
  const auto order = haptel::OrderNodes(scene);
  REQUIRE(order.objects == std::vector<size_t>{1, 3, 4, 0, 2});
  REQUIRE(order.dynamic_count == 3);
  REQUIRE(std::vector<size_t>(order.Dynamic().begin(), order.Dynamic().end()) ==
          std::vector<size_t>{1, 3, 4});
  REQUIRE(std::vector<size_t>(order.Static().begin(), order.Static().end()) ==
          std::vector<size_t>{0, 2});

  struct Node {
    bool dynamic;
    int synced = 0;
  };
  std::vector<Node> nodes;
  for (size_t index : order.objects) nodes.push_back({scene.objects[index].dynamic});
  const auto is_dynamic = [](const Node& n) { return n.dynamic; };
  const auto sync = [](Node& n) { ++n.synced; };
  REQUIRE(haptel::SyncPoses(std::span<Node>(nodes), is_dynamic, sync) == 3);
  for (size_t i = 0; i < nodes.size(); ++i) REQUIRE(nodes[i].synced == (i < 3 ? 1 : 0));

  // The walk stops at the first static node, whatever follows it.
  std::vector<Node> unordered{{true}, {false}, {true}};
  REQUIRE(haptel::SyncPoses(std::span<Node>(unordered), is_dynamic, sync) == 1);
  REQUIRE(unordered[2].synced == 0);

  const Scene table = LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  const auto table_order = haptel::OrderNodes(table);
  REQUIRE(table_order.objects == std::vector<size_t>{2, 0, 1});
  REQUIRE(table_order.dynamic_count == 1);
}

TEST_CASE("material presets and pair averaging", "[scene][material]") {
  const std::vector<std::string> expected{"wood",      "marble", "brick",  "steel",
                                          "aluminium", "glass",  "carpet", "ice"};
  REQUIRE(haptel::MaterialPresetNames() == expected);
  for (const auto& name : expected) {
    const auto m = haptel::MaterialPreset(name);
    REQUIRE(m.has_value());
    INFO(name);
    REQUIRE(m->restitution >= 0.0);
    REQUIRE(m->restitution <= 1.0);
    REQUIRE(m->dynamic_friction > 0.0);
    REQUIRE(m->dynamic_friction <= m->static_friction);
  }
  REQUIRE_FALSE(haptel::MaterialPreset("rubber").has_value());
  REQUIRE_FALSE(haptel::MaterialPreset("Wood").has_value());
  // Sanity against the tables: ice is slipperiest, steel on steel μs 0.74.
  REQUIRE(haptel::MaterialPreset("ice")->static_friction <
          haptel::MaterialPreset("wood")->static_friction);
  REQUIRE(haptel::MaterialPreset("steel")->static_friction == Approx(0.74));

  const Material a{0.2, 0.6, 0.4};
  const Material b{0.6, 0.2, 0.1};
  const Material ab = haptel::CombineMaterials(a, b);
  REQUIRE(ab.restitution == Approx(0.4));
  REQUIRE(ab.static_friction == Approx(0.4));
  REQUIRE(ab.dynamic_friction == Approx(0.25));
  REQUIRE(haptel::CombineMaterials(b, a) == ab);
  REQUIRE(haptel::CombineMaterials(a, a) == a);
  const Material steel_ice =
      haptel::CombineMaterials(*haptel::MaterialPreset("steel"), *haptel::MaterialPreset("ice"));
  REQUIRE(steel_ice.static_friction == Approx((0.74 + 0.1) / 2));
}

TEST_CASE("YAML scene: every form the header documents loads", "[scene]") {
  const fs::path file = Write("forms.yaml", R"(objects:
  - name: blob
    type: dynamic
    position: [1, 2, 3]
    rotation: [0, -1, 0,  1, 0, 0,  0, 0, 1]
    density: 1000
    material: steel
    shapes:
      - {type: sphere, radius: 0.1}
      - {type: capsule, radius: 0.02, length: 0.1, position: [0, 0, 0.2], quaternion_wxyz: [0.7071068, 0.7071068, 0, 0]}
      - type: convex
        points: [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1], [0.01, 0.01, 0.01]]
  - name: ground
    type: static
    shapes:
      - {type: plane, normal: [0, 0, 2], offset: 1}
)");
  const Scene s = LoadScene(file);
  REQUIRE(s.objects.size() == 2);
  const auto& blob = s.objects[0];
  RequireNearV(blob.position, Vector3d(1, 2, 3));
  RequireNearV(blob.rotation * Vector3d::UnitX(), Vector3d::UnitY());
  REQUIRE(blob.density == 1000.0);
  REQUIRE(blob.material == *haptel::MaterialPreset("steel"));
  REQUIRE(blob.shapes[1].kind == ShapeKind::kCapsule);
  RequireNearV(blob.shapes[1].rotation * Vector3d::UnitZ(), -Vector3d::UnitY(), 1e-6);
  REQUIRE(blob.shapes[2].points.size() == 5);
  const auto& ground = s.objects[1];
  RequireNearV(ground.shapes[0].normal, Vector3d::UnitZ());
  REQUIRE(ground.shapes[0].offset == Approx(0.5));  // normalised with the normal
  REQUIRE(ground.material == Material{});
}

TEST_CASE("YAML scene: bad files name the file, the line and the key", "[scene][errors]") {
  SECTION("unknown key") {
    const std::string text = std::string(kGoodObjects) + "    colour: red\n";
    const std::string message = ErrorOf("unknown.yaml", text);
    RequireLocated(message, Scratch() / "unknown.yaml", 6);
    REQUIRE_THAT(message, Contains("objects[0].colour") && Contains("unknown key"));
  }
  SECTION("unknown key in a shape") {
    const std::string message = ErrorOf("shape_key.yaml", R"(objects:
  - name: ball
    type: dynamic
    mass: 1
    shapes:
      - {type: sphere, radius: 0.1, size: [1, 1, 1]}
)");
    RequireLocated(message, Scratch() / "shape_key.yaml", 6);
    REQUIRE_THAT(message, Contains("objects[0].shapes[0].size") && Contains("unknown key"));
  }
  SECTION("mass and density both") {
    const std::string message = ErrorOf("both.yaml", R"(objects:
  - name: ball
    type: dynamic
    mass: 1
    density: 500
    shapes:
      - {type: sphere, radius: 0.1}
)");
    RequireLocated(message, Scratch() / "both.yaml", 5);
    REQUIRE_THAT(message, Contains("objects[0].density") && Contains("not both"));
  }
  SECTION("neither mass nor density on a dynamic object") {
    const std::string message = ErrorOf("neither.yaml", R"(objects:
  - name: ball
    type: dynamic
    shapes:
      - {type: sphere, radius: 0.1}
)");
    RequireLocated(message, Scratch() / "neither.yaml", 2);
    REQUIRE_THAT(message, Contains("objects[0].mass"));
  }
  SECTION("mass on a static object") {
    const std::string message =
        ErrorOf("static_mass.yaml", std::string(kGoodObjects) + "    mass: 3\n");
    RequireLocated(message, Scratch() / "static_mass.yaml", 6);
    REQUIRE_THAT(message, Contains("objects[0].mass") && Contains("static"));
  }
  SECTION("plane on a dynamic object") {
    const std::string message = ErrorOf("plane.yaml", R"(objects:
  - name: slab
    type: dynamic
    mass: 1
    shapes:
      - {type: sphere, radius: 0.1}
      - {type: plane, normal: [0, 0, 1], offset: 0}
)");
    RequireLocated(message, Scratch() / "plane.yaml", 7);
    REQUIRE_THAT(message, Contains("objects[0].shapes[1].type") &&
                              Contains("planes only on static objects"));
  }
  SECTION("bad number") {
    const std::string message = ErrorOf("number.yaml", R"(objects:
  - name: ball
    type: dynamic
    mass: 1
    shapes:
      - type: sphere
        radius: 0.1x
)");
    RequireLocated(message, Scratch() / "number.yaml", 7);
    REQUIRE_THAT(message, Contains("objects[0].shapes[0].radius") && Contains("'0.1x'"));
  }
  SECTION("unknown preset") {
    const std::string message =
        ErrorOf("preset.yaml", std::string(kGoodObjects) + "    material: rubber\n");
    RequireLocated(message, Scratch() / "preset.yaml", 6);
    REQUIRE_THAT(message, Contains("objects[0].material") && Contains("wood, marble") &&
                              Contains("'rubber'"));
  }
  SECTION("incomplete explicit material") {
    const std::string message =
        ErrorOf("material.yaml", std::string(kGoodObjects) +
                                     "    material: {restitution: 0.2, static_friction: 0.5}\n");
    REQUIRE_THAT(message,
                 Contains("material.yaml:6") && Contains("objects[0].material.dynamic_friction"));
  }
  SECTION("a rotation that is not one") {
    const std::string message =
        ErrorOf("rotation.yaml",
                std::string(kGoodObjects) + "    rotation: [1, 0, 0, 0, 1, 0, 0, 0, 0.5]\n");
    RequireLocated(message, Scratch() / "rotation.yaml", 6);
    REQUIRE_THAT(message, Contains("objects[0].rotation") && Contains("rotation matrix"));
  }
  SECTION("flat convex points") {
    const std::string message = ErrorOf("flat.yaml", R"(objects:
  - name: card
    type: dynamic
    mass: 0.01
    shapes:
      - type: convex
        points: [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
)");
    RequireLocated(message, Scratch() / "flat.yaml", 7);
    REQUIRE_THAT(message, Contains("objects[0].shapes[0].points") && Contains("volume"));
  }
  SECTION("a bad convex point") {
    const std::string message = ErrorOf("point.yaml", R"(objects:
  - name: tet
    type: dynamic
    mass: 0.01
    shapes:
      - type: convex
        points:
          - [0, 0, 0]
          - [1, 0, 0]
          - [0, 1]
          - [0, 0, 1]
)");
    RequireLocated(message, Scratch() / "point.yaml", 10);
    REQUIRE_THAT(message, Contains("objects[0].shapes[0].points[2]"));
  }
  SECTION("duplicate names") {
    const std::string message =
        ErrorOf("twice.yaml", std::string(kGoodObjects) + R"(  - name: ground
    type: static
    shapes:
      - {type: plane, normal: [0, 0, 1], offset: 0}
)");
    RequireLocated(message, Scratch() / "twice.yaml", 6);
    REQUIRE_THAT(message, Contains("objects[1].name"));
  }
  SECTION("box with both size and half extents; unknown shape type") {
    REQUIRE_THAT(ErrorOf("box.yaml", R"(objects:
  - name: b
    type: static
    shapes:
      - {type: box, size: [1, 1, 1], half_extents: [1, 1, 1]}
)"),
                 Contains("box.yaml:5") && Contains("objects[0].shapes[0].size"));
    REQUIRE_THAT(
        ErrorOf("cone.yaml", R"(objects:
  - name: b
    type: static
    shapes:
      - {type: cone, radius: 1}
)"),
        Contains("cone.yaml:5") && Contains("objects[0].shapes[0].type") && Contains("'cone'"));
  }
  SECTION("no objects") {
    REQUIRE_THAT(ErrorOf("empty.yaml", "objects: []\n"),
                 Contains("empty.yaml") && Contains("'objects'"));
  }
}

TEST_CASE("placement: a scene moved and turned as a whole; roll, pitch, yaw about fixed axes",
          "[scene][placement]") {
  using haptel::RotationFromRpyDeg;
  RequireNearM(RotationFromRpyDeg(Vector3d::Zero()), Matrix3d::Identity(), 0.0);
  // Roll first (about x), then yaw (about z): y → z (roll 90°) stays z; x → y (yaw 90°).
  const Matrix3d r = RotationFromRpyDeg(Vector3d(90, 0, 90));
  RequireNearV(r * Vector3d::UnitY(), Vector3d::UnitZ(), 1e-12);
  RequireNearV(r * Vector3d::UnitX(), Vector3d::UnitY(), 1e-12);
  RequireNearM(RotationFromRpyDeg(Vector3d(10, 20, 30)),
               (Eigen::AngleAxisd(30 * std::numbers::pi / 180, Vector3d::UnitZ()) *
                Eigen::AngleAxisd(20 * std::numbers::pi / 180, Vector3d::UnitY()) *
                Eigen::AngleAxisd(10 * std::numbers::pi / 180, Vector3d::UnitX()))
                   .toRotationMatrix(),
               1e-12);

  const Scene table = LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  REQUIRE(haptel::PlaceScene(table, haptel::ScenePlacement{}).objects[2].position ==
          table.objects[2].position);
  haptel::ScenePlacement placement;
  placement.position = Vector3d(0.2, 0.0, -0.75);
  placement.rotation = RotationFromRpyDeg(Vector3d(0, 0, 90));
  REQUIRE_FALSE(placement.IsIdentity());
  const Scene placed = haptel::PlaceScene(table, placement);
  const auto& box = placed.objects[2];
  // The box at (0.1, 0, 0.8) turns to (0, 0.1, 0.8), then moves.
  RequireNearV(box.position, Vector3d(0.2, 0.1, 0.05), 1e-12);
  RequireNearM(box.rotation, placement.rotation * table.objects[2].rotation, 1e-12);
  // Shapes stay where they are in their objects.
  RequireNearV(placed.objects[1].shapes[0].position, table.objects[1].shapes[0].position, 0.0);
  // The floor plane z = 0 becomes z = -0.75 in the world.
  const auto& floor = placed.objects[0];
  const Vector3d n = floor.rotation * floor.shapes[0].normal;
  REQUIRE(n.dot(floor.position) + floor.shapes[0].offset == Approx(-0.75));
}

TEST_CASE("bounds: each shape's world box; planes are unbounded", "[scene][bounds]") {
  const Scene table = LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  REQUIRE_FALSE(haptel::ShapeBounds(table.objects[0], table.objects[0].shapes[0]));
  const auto bounds = haptel::SceneBounds(table);
  REQUIRE(bounds);
  // The table top (1.2 × 0.8 m) spans x and y; z from the floor to the box's top.
  RequireNearV(bounds->min, Vector3d(-0.6, -0.4, 0.0), 1e-12);
  RequireNearV(bounds->max, Vector3d(0.6, 0.4, 0.85), 1e-12);
  // The box, turned 30° about z: half width 0.05·(cos 30° + sin 30°).
  const auto box = haptel::ShapeBounds(table.objects[2], table.objects[2].shapes[0]);
  REQUIRE(box);
  const double h = 0.05 * (std::cos(std::numbers::pi / 6) + std::sin(std::numbers::pi / 6));
  RequireNearV(box->max - box->min, Vector3d(2 * h, 2 * h, 0.1), 1e-9);

  haptel::SceneObject o;
  o.rotation = Eigen::AngleAxisd(std::numbers::pi / 2, Vector3d::UnitX()).toRotationMatrix();
  o.position = Vector3d(1, 2, 3);
  haptel::SceneShape capsule;
  capsule.kind = ShapeKind::kCapsule;
  capsule.radius = 0.1;
  capsule.length = 1.0;
  const auto c = haptel::ShapeBounds(o, capsule);  // its axis (z) turned onto -y
  REQUIRE(c);
  RequireNearV(c->min, Vector3d(0.9, 1.4, 2.9), 1e-12);
  RequireNearV(c->max, Vector3d(1.1, 2.6, 3.1), 1e-12);

  Scene planes;
  planes.objects.push_back(table.objects[0]);
  REQUIRE_FALSE(haptel::SceneBounds(planes));
}
