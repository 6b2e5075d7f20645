// The thesis's haptic scene format (Appendix I): its own example loads with
// the frame converted to the device's; scenes of our own in the format load
// with per-shape masses, densities and materials; every malformed file is one
// line "file:line: <element>: what was expected"; a 10 MB scene loads.
#include <Eigen/Geometry>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
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
using haptel::Material;
using haptel::Scene;
using haptel::ShapeKind;

namespace {

constexpr double kPi = std::numbers::pi;

struct ScratchFolder {
  fs::path dir = haptel::test::ScratchDir("test_scene_xml");
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
  const fs::path file = Scratch() / name;
  std::ofstream out(file, std::ios::binary);
  out << text;
  REQUIRE(out.good());
  return file;
}

// The ConfigError message of importing `text`; fails the test when it loads.
// Every message is one line.
std::string ErrorOf(const std::string& name, const std::string& text) {
  const fs::path file = Write(name, text);
  try {
    ImportMhapticXml(file);
  } catch (const ConfigError& e) {
    const std::string message = e.what();
    INFO(message);
    REQUIRE(message.find('\n') == std::string::npos);
    return message;
  }
  FAIL("'" << name << "' loaded without an error");
  return "";
}

// 1-based number of the first line of text that contains marker (which must
// occur once).
int LineOf(const std::string& text, const std::string& marker) {
  const size_t at = text.find(marker);
  REQUIRE(at != std::string::npos);
  REQUIRE(text.find(marker, at + 1) == std::string::npos);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
}

// "file:LINE: <element>:" at the start of the message.
void RequireAt(const std::string& message, const std::string& name, int line,
               const std::string& element) {
  INFO(message);
  const std::string head =
      (Scratch() / name).string() + ":" + std::to_string(line) + ": <" + element + ">: ";
  REQUIRE(message.rfind(head, 0) == 0);
}

void RequireNearV(const Vector3d& a, const Vector3d& b, double tol = 1e-9) {
  INFO(a.transpose() << " vs " << b.transpose());
  REQUIRE((a - b).cwiseAbs().maxCoeff() <= tol);
}

void RequireNearM(const Matrix3d& a, const Matrix3d& b, double tol = 1e-9) {
  INFO(a << "\nvs\n" << b);
  REQUIRE((a - b).cwiseAbs().maxCoeff() <= tol);
}

// ---- writing the format, one element per line -------------------------------

std::string Numbers(const std::string& tag, const std::vector<std::string>& values,
                    const std::string& number = "float") {
  std::string out = "<MHAPTIC:" + tag + ">\n";
  for (const std::string& v : values) out += "  <" + number + ">" + v + "</" + number + ">\n";
  return out + "</MHAPTIC:" + tag + ">\n";
}
std::string Position(const std::string& x = "0", const std::string& y = "0",
                     const std::string& z = "0") {
  return Numbers("position", {x, y, z});
}
std::string Rotation(const std::vector<std::string>& rows = {"1", "0", "0", "0", "1", "0", "0", "0",
                                                             "1"}) {
  return Numbers("rotation", rows);
}
std::string Shape(const std::string& type, const std::string& body) {
  return "<MHAPTIC:shape type=\"" + type + "\">\n" + body + "</MHAPTIC:shape>\n";
}
std::string Object(const std::string& type, const std::string& name, const std::string& body,
                   const std::string& position = Position()) {
  return "<MHAPTIC:object type=\"" + type + "\">\n<MHAPTIC:name>" + name + "</MHAPTIC:name>\n" +
         position + Rotation() + body + "</MHAPTIC:object>\n";
}
std::string Document(const std::string& objects) {
  return "<?xml version=\"1.0\" encoding=\"ISO-8859-1\" ?>\n"
         "<!DOCTYPE MHAPTIC:scene SYSTEM \"HapticScene.dtd\">\n"
         "<MHAPTIC:scene xmlns:MHAPTIC=\"http://vrlab.epfl.ch/~reno\">\n" +
         objects + "</MHAPTIC:scene>\n";
}
std::string Sphere(const std::string& radius = "0.05") {
  return Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1"}) +
                             Numbers("sphereparams", {radius}));
}
// A valid one-object document around `body` (shapes of a dynamic "ball").
std::string Ball(const std::string& body) { return Document(Object("Dynamic", "ball", body)); }

}  // namespace

TEST_CASE("the thesis's Appendix I example loads; its y-up ground plane is z-up", "[scene][xml]") {
  const fs::path file = haptel::ShippedFile("tests/config/data/thesis_appendix_i.xml");
  const Scene s = ImportMhapticXml(file);
  REQUIRE(s.objects.size() == 1);
  const auto& ground = s.objects[0];
  REQUIRE(ground.name == "groundLiving");
  REQUIRE_FALSE(ground.dynamic);
  REQUIRE(ground.mass == 0.0);  // static: no mass, none given
  REQUIRE(ground.density == 0.0);
  // The file's (1.766357, -0, -4.121672), y up, x right, z back, in the device
  // frame: forward = −z, left = −x, up = y.
  RequireNearV(ground.position, Vector3d(4.121672, -1.766357, 0.0), 1e-12);
  RequireNearM(ground.rotation, Matrix3d::Identity(), 0.0);
  REQUIRE(ground.material == Material{0.24, 0.35, 0.2});
  REQUIRE(ground.shapes.size() == 1);
  const auto& plane = ground.shapes[0];
  REQUIRE(plane.kind == ShapeKind::kPlane);
  RequireNearV(plane.position, Vector3d::Zero(), 0.0);
  RequireNearM(plane.rotation, Matrix3d::Identity(), 0.0);
  // "0 1 0 -0.000001": y = -1e-6 in the file, z = -1e-6 in the device frame.
  RequireNearV(plane.normal, Vector3d::UnitZ(), 0.0);
  REQUIRE(plane.offset == -0.000001);
  const Vector3d world_normal = ground.rotation * plane.rotation * plane.normal;
  RequireNearV(world_normal, Vector3d::UnitZ(), 0.0);
  REQUIRE(world_normal.dot(ground.position) + plane.offset == Approx(-0.000001));
  // A plane has no bounds.
  REQUIRE_FALSE(haptel::SceneBounds(s));
  REQUIRE(haptel::OrderNodes(s).dynamic_count == 0);
}

TEST_CASE(
    "the example exactly as the thesis text prints it (split at a page break) is refused "
    "at the stray end tag",
    "[scene][xml][errors]") {
  // The text's page break closes shape, object and scene, then repeats
  // </MHAPTIC:materialparams> and goes on with the plane's parameters:
  // thesis_appendix_i.xml is the two parts joined.
  const fs::path file = haptel::ShippedFile("tests/config/data/thesis_appendix_i_as_printed.xml");
  try {
    ImportMhapticXml(file);
    FAIL("the as-printed example loaded");
  } catch (const ConfigError& e) {
    const std::string message = e.what();
    INFO(message);
    REQUIRE(message.find('\n') == std::string::npos);
    REQUIRE_THAT(message, Contains(file.string() + ":47: </MHAPTIC:materialparams>: ") &&
                              Contains("after the root element <MHAPTIC:scene> ended"));
  }
}

TEST_CASE("the conversion from the file frame is one proper rotation: y up → z up",
          "[scene][xml][frame]") {
  const Matrix3d r = haptel::MhapticToDevice();
  RequireNearM(r * r.transpose(), Matrix3d::Identity(), 0.0);
  REQUIRE(r.determinant() == 1.0);
  RequireNearV(r * Vector3d::UnitY(), Vector3d::UnitZ(), 0.0);   // up
  RequireNearV(r * -Vector3d::UnitZ(), Vector3d::UnitX(), 0.0);  // away from the operator
  RequireNearV(r * -Vector3d::UnitX(), Vector3d::UnitY(), 0.0);  // the operator's left
}

TEST_CASE("scenes of our own: two shapes, mass given and density × volume, materials, capsules",
          "[scene][xml]") {
  const std::string material = Numbers("materialparams", {"0.3", "0.6", "0.5"});
  const std::string text = Document(
      "<!-- comments anywhere -->\n" +
      Object("Dynamic", "pestle",
             Shape("Box", Position("0", "0.1", "0") + Rotation() + Numbers("mass", {"0.3"}) +
                              material + Numbers("boxparams", {"0.1", "0.2", "0.3"})) +
                 Shape("Sphere", Position("0", "-0.1", "0") + Rotation() +
                                     Numbers("density", {"500"}, "integer") + material +
                                     Numbers("sphereparams", {"0.05"}, "double")),
             Position("1", "2", "3")) +
      // mass <= 0: density × volume at PhysX's default density, 1 kg/m³.
      Object(
          "Dynamic", "feather",
          Shape("Capsule", Position() + Rotation({"0", "-1", "0", "1", "0", "0", "0", "0", "1"}) +
                               Numbers("mass", {"0"}, "integer") +
                               Numbers("capsuleparams", {"0.02", "0.1"}))) +
      // Static: no mass needed; one given is ignored.
      Object("Static",
             "K\xFC"
             "che",
             Shape("Box", Position() + Rotation() + Numbers("boxparams", {"1", "0.02", "0.5"})) +
                 Shape("Box", Position("0", "-0.5", "0") + Rotation() +
                                  Numbers("mass", {"7"}, "double") +
                                  Numbers("boxparams", {"0.02", "0.5", "0.02"}))));
  const Scene s = ImportMhapticXml(Write("own.xml", text));
  REQUIRE(s.objects.size() == 3);

  const auto& pestle = s.objects[0];
  REQUIRE(pestle.dynamic);
  RequireNearV(pestle.position, Vector3d(-3, -1, 2));  // file (1, 2, 3)
  REQUIRE(pestle.material == Material{0.3, 0.6, 0.5});
  REQUIRE(pestle.shapes.size() == 2);
  const auto& box = pestle.shapes[0];
  REQUIRE(box.kind == ShapeKind::kBox);
  RequireNearV(box.position, Vector3d(0, 0, 0.1));
  RequireNearV(box.half_extents, Vector3d(0.3, 0.1, 0.2));  // file x, y, z half sides → y, z, x
  const auto& ball = pestle.shapes[1];
  REQUIRE(ball.kind == ShapeKind::kSphere);
  REQUIRE(ball.radius == 0.05);
  RequireNearV(ball.position, Vector3d(0, 0, -0.1));
  const double ball_mass = 500.0 * 4.0 / 3.0 * kPi * std::pow(0.05, 3);
  REQUIRE(box.density == Approx(0.3 / 0.048));
  REQUIRE(ball.density == 500.0);
  REQUIRE(pestle.mass == Approx(0.3 + ball_mass));
  REQUIRE(pestle.density == 0.0);
  const auto masses = haptel::ShapeMasses(pestle);
  REQUIRE(masses.size() == 2);
  REQUIRE(masses[0] == Approx(0.3));
  REQUIRE(masses[1] == Approx(ball_mass));
  const auto mp = haptel::ComputeMassProperties(pestle);
  REQUIRE(mp.mass == Approx(0.3 + ball_mass));
  REQUIRE(mp.com.z() == Approx((0.3 * 0.1 - ball_mass * 0.1) / (0.3 + ball_mass)));

  const auto& feather = s.objects[1];
  const auto& capsule = feather.shapes[0];
  REQUIRE(capsule.kind == ShapeKind::kCapsule);
  REQUIRE(capsule.radius == 0.02);
  REQUIRE(capsule.length == 0.1);  // between the hemisphere centres
  // Along its local y in the file, turned 90° about the file's z: along −x in
  // the file, the device's +y.
  RequireNearV(capsule.rotation * Vector3d::UnitZ(), Vector3d::UnitY(), 1e-12);
  const double volume = kPi * 0.02 * 0.02 * 0.1 + 4.0 / 3.0 * kPi * std::pow(0.02, 3);
  REQUIRE(capsule.density == 1.0);
  REQUIRE(feather.mass == Approx(volume));
  const auto bounds = haptel::ShapeBounds(feather, capsule);
  REQUIRE(bounds);
  RequireNearV(bounds->max, Vector3d(0.02, 0.07, 0.02), 1e-12);

  const auto& shelf = s.objects[2];
  REQUIRE(shelf.name ==
          "K\xC3\xBC"
          "che");  // ISO-8859-1 in the file, UTF-8 here
  REQUIRE_FALSE(shelf.dynamic);
  REQUIRE(shelf.mass == 0.0);
  REQUIRE(shelf.shapes[1].density == 0.0);
  REQUIRE(shelf.material == Material{});  // none given
  RequireNearV(shelf.shapes[0].half_extents, Vector3d(0.5, 1, 0.02));

  // Node order: dynamic first.
  REQUIRE(haptel::OrderNodes(s).dynamic_count == 2);
}

TEST_CASE("malformed scenes: one line, file:line: <element>: what was expected",
          "[scene][xml][errors]") {
  SECTION("zero radius") {
    const std::string text = Ball(Sphere("0.000000"));
    RequireAt(ErrorOf("radius.xml", text), "radius.xml", LineOf(text, "0.000000"),
              "MHAPTIC:sphereparams");
    REQUIRE_THAT(ErrorOf("radius.xml", text), Contains("radius") && Contains("got 0"));
  }
  SECTION("missing rotation") {
    const std::string text = Ball(Shape(
        "Box", Position() + Numbers("mass", {"1"}) + Numbers("boxparams", {"0.1", "0.1", "0.1"})));
    const std::string message = ErrorOf("rotation.xml", text);
    RequireAt(message, "rotation.xml", LineOf(text, "type=\"Box\""), "MHAPTIC:shape");
    REQUIRE_THAT(message, Contains("expected a <MHAPTIC:rotation>"));
  }
  SECTION("a rotation that is not one") {
    const std::string text =
        Ball(Shape("Sphere", Position() + Rotation({"1", "0", "0", "0", "1", "0", "0", "0", "-1"}) +
                                 Numbers("mass", {"1"}) + Numbers("sphereparams", {"0.1"})));
    const std::string message = ErrorOf("improper.xml", text);
    REQUIRE_THAT(message, Contains("<MHAPTIC:rotation>: expected a rotation matrix"));
  }
  SECTION("truncated file") {
    const std::string whole = Ball(Sphere() + Sphere());
    // Cut after the second shape's <MHAPTIC:position>.
    const size_t second = whole.find("<MHAPTIC:shape", whole.find("<MHAPTIC:shape") + 1);
    const size_t cut = whole.find('\n', whole.find("<MHAPTIC:position>", second)) + 1;
    const std::string text = whole.substr(0, cut);
    const std::string message = ErrorOf("truncated.xml", text);
    const int last_line = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
    RequireAt(message, "truncated.xml", last_line, "MHAPTIC:position");
    REQUIRE_THAT(message, Contains("not closed") && Contains("truncated"));

    // Cut inside a tag.
    const std::string mid = whole.substr(0, cut + 8);
    REQUIRE_THAT(ErrorOf("truncated-tag.xml", mid),
                 Contains("truncated-tag.xml:") && Contains("XML syntax"));
    // Nothing at all.
    REQUIRE_THAT(ErrorOf("empty.xml", ""), Contains("empty.xml:1: <MHAPTIC:scene>: expected"));
  }
  SECTION("an element closed by another's end tag") {
    const std::string text =
        "<MHAPTIC:scene xmlns:MHAPTIC=\"x\">\n<MHAPTIC:object type=\"Static\">\n"
        "</MHAPTIC:shape>\n</MHAPTIC:scene>\n";
    RequireAt(ErrorOf("mismatch.xml", text), "mismatch.xml", 2, "MHAPTIC:object");
  }
  SECTION("unknown element and attribute") {
    const std::string text = Ball(Sphere() + "<MHAPTIC:colour>red</MHAPTIC:colour>\n");
    const std::string message = ErrorOf("element.xml", text);
    RequireAt(message, "element.xml", LineOf(text, "<MHAPTIC:colour>"), "MHAPTIC:object");
    REQUIRE_THAT(message, Contains("unexpected <MHAPTIC:colour>") && Contains("<MHAPTIC:shape>"));

    std::string attribute = Ball(Sphere());
    attribute.replace(attribute.find("type=\"Sphere\""), 13, "type=\"Sphere\" colour=\"red\"");
    const std::string m2 = ErrorOf("attribute.xml", attribute);
    RequireAt(m2, "attribute.xml", LineOf(attribute, "colour"), "MHAPTIC:shape");
    REQUIRE_THAT(m2, Contains("unknown attribute 'colour'"));
  }
  SECTION("trimesh") {
    const std::string text =
        Ball(Shape("Trimesh", Position() + Rotation() + Numbers("mass", {"1"}) +
                                  Numbers("trimeshparams", {"0"})));
    const std::string message = ErrorOf("trimesh.xml", text);
    RequireAt(message, "trimesh.xml", LineOf(text, "Trimesh"), "MHAPTIC:shape");
    REQUIRE_THAT(message, Contains("Trimesh is not supported"));
    // The parameters alone, in another shape.
    const std::string params = Ball(
        Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1"}) +
                            Numbers("sphereparams", {"0.1"}) + Numbers("trimeshparams", {"0"})));
    REQUIRE_THAT(ErrorOf("trimesh2.xml", params),
                 Contains("<MHAPTIC:trimeshparams>: triangle meshes are not supported"));
  }
  SECTION("a number that is not a number") {
    const std::string text = Ball(Sphere("abc"));
    const std::string message = ErrorOf("nan.xml", text);
    RequireAt(message, "nan.xml", LineOf(text, "abc"), "float");
    REQUIRE_THAT(message, Contains("expected a finite number, got 'abc'"));
    for (const char* bad : {"1.0x", "", "nan", "inf", "+-1", "1,5", "0x10"}) {
      INFO(bad);
      REQUIRE_THAT(ErrorOf("bad.xml", Ball(Sphere(bad))), Contains("<float>: expected"));
    }
    const std::string integer =
        Ball(Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1.5"}, "integer") +
                                 Numbers("sphereparams", {"0.1"})));
    REQUIRE_THAT(ErrorOf("integer.xml", integer),
                 Contains("<integer>: expected an integer, got '1.5'"));
  }
  SECTION("a <float> where a structure is expected, and the reverse") {
    const std::string in_object = Ball("<float>1</float>\n" + Sphere());
    const std::string message = ErrorOf("float.xml", in_object);
    RequireAt(message, "float.xml", LineOf(in_object, "<float>1</float>\n<MHAPTIC:shape"),
              "MHAPTIC:object");
    REQUIRE_THAT(message, Contains("unexpected <float>"));
    const std::string in_scene = Document("<float>1</float>\n" + Object("Static", "a", Sphere()));
    REQUIRE_THAT(ErrorOf("float2.xml", in_scene),
                 Contains("<MHAPTIC:scene>: unexpected <float> (expected <MHAPTIC:object>)"));
    const std::string in_numbers = Ball(
        Shape("Sphere", "<MHAPTIC:position>\n" + Position() + "</MHAPTIC:position>\n" + Rotation() +
                            Numbers("mass", {"1"}) + Numbers("sphereparams", {"0.1"})));
    REQUIRE_THAT(
        ErrorOf("nested.xml", in_numbers),
        Contains("<MHAPTIC:position>: expected 3 numbers") && Contains("got <MHAPTIC:position>"));
    const std::string text_numbers =
        Ball(Shape("Sphere", "<MHAPTIC:position>0 0 0</MHAPTIC:position>\n" + Rotation() +
                                 Numbers("mass", {"1"}) + Numbers("sphereparams", {"0.1"})));
    REQUIRE_THAT(ErrorOf("text.xml", text_numbers), Contains("got text '0 0 0'"));
    REQUIRE_THAT(
        ErrorOf("count.xml", Ball(Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1"}) +
                                                      Numbers("sphereparams", {"0.1", "0.2"})))),
        Contains("<MHAPTIC:sphereparams>: expected 1 number") && Contains("got 2"));
    REQUIRE_THAT(ErrorOf("loose.xml", Ball("stray words\n" + Sphere())),
                 Contains("<MHAPTIC:object>: unexpected text 'stray words'"));
  }
  SECTION("mass and density") {
    const std::string both =
        Ball(Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1"}) +
                                 Numbers("density", {"1000"}) + Numbers("sphereparams", {"0.1"})));
    const std::string message = ErrorOf("both.xml", both);
    RequireAt(message, "both.xml", LineOf(both, "<MHAPTIC:density>"), "MHAPTIC:density");
    REQUIRE_THAT(message, Contains("not both"));
    const std::string none =
        Ball(Shape("Sphere", Position() + Rotation() + Numbers("sphereparams", {"0.1"})));
    REQUIRE_THAT(ErrorOf("none.xml", none),
                 Contains("<MHAPTIC:shape>: expected a <MHAPTIC:mass> or a <MHAPTIC:density>"));
    const std::string negative =
        Ball(Shape("Sphere", Position() + Rotation() + Numbers("density", {"-5"}) +
                                 Numbers("sphereparams", {"0.1"})));
    REQUIRE_THAT(ErrorOf("negative.xml", negative),
                 Contains("<MHAPTIC:density>: expected a density (kg/m³) in"));
  }
  SECTION("a plane on a dynamic object; the parameters of another type") {
    const std::string plane =
        Ball(Shape("Plane", Position() + Rotation() + Numbers("mass", {"1"}) +
                                Numbers("planeparams", {"0", "1", "0", "0"})));
    REQUIRE_THAT(ErrorOf("plane.xml", plane),
                 Contains("<MHAPTIC:shape>: expected Sphere, Box or Capsule"));
    const std::string other = Ball(Shape("Box", Position() + Rotation() + Numbers("mass", {"1"}) +
                                                    Numbers("sphereparams", {"0.1"})));
    REQUIRE_THAT(ErrorOf("other.xml", other),
                 Contains("<MHAPTIC:sphereparams>: unexpected in a Box shape"));
    REQUIRE_THAT(
        ErrorOf("flat.xml",
                Document(Object("Static", "f",
                                Shape("Plane", Position() + Rotation() +
                                                   Numbers("planeparams", {"0", "0", "0", "1"}))))),
        Contains("<MHAPTIC:planeparams>: expected a non-zero normal"));
  }
  SECTION("two materials in one object") {
    const std::string text =
        Ball(Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1"}) +
                                 Numbers("materialparams", {"0.1", "0.5", "0.4"}) +
                                 Numbers("sphereparams", {"0.1"})) +
             Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1"}) +
                                 Numbers("materialparams", {"0.9", "0.5", "0.4"}) +
                                 Numbers("sphereparams", {"0.1"})));
    REQUIRE_THAT(ErrorOf("materials.xml", text),
                 Contains("<MHAPTIC:materialparams>: expected the same materialparams") &&
                     Contains("one material per object"));
    REQUIRE_THAT(ErrorOf("restitution.xml",
                         Ball(Shape("Sphere", Position() + Rotation() + Numbers("mass", {"1"}) +
                                                  Numbers("materialparams", {"1.5", "0.5", "0.4"}) +
                                                  Numbers("sphereparams", {"0.1"})))),
                 Contains("<MHAPTIC:materialparams>: expected a restitution in [0, 1], got 1.5"));
  }
  SECTION("the document: root, namespace, DOCTYPE, encoding, names, types") {
    REQUIRE_THAT(ErrorOf("old.xml",
                         "<MHAPTIC:scene>\n  <object type=\"Static\" name=\"floor\">\n"
                         "  </object>\n</MHAPTIC:scene>\n"),
                 Contains("old.xml:1: <MHAPTIC:scene>: expected the attribute xmlns:MHAPTIC"));
    REQUIRE_THAT(
        ErrorOf("old2.xml",
                "<MHAPTIC:scene xmlns:MHAPTIC=\"x\">\n  <object type=\"Static\">\n"
                "  </object>\n</MHAPTIC:scene>\n"),
        Contains("old2.xml:2: <MHAPTIC:scene>: unexpected <object> (expected <MHAPTIC:object>)"));
    REQUIRE_THAT(ErrorOf("root.xml", "<scene>\n</scene>\n"),
                 Contains("root.xml:1: <scene>: expected the root element <MHAPTIC:scene>"));
    REQUIRE_THAT(ErrorOf("noobject.xml", Document("")),
                 Contains("noobject.xml:3: <MHAPTIC:scene>: expected at least one"));
    std::string doctype = Ball(Sphere());
    doctype.replace(doctype.find("DOCTYPE MHAPTIC:scene"), 21, "DOCTYPE html");
    REQUIRE_THAT(ErrorOf("doctype.xml", doctype),
                 Contains("doctype.xml:2: <!DOCTYPE>: expected the document type MHAPTIC:scene"));
    std::string encoding = Ball(Sphere());
    encoding.replace(encoding.find("ISO-8859-1"), 10, "UTF-16");
    REQUIRE_THAT(ErrorOf("encoding.xml", encoding),
                 Contains("encoding.xml:1: <?xml>: expected encoding UTF-8 or ISO-8859-1"));
    // The same document saved as UTF-16, with its byte order mark or without.
    std::string utf16 = "\xFF\xFE";
    for (const char c : Ball(Sphere())) utf16 += std::string{c, '\0'};
    REQUIRE_THAT(ErrorOf("utf16.xml", utf16),
                 Contains("utf16.xml:1: <?xml>: expected a text file in UTF-8") &&
                     Contains("got UTF-16") && Contains("save it as UTF-8"));
    REQUIRE_THAT(ErrorOf("utf16-nobom.xml", utf16.substr(2)), Contains("got NUL bytes"));
    REQUIRE_THAT(ErrorOf("twice.xml", Document(Object("Static", "a", Sphere()) +
                                               Object("Dynamic", "a", Sphere()))),
                 Contains("<MHAPTIC:name>: expected a name no other object has, got 'a' again"));
    REQUIRE_THAT(ErrorOf("noname.xml", Document("<MHAPTIC:object type=\"Static\">\n" + Position() +
                                                Rotation() + Sphere() + "</MHAPTIC:object>\n")),
                 Contains("<MHAPTIC:object>: expected a <MHAPTIC:name>"));
    REQUIRE_THAT(ErrorOf("kind.xml", Document(Object("Moving", "a", Sphere()))),
                 Contains("<MHAPTIC:object>: expected type Static or Dynamic, got 'Moving'"));
    REQUIRE_THAT(
        ErrorOf("cone.xml", Ball(Shape("Cone", Position()))),
        Contains("<MHAPTIC:shape>: expected type Plane, Sphere, Box or Capsule, got 'Cone'"));
    REQUIRE_THAT(ErrorOf("noshape.xml", Ball("")),
                 Contains("<MHAPTIC:object>: expected at least one <MHAPTIC:shape>"));
    REQUIRE_THAT(ErrorOf("dup.xml", Ball(Shape("Sphere", Position() + Position() + Rotation()))),
                 Contains("<MHAPTIC:shape>: <MHAPTIC:position> given twice"));
    const std::string second = Ball(Sphere()) + "<MHAPTIC:scene xmlns:MHAPTIC=\"x\"/>\n";
    RequireAt(ErrorOf("second.xml", second), "second.xml",
              LineOf(second, "<MHAPTIC:scene xmlns:MHAPTIC=\"x\"/>"), "MHAPTIC:scene");
  }
}

TEST_CASE("a 10 MB scene loads, and one with a flaw at its end is refused at that line",
          "[scene][xml][large]") {
  // A dynamic object of two shapes, ~2.7 kB in the format's verbose style.
  const auto object = [](int i) {
    std::string name = "o";  // (not "o" + …: GCC 12 -Wrestrict false positive)
    name += std::to_string(i);
    return Object(
        "Dynamic", name,
        Shape("Box", Position("0", "0.05", "0") + Rotation() + Numbers("mass", {"0.5"}) +
                         Numbers("materialparams", {"0.4", "0.5", "0.35"}) +
                         Numbers("boxparams", {"0.05", "0.05", "0.05"})) +
            Shape("Sphere", Position("0", "-0.05", "0") + Rotation() + Numbers("density", {"800"}) +
                                Numbers("materialparams", {"0.4", "0.5", "0.35"}) +
                                Numbers("sphereparams", {"0.04"})),
        Position(std::to_string(i % 100 * 0.2), "1", std::to_string(i / 100 * 0.2)));
  };
  std::string objects;
  int count = 0;
  while (objects.size() < 10'000'000) objects += object(count++);
  const std::string text = Document(objects);
  REQUIRE(text.size() >= 10'000'000);
  const Scene s = ImportMhapticXml(Write("large.xml", text));
  REQUIRE(static_cast<int>(s.objects.size()) == count);
  REQUIRE(s.objects.back().name.substr(1) == std::to_string(count - 1));
  REQUIRE(s.objects.back().shapes.size() == 2);

  std::string flawed = text;
  const size_t last = flawed.rfind("<float>0.04</float>");
  flawed.replace(last, 19, "<float>0.04m</float>");
  const std::string message = ErrorOf("large-flawed.xml", flawed);
  RequireAt(message, "large-flawed.xml", LineOf(flawed, "0.04m"), "float");
}
