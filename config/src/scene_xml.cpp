// The thesis's haptic scene format (Appendix I), read with tinyxml2 and a
// strict element reader on top: format and rules in scene.hpp.
#include <tinyxml2.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/yaml_map.hpp"
#include "haptel/geometry/mass_properties.hpp"
#include "scene_detail.hpp"

namespace haptel {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---- the frame -----------------------------------------------------------------
//
// An MHaptic file is in the world frame of the thesis's physics engine and
// viewer. The thesis chose it to match OpenGL's camera (§4, registering the
// CyberForce trackers: "y for up/down, and x for left right ... it reminds
// the OpenGL camera orientation"): y up, x to the operator's right and, the
// frame being right-handed, z back towards the operator (OpenGL's camera looks
// down −z). The example's ground plane "0 1 0 d" (normal +y) is its floor.
// Haptel's device frame is x forward (away from the operator), y left, z up.
// For a vector v given in the file's axes:
//   forward  x_device = −z_file   (z_file points back at the operator)
//   left     y_device = −x_file   (x_file points to the operator's right)
//   up       z_device = +y_file
// These are the rows of R, v_device = R·v_file:
//       | 0  0 −1 |
//   R = |−1  0  0 |   det R = +1: a proper rotation (120° about (1, −1, −1)/√3),
//       | 0  1  0 |   so no handedness changes and no shape is mirrored.
Matrix3d MhapticToDevice() {
  Matrix3d r;
  r << 0, 0, -1,  //
      -1, 0, 0,   //
      0, 1, 0;
  return r;
}

namespace {

using config_detail::kMaxCoordinate;
using config_detail::kMaxDensity;
using config_detail::kMaxFriction;
using config_detail::kMaxMass;
using config_detail::kMaxSize;
using config_detail::kMinDensity;
using config_detail::kMinSize;
using tinyxml2::XMLAttribute;
using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;
using tinyxml2::XMLNode;

// The change of basis above applied to one object read in the file's axes: a
// re-expression, not a motion. Its pose (p, Q) becomes (R·p, R·Q·Rᵀ), and
// each shape's pose in the object likewise; then each shape's parameters are
// written in its new local axes: a plane's normal n → R·n (the offset d is a
// distance and stays); a box's half sides are permuted, |R|·h (R is a signed
// permutation); a capsule's axis, local y in the file (PhysX 2 capsules lie
// along y), becomes R·y = local z, which is Haptel's capsule axis, so
// capsules need nothing more; spheres nothing at all.
void ToDeviceFrame(SceneObject& object) {
  const Matrix3d r = MhapticToDevice();
  object.position = r * object.position;
  object.rotation = r * object.rotation * r.transpose();
  for (SceneShape& s : object.shapes) {
    s.position = r * s.position;
    s.rotation = r * s.rotation * r.transpose();
    if (s.kind == ShapeKind::kPlane) s.normal = r * s.normal;
    if (s.kind == ShapeKind::kBox) s.half_extents = r.cwiseAbs() * s.half_extents;
    for (Vector3d& p : s.points) p = r * p;
  }
}

constexpr const char* kScene = "MHAPTIC:scene";
constexpr const char* kObject = "MHAPTIC:object";
constexpr const char* kShape = "MHAPTIC:shape";
constexpr const char* kName = "MHAPTIC:name";
constexpr const char* kPosition = "MHAPTIC:position";
constexpr const char* kRotation = "MHAPTIC:rotation";
constexpr const char* kMass = "MHAPTIC:mass";
constexpr const char* kDensity = "MHAPTIC:density";
constexpr const char* kMaterial = "MHAPTIC:materialparams";
constexpr const char* kPlane = "MHAPTIC:planeparams";
constexpr const char* kSphere = "MHAPTIC:sphereparams";
constexpr const char* kBox = "MHAPTIC:boxparams";
constexpr const char* kCapsule = "MHAPTIC:capsuleparams";
constexpr const char* kTrimesh = "MHAPTIC:trimeshparams";
// Appended to the text: the last node of every complete parse. tinyxml2 stops
// silently at an end tag outside the root; a missing sentinel tells.
constexpr const char* kSentinel = "haptel-end-of-file";

// Text for a one-line message: blanks collapsed, at most 40 characters.
std::string Shown(std::string_view text) {
  std::string out;
  for (char c : text) {
    const bool blank = c == ' ' || c == '\t' || c == '\r' || c == '\n';
    if (blank) {
      if (!out.empty() && out.back() != ' ') out += ' ';
    } else {
      out += c;
    }
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  if (out.size() > 40) out = out.substr(0, 37) + "...";
  return out;
}

std::string_view Trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::string Format(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string Tag(const char* name) { return std::string("<") + name + ">"; }

bool Is(const XMLElement& e, const char* name) { return std::string_view(e.Name()) == name; }

// A number read from a <float>, <double> or <integer> element.
struct Number {
  double value = 0.0;
  int line = 0;
};

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(int line, std::string_view element, const std::string& what) const {
    throw ConfigError(file_ + ":" + std::to_string(std::max(line, 1)) + ": <" +
                      std::string(element) + ">: " + what);
  }
  [[noreturn]] void Fail(const XMLElement& e, const std::string& what) const {
    Fail(e.GetLineNum(), e.Name(), what);
  }

  // Rejects attributes other than `allowed`.
  void Attributes(const XMLElement& e, std::initializer_list<const char*> allowed) const {
    for (const XMLAttribute* a = e.FirstAttribute(); a != nullptr; a = a->Next()) {
      const bool known = std::any_of(allowed.begin(), allowed.end(), [&](const char* name) {
        return std::string_view(a->Name()) == name;
      });
      if (known) continue;
      std::string expected;
      for (const char* name : allowed)
        expected += (expected.empty() ? "" : ", ") + std::string(name);
      Fail(a->GetLineNum(), e.Name(),
           "unknown attribute '" + std::string(a->Name()) + "' (expected " +
               (expected.empty() ? std::string("none") : expected) + ")");
    }
  }

  // The element children of a structure element: comments are skipped;
  // text, declarations and elements not in `allowed` are errors; each name at
  // most once except `repeatable`.
  std::vector<const XMLElement*> Children(const XMLElement& e,
                                          std::initializer_list<const char*> allowed,
                                          const char* repeatable = nullptr) const {
    std::vector<const XMLElement*> out;
    for (const XMLNode* n = e.FirstChild(); n != nullptr; n = n->NextSibling()) {
      if (n->ToComment() != nullptr) continue;
      if (n->ToText() != nullptr) {
        if (!Trim(n->Value()).empty()) {
          Fail(n->GetLineNum(), e.Name(), "unexpected text '" + Shown(n->Value()) + "'");
        }
        continue;
      }
      const XMLElement* c = n->ToElement();
      if (c == nullptr) Fail(n->GetLineNum(), e.Name(), "unexpected <!" + Shown(n->Value()) + ">");
      const bool known = std::any_of(allowed.begin(), allowed.end(),
                                     [&](const char* name) { return Is(*c, name); });
      if (!known) {
        std::string expected;
        for (const char* name : allowed) expected += (expected.empty() ? "" : ", ") + Tag(name);
        Fail(c->GetLineNum(), e.Name(),
             "unexpected " + Tag(c->Name()) + " (expected " + expected + ")");
      }
      if (repeatable == nullptr || !Is(*c, repeatable)) {
        for (const XMLElement* seen : out) {
          if (Is(*seen, c->Name())) {
            Fail(c->GetLineNum(), e.Name(),
                 Tag(c->Name()) + " given twice (first at line " +
                     std::to_string(seen->GetLineNum()) + ")");
          }
        }
      }
      out.push_back(c);
    }
    return out;
  }

  static const XMLElement* Find(const std::vector<const XMLElement*>& children, const char* name) {
    for (const XMLElement* c : children) {
      if (Is(*c, name)) return c;
    }
    return nullptr;
  }

  const XMLElement& Require(const XMLElement& parent,
                            const std::vector<const XMLElement*>& children, const char* name,
                            const std::string& meaning) const {
    const XMLElement* c = Find(children, name);
    if (c == nullptr) Fail(parent, "expected a " + Tag(name) + " (" + meaning + ")");
    return *c;
  }

  // The text of an element that holds only text (comments allowed).
  std::string Text(const XMLElement& e) const {
    Attributes(e, {});
    std::string out;
    for (const XMLNode* n = e.FirstChild(); n != nullptr; n = n->NextSibling()) {
      if (n->ToComment() != nullptr) continue;
      if (n->ToText() == nullptr) {
        Fail(e, "expected text only, got " +
                    (n->ToElement() != nullptr ? Tag(n->Value()) : "<!" + Shown(n->Value()) + ">"));
      }
      out += n->Value();
    }
    return std::string(Trim(out));
  }

  // Exactly `count` number elements (<float>, <double>, <integer>) and
  // nothing else; `meaning` says what they are.
  std::vector<Number> Numbers(const XMLElement& e, size_t count, const std::string& meaning) const {
    Attributes(e, {});
    const auto expected = [&] {  // (built only for a message: a large scene reads many)
      return std::to_string(count) + (count == 1 ? " number" : " numbers") + " (" + meaning +
             ") as <float>, <double> or <integer>";
    };
    std::vector<Number> out;
    out.reserve(count);
    for (const XMLNode* n = e.FirstChild(); n != nullptr; n = n->NextSibling()) {
      if (n->ToComment() != nullptr) continue;
      if (n->ToText() != nullptr) {
        if (!Trim(n->Value()).empty()) {
          Fail(n->GetLineNum(), e.Name(),
               "expected " + expected() + ", got text '" + Shown(n->Value()) + "'");
        }
        continue;
      }
      const XMLElement* c = n->ToElement();
      if (c == nullptr || !(Is(*c, "float") || Is(*c, "double") || Is(*c, "integer"))) {
        Fail(n->GetLineNum(), e.Name(),
             "expected " + expected() + ", got " +
                 (c != nullptr ? Tag(c->Name()) : "<!" + Shown(n->Value()) + ">"));
      }
      out.push_back(ParseNumber(*c));
    }
    if (out.size() != count) {
      Fail(e, "expected " + expected() + ", got " + std::to_string(out.size()));
    }
    return out;
  }

  double InRange(const Number& n, const char* element, double min, double max,
                 const std::string& meaning) const {
    if (!(n.value >= min && n.value <= max)) {
      Fail(n.line, element,
           "expected " + meaning + " in [" + Format(min) + ", " + Format(max) + "], got " +
               Format(n.value));
    }
    return n.value;
  }

  Vector3d Vector(const XMLElement& e, const std::string& meaning, double min, double max) const {
    const auto n = Numbers(e, 3, meaning);
    Vector3d out;
    for (int i = 0; i < 3; ++i)
      out[i] = InRange(n[static_cast<size_t>(i)], e.Name(), min, max, meaning);
    return out;
  }

  Matrix3d Rotation(const XMLElement& e) const {
    std::vector<double> rows;
    for (const Number& n : Numbers(e, 9, "a 3×3 rotation matrix, row by row"))
      rows.push_back(n.value);
    Matrix3d out;
    const std::string problem = config_detail::ToRotation(rows, out);
    if (!problem.empty()) Fail(e, "expected " + problem);
    return out;
  }

 private:
  Number ParseNumber(const XMLElement& e) const {
    const std::string text = Text(e);
    const bool integer = Is(e, "integer");
    const char* first = text.data() + (!text.empty() && text[0] == '+' ? 1 : 0);
    const char* last = text.data() + text.size();
    double value = 0.0;
    bool ok = false;
    if (integer) {
      long long i = 0;
      const auto [end, ec] = std::from_chars(first, last, i);
      ok = ec == std::errc() && end == last && first != last;
      value = static_cast<double>(i);
    } else {
      const auto [end, ec] = std::from_chars(first, last, value);
      ok = ec == std::errc() && end == last && first != last && std::isfinite(value);
    }
    if (!ok || (first != text.data() && (first == last || *first == '-' || *first == '+'))) {
      Fail(e, std::string("expected ") + (integer ? "an integer" : "a finite number") + ", got '" +
                  Shown(text) + "'");
    }
    return {value, e.GetLineNum()};
  }

  std::string file_;
};

// One shape as the file gives it (file axes), with what the object needs.
struct XmlShape {
  SceneShape shape;
  std::optional<Material> material;
  int material_line = 0;
  double mass = 0.0;  ///< kg, dynamic objects: the shape's mass (PhysX rule applied)
};

const char* TypeParams(std::string_view type) {
  if (type == "Plane") return kPlane;
  if (type == "Sphere") return kSphere;
  if (type == "Box") return kBox;
  if (type == "Capsule") return kCapsule;
  return kTrimesh;
}

XmlShape ReadShape(const Reader& r, const XMLElement& e, bool dynamic) {
  r.Attributes(e, {"type"});
  const XMLAttribute* type_attribute = e.FindAttribute("type");
  if (type_attribute == nullptr) {
    r.Fail(e, "expected a type attribute: Plane, Sphere, Box or Capsule");
  }
  const std::string_view type = type_attribute->Value();
  const int type_line = type_attribute->GetLineNum();
  if (type == "Trimesh") {
    r.Fail(type_line, e.Name(),
           "type Trimesh is not supported (nor was it in the thesis's own loader): approximate "
           "the object by planes, spheres, boxes and capsules");
  }
  if (type != "Plane" && type != "Sphere" && type != "Box" && type != "Capsule") {
    r.Fail(type_line, e.Name(),
           "expected type Plane, Sphere, Box or Capsule, got '" + Shown(type) + "'");
  }
  if (type == "Plane" && dynamic) {
    r.Fail(type_line, e.Name(),
           "expected Sphere, Box or Capsule: a Plane belongs on a Static object only");
  }
  const auto children = r.Children(e, {kPosition, kRotation, kDensity, kMass, kMaterial, kPlane,
                                       kSphere, kBox, kCapsule, kTrimesh});
  XmlShape out;
  SceneShape& s = out.shape;
  s.position = r.Vector(r.Require(e, children, kPosition, "the shape's x y z in the object, m"),
                        "x y z, m", -kMaxCoordinate, kMaxCoordinate);
  s.rotation = r.Rotation(r.Require(e, children, kRotation, "3×3 numbers, row by row"));

  // Parameters: exactly the ones of the type.
  const char* wanted = TypeParams(type);
  for (const char* params : {kPlane, kSphere, kBox, kCapsule, kTrimesh}) {
    const XMLElement* c = Reader::Find(children, params);
    if (c == nullptr || params == wanted) continue;
    if (params == kTrimesh) r.Fail(*c, "triangle meshes are not supported");
    r.Fail(*c, "unexpected in a " + std::string(type) + " shape (its parameters are " +
                   Tag(wanted) + ")");
  }
  if (type == "Plane") {
    const XMLElement& p = r.Require(e, children, kPlane, "a b c d of the plane ax + by + cz = d");
    const auto n = r.Numbers(p, 4, "a b c d of ax + by + cz = d");
    for (const Number& v : n) r.InRange(v, kPlane, -kMaxCoordinate, kMaxCoordinate, "a b c d");
    const Vector3d normal(n[0].value, n[1].value, n[2].value);
    if (normal.norm() < 1e-9) r.Fail(p, "expected a non-zero normal (a, b, c)");
    s.kind = ShapeKind::kPlane;
    s.normal = normal.normalized();
    s.offset = n[3].value / normal.norm();
  } else if (type == "Sphere") {
    const XMLElement& p = r.Require(e, children, kSphere, "the radius, m");
    s.kind = ShapeKind::kSphere;
    s.radius =
        r.InRange(r.Numbers(p, 1, "radius, m")[0], kSphere, kMinSize, kMaxSize, "a radius (m)");
  } else if (type == "Box") {
    const XMLElement& p = r.Require(e, children, kBox, "half the sides: 3 numbers, m");
    s.kind = ShapeKind::kBox;
    s.half_extents = r.Vector(p, "half the sides, m", kMinSize, kMaxSize);
  } else {
    const XMLElement& p = r.Require(e, children, kCapsule, "radius and length, m");
    const auto n = r.Numbers(p, 2, "radius and length, m");
    s.kind = ShapeKind::kCapsule;
    s.radius = r.InRange(n[0], kCapsule, kMinSize, kMaxSize, "a radius (m)");
    s.length =
        r.InRange(n[1], kCapsule, 0.0, kMaxSize, "a length (m, between the hemisphere centres)");
  }

  if (const XMLElement* m = Reader::Find(children, kMaterial)) {
    const auto n = r.Numbers(*m, 3, "restitution, static friction, dynamic friction");
    out.material = Material{r.InRange(n[0], kMaterial, 0.0, 1.0, "a restitution"),
                            r.InRange(n[1], kMaterial, 0.0, kMaxFriction, "a static friction"),
                            r.InRange(n[2], kMaterial, 0.0, kMaxFriction, "a dynamic friction")};
    out.material_line = m->GetLineNum();
  }

  // Mass or density (PhysX 2's NxShapeDesc): one of them; read everywhere,
  // used on dynamic objects only.
  const XMLElement* mass = Reader::Find(children, kMass);
  const XMLElement* density = Reader::Find(children, kDensity);
  if (mass != nullptr && density != nullptr) {
    const XMLElement& second = mass->GetLineNum() > density->GetLineNum() ? *mass : *density;
    r.Fail(second, "expected either <MHAPTIC:mass> or <MHAPTIC:density>, not both");
  }
  const std::optional<Number> mass_value =
      mass != nullptr ? std::optional(r.Numbers(*mass, 1, "mass, kg")[0]) : std::nullopt;
  const std::optional<Number> density_value =
      density != nullptr ? std::optional(r.Numbers(*density, 1, "density, kg/m³")[0])
                         : std::nullopt;
  if (dynamic) {
    if (!mass_value && !density_value) {
      r.Fail(e, "expected a <MHAPTIC:mass> or a <MHAPTIC:density> (a shape of a Dynamic object)");
    }
    const double volume = ShapeMassProperties(s, 1.0).volume;
    if (mass_value && mass_value->value > 0.0) {
      out.mass = r.InRange(*mass_value, kMass, 0.0, kMaxMass, "a mass (kg)");
      s.density = out.mass / volume;
    } else {
      // mass <= 0: density × volume, the density being PhysX's default 1 kg/m³
      // when the file gives a mass rather than a density.
      s.density = density_value ? r.InRange(*density_value, kDensity, kMinDensity, kMaxDensity,
                                            "a density (kg/m³)")
                                : 1.0;
      out.mass = s.density * volume;
    }
  }
  return out;
}

SceneObject ReadObject(const Reader& r, const XMLElement& e, std::set<std::string>& names) {
  r.Attributes(e, {"type"});
  const XMLAttribute* type = e.FindAttribute("type");
  if (type == nullptr) r.Fail(e, "expected a type attribute: Static or Dynamic");
  const std::string_view type_value = type->Value();
  if (type_value != "Static" && type_value != "Dynamic") {
    r.Fail(type->GetLineNum(), e.Name(),
           "expected type Static or Dynamic, got '" + Shown(type_value) + "'");
  }
  SceneObject object;
  object.dynamic = type_value == "Dynamic";
  const auto children = r.Children(e, {kName, kPosition, kRotation, kShape}, kShape);

  const XMLElement& name = r.Require(e, children, kName, "the object's name");
  object.name = r.Text(name);
  if (object.name.empty()) r.Fail(name, "expected a name, got none");
  if (!names.insert(object.name).second) {
    r.Fail(name, "expected a name no other object has, got '" + Shown(object.name) + "' again");
  }
  object.position = r.Vector(r.Require(e, children, kPosition, "the object's x y z, m"), "x y z, m",
                             -kMaxCoordinate, kMaxCoordinate);
  object.rotation = r.Rotation(r.Require(e, children, kRotation, "3×3 numbers, row by row"));

  std::optional<Material> material;
  int material_line = 0;
  bool first = true;
  for (const XMLElement* c : children) {
    if (!Is(*c, kShape)) continue;
    XmlShape shape = ReadShape(r, *c, object.dynamic);
    // One material per object in Haptel: the shapes must agree.
    const Material given = shape.material.value_or(Material{});
    if (first) {
      material = given;
      material_line = shape.material ? shape.material_line : c->GetLineNum();
    } else if (!(given == *material)) {
      r.Fail(shape.material ? shape.material_line : c->GetLineNum(),
             shape.material ? kMaterial : kShape,
             "expected the same materialparams as the object's other shapes (line " +
                 std::to_string(material_line) + "): Haptel has one material per object");
    }
    first = false;
    object.mass += shape.mass;
    object.shapes.push_back(std::move(shape.shape));
  }
  if (object.shapes.empty()) r.Fail(e, "expected at least one <MHAPTIC:shape>");
  object.material = material.value_or(Material{});
  ToDeviceFrame(object);
  if (object.dynamic) {
    const std::string problem = config_detail::CheckMassProperties(object);
    if (!problem.empty()) r.Fail(e, "expected " + problem);
  }
  return object;
}

// ---- the text ---------------------------------------------------------------------

// The file's bytes, with room for the sentinel.
std::string ReadFile(const std::filesystem::path& file) {
  config_detail::CheckRegularFile(file, "an XML scene file");
  std::ifstream in(file, std::ios::binary);
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (!in || ec) throw ConfigError(file.string() + ": cannot open the file");
  std::string out;
  out.reserve(size + 32);
  out.resize(size);
  in.read(out.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) {
    throw ConfigError(file.string() + ": cannot read the file");
  }
  return out;
}

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The encoding the <?xml …?> declaration names ("" when none).
std::string DeclaredEncoding(const std::string& text) {
  const size_t start = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  if (text.compare(start, 5, "<?xml") != 0) return "";
  const size_t end = text.find("?>", start);
  const std::string_view decl = std::string_view(text).substr(start, end - start);
  const size_t key = decl.find("encoding");
  if (key == std::string_view::npos) return "";
  const size_t quote = decl.find_first_of("\"'", key);
  if (quote == std::string_view::npos) return "";
  const size_t close = decl.find(decl[quote], quote + 1);
  if (close == std::string_view::npos) return "";
  return std::string(decl.substr(quote + 1, close - quote - 1));
}

std::string Latin1ToUtf8(const std::string& text) {
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  for (char c : text) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x80) {
      out += c;
    } else {
      out += static_cast<char>(0xC0 | (b >> 6));
      out += static_cast<char>(0x80 | (b & 0x3F));
    }
  }
  return out;
}

// After a parse that stopped early: the line and name of the first tag
// outside the root element. The text is well-formed up to there (tinyxml2
// checked it), so a tag scanner that skips comments, CDATA, declarations and
// quoted attribute values finds it.
std::pair<int, std::string> FirstTagAfterRoot(const std::string& text) {
  int line = 1;
  int depth = 0;
  bool root_closed = false;
  size_t i = 0;
  const auto advance_to = [&](size_t end) {
    line += static_cast<int>(std::count(text.begin() + static_cast<std::ptrdiff_t>(i),
                                        text.begin() + static_cast<std::ptrdiff_t>(end), '\n'));
    i = end;
  };
  const auto name_at = [&](size_t from) {
    size_t j = from;
    while (j < text.size() && std::string_view(" \t\r\n/>").find(text[j]) == std::string_view::npos)
      ++j;
    return text.substr(from, j - from);
  };
  const auto skip = [&](std::string_view end) {
    const size_t found = text.find(end, i);
    advance_to(found == std::string::npos ? text.size() : found + end.size());
  };
  while (i < text.size()) {
    const size_t lt = text.find('<', i);
    if (lt == std::string::npos) break;
    advance_to(lt);
    if (text.compare(i, 4, "<!--") == 0) {
      skip("-->");
    } else if (text.compare(i, 9, "<![CDATA[") == 0) {
      skip("]]>");
    } else if (text.compare(i, 2, "<?") == 0) {
      skip("?>");
    } else if (text.compare(i, 2, "<!") == 0) {
      skip(">");
    } else if (text.compare(i, 2, "</") == 0) {
      if (depth == 0) return {line, "/" + name_at(i + 2)};
      skip(">");
      if (--depth == 0) root_closed = true;
    } else {
      if (root_closed) return {line, name_at(i + 1)};
      const std::string name = name_at(i + 1);
      char quote = 0;
      size_t j = i + 1;
      for (; j < text.size(); ++j) {
        if (quote != 0) {
          if (text[j] == quote) quote = 0;
        } else if (text[j] == '"' || text[j] == '\'') {
          quote = text[j];
        } else if (text[j] == '>') {
          break;
        }
      }
      const bool empty = j > 0 && j < text.size() && text[j - 1] == '/';
      advance_to(std::min(j + 1, text.size()));
      if (!empty) {
        ++depth;
      } else if (depth == 0) {
        root_closed = true;
      }
    }
  }
  return {line, ""};
}

// The name of the last start tag on `line` not closed on it (the element
// tinyxml2 found unclosed at the end of the file), or "".
std::string OpenTagOnLine(const std::string& text, int line) {
  size_t begin = 0;
  for (int l = 1; l < line && begin != std::string::npos; ++l) {
    begin = text.find('\n', begin);
    if (begin != std::string::npos) ++begin;
  }
  if (begin == std::string::npos) return "";
  const std::string_view row = std::string_view(text).substr(begin, text.find('\n', begin) - begin);
  std::vector<std::string> open;
  for (size_t i = row.find('<'); i != std::string_view::npos; i = row.find('<', i + 1)) {
    if (i + 1 >= row.size() || row[i + 1] == '!' || row[i + 1] == '?') continue;
    const bool closing = row[i + 1] == '/';
    size_t j = i + (closing ? 2 : 1);
    const size_t name_begin = j;
    while (j < row.size() && std::string_view(" \t\r/>").find(row[j]) == std::string_view::npos)
      ++j;
    const std::string name(row.substr(name_begin, j - name_begin));
    const size_t gt = row.find('>', j);
    if (closing) {
      if (!open.empty() && open.back() == name) open.pop_back();
    } else if (gt == std::string_view::npos || row[gt - 1] != '/') {
      open.push_back(name);
    }
  }
  return open.empty() ? "" : open.back();
}

// tinyxml2's "Error=… Line number=N: XMLElement name=X" → X, or "".
std::string ErrorElement(const XMLDocument& doc) {
  const std::string_view str = doc.ErrorStr();
  const size_t at = str.find("name=");
  return at == std::string_view::npos ? "" : std::string(Trim(str.substr(at + 5)));
}

[[noreturn]] void SyntaxError(const Reader& r, const XMLDocument& doc, const std::string& text) {
  const int line = std::max(doc.ErrorLineNum(), 1);
  std::string element = ErrorElement(doc);
  std::string what;
  switch (doc.ErrorID()) {
    case tinyxml2::XML_ERROR_PARSING:
      what = "not closed: the file ends first (truncated?)";
      break;
    case tinyxml2::XML_ERROR_MISMATCHED_ELEMENT:
      what = "closed by the end tag of another element (expected </" + element + ">)";
      break;
    case tinyxml2::XML_ERROR_PARSING_ELEMENT:
      what = "malformed tag (expected <name attribute=\"value\"…> or </name>)";
      break;
    case tinyxml2::XML_ERROR_PARSING_ATTRIBUTE:
      what = "malformed attribute (expected name=\"value\")";
      break;
    case tinyxml2::XML_ERROR_PARSING_TEXT:
      what = "malformed text (a stray '<', or text outside the root element)";
      break;
    case tinyxml2::XML_ERROR_PARSING_CDATA:
      what = "unterminated CDATA section";
      break;
    case tinyxml2::XML_ERROR_PARSING_COMMENT:
      what = "unterminated comment (expected -->)";
      break;
    case tinyxml2::XML_ERROR_PARSING_DECLARATION:
      what = "malformed <?xml ?> declaration, or one that is not at the start";
      break;
    case tinyxml2::XML_ERROR_PARSING_UNKNOWN:
      what = "malformed <!...> declaration";
      break;
    case tinyxml2::XML_ELEMENT_DEPTH_EXCEEDED:
      what = "elements nested too deep";
      break;
    default:
      what = std::string("XML error ") + doc.ErrorName();
      break;
  }
  if (element.empty()) element = OpenTagOnLine(text, line);
  r.Fail(line, element.empty() ? std::string_view("?") : std::string_view(element),
         "XML syntax: " + what);
}

}  // namespace

Scene ImportMhapticXml(const std::filesystem::path& file) {
  const Reader r(file.string());
  std::string text = ReadFile(file);
  // UTF-16 (or UTF-32) text: every other byte is NUL, and the parser's own
  // message would be one stray character ("file:1: <").
  const bool bom16 = text.size() >= 2 && ((text[0] == '\xFF' && text[1] == '\xFE') ||
                                          (text[0] == '\xFE' && text[1] == '\xFF'));
  if (bom16 || text.find('\0') != std::string::npos) {
    r.Fail(
        1, "?xml",
        std::string("expected a text file in UTF-8 or ISO-8859-1, got ") +
            (bom16 ? "UTF-16 (its byte order mark)" : "NUL bytes (UTF-16 or UTF-32, or not text)") +
            "; save it as UTF-8");
  }
  const std::string encoding = Lower(DeclaredEncoding(text));
  const bool latin1 = encoding == "iso-8859-1" || encoding == "latin1" ||
                      encoding == "iso_8859-1" || encoding == "latin-1";
  if (latin1 && std::any_of(text.begin(), text.end(), [](char c) { return (c & 0x80) != 0; })) {
    text = Latin1ToUtf8(text);
  } else if (!latin1 && !encoding.empty() && encoding != "utf-8" && encoding != "us-ascii" &&
             encoding != "ascii") {
    r.Fail(1, "?xml",
           "expected encoding UTF-8 or ISO-8859-1, got '" + DeclaredEncoding(text) + "'");
  }

  XMLDocument doc;
  const size_t length = text.size();
  text += "<";
  text += kSentinel;
  text += "/>";
  doc.Parse(text.data(), text.size());
  text.resize(length);
  if (doc.Error()) SyntaxError(r, doc, text);

  // The document: declaration, comments, at most one DOCTYPE, one root
  // element, and the sentinel last.
  const XMLElement* root = nullptr;
  bool doctype = false;
  bool complete = false;
  for (const XMLNode* n = doc.FirstChild(); n != nullptr; n = n->NextSibling()) {
    if (n->ToComment() != nullptr || n->ToDeclaration() != nullptr) continue;
    if (const auto* unknown = n->ToUnknown()) {
      const std::string_view value = Trim(unknown->Value());
      if (value.rfind("DOCTYPE", 0) != 0) {
        r.Fail(n->GetLineNum(), "!" + Shown(value).substr(0, 12),
               "unexpected declaration (only <!DOCTYPE MHAPTIC:scene …> is allowed)");
      }
      if (doctype || root != nullptr) {
        r.Fail(n->GetLineNum(), "!DOCTYPE", "expected one DOCTYPE, before the root element");
      }
      std::istringstream words{std::string(value)};
      std::string keyword, name;
      words >> keyword >> name;
      if (name != kScene) {
        r.Fail(n->GetLineNum(), "!DOCTYPE",
               "expected the document type MHAPTIC:scene, got '" + Shown(name) + "'");
      }
      doctype = true;
      continue;
    }
    const XMLElement* e = n->ToElement();
    if (e == nullptr) continue;  // (text at the top level is a tinyxml2 error)
    if (Is(*e, kSentinel) && n->NextSibling() == nullptr) {
      complete = true;
      break;
    }
    if (root != nullptr) {
      r.Fail(*e, "unexpected second root element (the root <" + std::string(root->Name()) +
                     "> is at line " + std::to_string(root->GetLineNum()) + ")");
    }
    root = e;
  }
  if (!complete) {
    const auto [line, name] = FirstTagAfterRoot(text);
    r.Fail(line, name.empty() ? std::string_view("?") : std::string_view(name),
           std::string("unexpected after the root element <") +
               (root != nullptr ? root->Name() : kScene) +
               "> ended (expected the end of the file)");
  }
  if (root == nullptr) r.Fail(1, kScene, "expected the root element <MHAPTIC:scene>, found none");
  if (!Is(*root, kScene)) {
    r.Fail(*root, "expected the root element <MHAPTIC:scene> (the thesis's MHaptic scene format)");
  }
  r.Attributes(*root, {"xmlns:MHAPTIC"});
  if (root->FindAttribute("xmlns:MHAPTIC") == nullptr) {
    r.Fail(*root,
           "expected the attribute xmlns:MHAPTIC (the namespace, e.g. "
           "\"http://vrlab.epfl.ch/~reno\")");
  }
  const auto objects = r.Children(*root, {kObject}, kObject);
  if (objects.empty()) r.Fail(*root, "expected at least one <MHAPTIC:object>");

  Scene scene;
  scene.file = file;
  scene.objects.reserve(objects.size());
  std::set<std::string> names;
  for (const XMLElement* o : objects) scene.objects.push_back(ReadObject(r, *o, names));
  return scene;
}

}  // namespace haptel
