#include "haptel/config/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/geometry/mass_properties.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---- materials -----------------------------------------------------------
//
// Friction: dry, clean surfaces of the material against itself, from
// Serway & Jewett, "Physics for Scientists and Engineers", Table 5.1
// (steel, glass, wood, ice; aluminium) and the Engineering ToolBox table
// "Friction and Friction Coefficients for some Common Materials" (brick).
// Marble and carpet have no standard table entry: their values are estimates
// from floor slip-resistance measurements (dry polished stone ≈ 0.5, dry
// carpet ≈ 0.6–0.8). Clean aluminium on aluminium galls (μs 1.05–1.35 in the
// tables), which handled objects do not: the aluminium-on-steel pair is used.
// Restitution: approximate low-speed (≈ 1 m/s) values of common drop tests;
// it depends strongly on speed and geometry, so treat it as a feel setting.
// All values approximate.
namespace {
struct Preset {
  const char* name;
  Material material;
};
constexpr Preset kPresets[] = {
    {"wood", {0.5, 0.4, 0.2}},         // wood/wood μs 0.25–0.5, μk 0.2
    {"marble", {0.6, 0.5, 0.4}},       // estimate (polished stone)
    {"brick", {0.3, 0.6, 0.5}},        // brick/masonry μs ≈ 0.6; μk estimate
    {"steel", {0.6, 0.74, 0.57}},      // mild steel/steel
    {"aluminium", {0.5, 0.61, 0.47}},  // aluminium/steel
    {"glass", {0.7, 0.94, 0.4}},       // glass/glass
    {"carpet", {0.1, 0.8, 0.6}},       // estimate (slip-resistance tests)
    {"ice", {0.3, 0.1, 0.03}},         // ice/ice at 0 °C
};
}  // namespace

std::optional<Material> MaterialPreset(const std::string& name) {
  for (const Preset& p : kPresets) {
    if (name == p.name) return p.material;
  }
  return std::nullopt;
}

const std::vector<std::string>& MaterialPresetNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Preset& p : kPresets) out.emplace_back(p.name);
    return out;
  }();
  return names;
}

Material CombineMaterials(const Material& a, const Material& b) {
  return {0.5 * (a.restitution + b.restitution), 0.5 * (a.static_friction + b.static_friction),
          0.5 * (a.dynamic_friction + b.dynamic_friction)};
}

const char* ShapeKindName(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kBox:
      return "box";
    case ShapeKind::kSphere:
      return "sphere";
    case ShapeKind::kCapsule:
      return "capsule";
    case ShapeKind::kPlane:
      return "plane";
    case ShapeKind::kConvex:
      return "convex";
  }
  return "?";
}

SceneNodeOrder OrderNodes(const Scene& scene) {
  SceneNodeOrder order;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (scene.objects[i].dynamic) order.objects.push_back(i);
  }
  order.dynamic_count = order.objects.size();
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (!scene.objects[i].dynamic) order.objects.push_back(i);
  }
  return order;
}

// ---- shared validation ------------------------------------------------------

namespace {

constexpr double kMaxCoordinate = 1e4;                   // m
constexpr double kMinSize = 1e-6;                        // m
constexpr double kMaxSize = 1e3;                         // m
constexpr double kMinMass = 1e-6, kMaxMass = 1e5;        // kg
constexpr double kMinDensity = 1e-3, kMaxDensity = 1e5;  // kg/m³
constexpr double kMaxFriction = 2.0;
constexpr size_t kMaxConvexPoints = 64;
const char* const kPresetList = "wood, marble, brick, steel, aluminium, glass, carpet, ice";

// A 3×3 matrix, row by row, that is a rotation within rounding of the file's
// digits; returned re-orthonormalised. Empty message when fine.
std::string ToRotation(const std::vector<double>& rows, Matrix3d& out) {
  Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = rows[static_cast<size_t>(3 * r + c)];
  }
  if ((m * m.transpose() - Matrix3d::Identity()).cwiseAbs().maxCoeff() > 2e-3 ||
      m.determinant() <= 0.0) {
    return "a rotation matrix (orthonormal rows, determinant +1; 9 numbers row by row)";
  }
  const Eigen::JacobiSVD<Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  out = svd.matrixU() * svd.matrixV().transpose();
  return "";
}

std::string QuaternionToRotation(const std::vector<double>& wxyz, Matrix3d& out) {
  Eigen::Quaterniond q(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
  if (std::abs(q.norm() - 1.0) > 1e-3) return "a unit quaternion [w, x, y, z]";
  out = q.normalized().toRotationMatrix();
  return "";
}

// Why a dynamic object cannot be a rigid body, or "".
std::string CheckMassProperties(const SceneObject& object) {
  try {
    const MassProperties p = ComputeMassProperties(object);
    if (!(p.mass > 0.0) || !p.inertia.allFinite() ||
        !(Diagonalize(p.inertia).moments.minCoeff() > 0.0)) {
      return "shapes giving a positive mass and inertia";
    }
  } catch (const std::invalid_argument& e) {
    return std::string("shapes with valid mass properties (") + e.what() + ")";
  }
  return "";
}

// ---- YAML ------------------------------------------------------------------

Matrix3d ReadRotation(YamlMap& map) {
  Matrix3d out = Matrix3d::Identity();
  const bool has_matrix = map.Has("rotation");
  const bool has_quaternion = map.Has("quaternion_wxyz");
  if (has_matrix && has_quaternion)
    map.Fail("quaternion_wxyz", "either 'rotation' or 'quaternion_wxyz', not both");
  if (has_matrix) {
    const std::string problem = ToRotation(map.Numbers("rotation", 9, -1.01, 1.01), out);
    if (!problem.empty()) map.Fail("rotation", problem);
  } else if (has_quaternion) {
    const std::string problem =
        QuaternionToRotation(map.Numbers("quaternion_wxyz", 4, -1.01, 1.01), out);
    if (!problem.empty()) map.Fail("quaternion_wxyz", problem);
  }
  return out;
}

Vector3d ToVector(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
Vector3d ToVector(const std::vector<double>& a) { return {a[0], a[1], a[2]}; }

// `points` of a convex shape, which must span a volume.
std::vector<Vector3d> ReadConvexPoints(YamlMap& shape) {
  std::vector<Vector3d> points;
  for (const auto& p : shape.Points3("points", 4, kMaxConvexPoints, kMaxSize)) points.emplace_back(p[0], p[1], p[2]);
  try {
    ComputeConvexHull(points);
  } catch (const std::invalid_argument& e) {
    shape.Fail("points", std::string("points spanning a volume (") + e.what() + ")");
  }
  return points;
}

SceneShape ReadShape(YamlMap& s, bool dynamic) {
  SceneShape shape;
  const std::string type = s.RequireString("type");
  const std::string kinds = "one of: box, sphere, capsule, plane, convex";
  if (type == "box") {
    shape.kind = ShapeKind::kBox;
    const bool half = s.Has("half_extents");
    const bool full = s.Has("size");
    if (half == full) s.Fail("size", "exactly one of 'half_extents' and 'size' for a box");
    shape.half_extents =
        half ? ToVector(s.Numbers("half_extents", 3, kMinSize, kMaxSize))
             : Vector3d(0.5 * ToVector(s.Numbers("size", 3, 2 * kMinSize, 2 * kMaxSize)));
  } else if (type == "sphere") {
    shape.kind = ShapeKind::kSphere;
    shape.radius = s.RequireNumber("radius", kMinSize, kMaxSize);
  } else if (type == "capsule") {
    shape.kind = ShapeKind::kCapsule;
    shape.radius = s.RequireNumber("radius", kMinSize, kMaxSize);
    shape.length = s.RequireNumber("length", 0.0, kMaxSize);
  } else if (type == "plane") {
    shape.kind = ShapeKind::kPlane;
    if (dynamic) s.Fail("type", "box, sphere, capsule or convex: planes only on static objects");
    const Vector3d n = ToVector(s.Numbers("normal", 3, -kMaxSize, kMaxSize));
    if (n.norm() < 1e-9) s.Fail("normal", "a non-zero normal vector");
    shape.normal = n.normalized();
    shape.offset = s.RequireNumber("offset", -kMaxCoordinate, kMaxCoordinate) / n.norm();
  } else if (type == "convex") {
    shape.kind = ShapeKind::kConvex;
    shape.points = ReadConvexPoints(s);
  } else {
    s.Fail("type", kinds);
  }
  shape.position = ToVector(s.Vec3("position", {0.0, 0.0, 0.0}, -kMaxCoordinate, kMaxCoordinate));
  shape.rotation = ReadRotation(s);
  s.Finish();
  return shape;
}

Material ReadMaterial(YamlMap& o) {
  if (!o.Has("material")) return Material{};
  const std::string expected = std::string("a preset (") + kPresetList +
                               ") or a mapping {restitution, static_friction, dynamic_friction}";
  if (o.IsScalar("material")) {
    const std::string name = o.String("material", "");
    const auto preset = MaterialPreset(name);
    if (!preset) o.Fail("material", expected);
    return *preset;
  }
  if (!o.IsMap("material")) o.Fail("material", expected);
  YamlMap m = o.Map("material");
  Material out;
  out.restitution = m.RequireNumber("restitution", 0.0, 1.0);
  out.static_friction = m.RequireNumber("static_friction", 0.0, kMaxFriction);
  out.dynamic_friction = m.RequireNumber("dynamic_friction", 0.0, kMaxFriction);
  m.Finish();
  return out;
}

}  // namespace

Scene LoadScene(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);

  Scene scene;
  scene.file = file;
  std::vector<YamlMap> objects = root.MapList("objects");
  if (objects.empty()) root.Fail("objects", "a list of at least one object");
  std::set<std::string> names;
  for (size_t i = 0; i < objects.size(); ++i) {
    YamlMap& o = objects[i];
    SceneObject obj;
    obj.name = o.RequireString("name");
    if (!names.insert(obj.name).second) o.Fail("name", "a name no other object has");
    const std::string type = o.RequireString("type");
    if (type != "static" && type != "dynamic") o.Fail("type", "static or dynamic");
    obj.dynamic = type == "dynamic";
    obj.position = ToVector(o.Vec3("position", {0.0, 0.0, 0.0}, -kMaxCoordinate, kMaxCoordinate));
    obj.rotation = ReadRotation(o);

    const bool has_mass = o.Has("mass");
    const bool has_density = o.Has("density");
    if (!obj.dynamic && (has_mass || has_density)) {
      o.Fail(has_mass ? "mass" : "density",
             "neither mass nor density on a static object (it does not move)");
    }
    if (obj.dynamic) {
      if (has_mass && has_density) o.Fail("density", "either 'mass' or 'density', not both");
      if (!has_mass && !has_density)
        o.Fail("mass", "a mass in kg (or a density in kg/m³) for a dynamic object");
      if (has_mass) obj.mass = o.RequireNumber("mass", kMinMass, kMaxMass);
      if (has_density) obj.density = o.RequireNumber("density", kMinDensity, kMaxDensity);
    }
    obj.material = ReadMaterial(o);

    std::vector<YamlMap> shapes = o.MapList("shapes");
    if (shapes.empty()) o.Fail("shapes", "a list of at least one shape");
    for (YamlMap& shape : shapes) obj.shapes.push_back(ReadShape(shape, obj.dynamic));
    if (obj.dynamic) {
      const std::string problem = CheckMassProperties(obj);
      if (!problem.empty()) o.Fail("shapes", problem);
    }
    o.Finish();
    scene.objects.push_back(std::move(obj));
  }
  root.Finish();
  return scene;
}

// ---- XML -------------------------------------------------------------------

namespace {

struct XmlAttribute {
  std::string name;
  std::string value;
  int line = 0;
};

struct XmlElement {
  std::string name;
  int line = 0;
  std::vector<XmlAttribute> attributes;
  std::vector<XmlElement> children;
  std::string text;  ///< all character data directly inside, concatenated
};

/// A small strict parser for the XML subset described in scene.hpp.
class XmlParser {
 public:
  XmlParser(std::string text, std::string file) : text_(std::move(text)), file_(std::move(file)) {}

  XmlElement ParseDocument() {
    if (text_.compare(0, 3, "\xEF\xBB\xBF") == 0) pos_ = 3;
    std::optional<XmlElement> root;
    while (true) {
      SkipBlanks();
      if (AtEnd()) break;
      if (Starts("<?")) {
        SkipUntil("?>", "processing instruction or XML declaration");
      } else if (Starts("<!--")) {
        SkipComment();
      } else if (Starts("<!")) {
        Fail(line_, "DOCTYPE and other declarations are not supported");
      } else if (Starts("</")) {
        Fail(line_, "closing tag without an opening one");
      } else if (Starts("<")) {
        if (root) Fail(line_, "a second root element (the root is <" + root->name + ">)");
        root = ParseElement(0);
      } else {
        Fail(line_, root ? "text after the root element <" + root->name + ">"
                         : "text before the root element");
      }
    }
    if (!root) Fail(line_, "no root element");
    return std::move(*root);
  }

 private:
  [[noreturn]] void Fail(int line, const std::string& what) const {
    throw ConfigError(file_ + ":" + std::to_string(line) + ": " + what);
  }
  bool AtEnd() const { return pos_ >= text_.size(); }
  bool Starts(const char* s) const {
    return text_.compare(pos_, std::char_traits<char>::length(s), s) == 0;
  }
  char Peek() const { return AtEnd() ? '\0' : text_[pos_]; }
  char Next() {
    const char c = text_[pos_++];
    if (c == '\n') ++line_;
    return c;
  }
  static bool Blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
  void SkipBlanks() {
    while (!AtEnd() && Blank(Peek())) Next();
  }
  void SkipUntil(const std::string& end, const std::string& what) {
    const int start = line_;
    const size_t found = text_.find(end, pos_);
    if (found == std::string::npos) Fail(start, "unterminated " + what);
    while (pos_ < found + end.size()) Next();
  }
  void SkipComment() {
    const int start = line_;
    pos_ += 4;
    const size_t found = text_.find("--", pos_);
    if (found == std::string::npos) Fail(start, "unterminated comment");
    if (text_.compare(found, 3, "-->") != 0) Fail(start, "'--' inside a comment");
    while (pos_ < found + 3) Next();
  }
  static bool NameStart(char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == ':' ||
           static_cast<unsigned char>(c) >= 0x80;
  }
  static bool NameChar(char c) {
    return NameStart(c) || std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '.';
  }
  std::string Name(const std::string& what) {
    if (!NameStart(Peek())) Fail(line_, "expected " + what);
    const size_t start = pos_;
    while (!AtEnd() && NameChar(Peek())) ++pos_;
    return text_.substr(start, pos_ - start);
  }

  // Character data up to (not including) the next '<' or the quote, with
  // entities decoded.
  std::string CharData(char stop, const std::string& where) {
    std::string out;
    while (!AtEnd() && Peek() != '<' && Peek() != stop) {
      if (Peek() == '&') {
        out += Entity(where);
      } else {
        out += Next();
      }
    }
    return out;
  }

  std::string Entity(const std::string& where) {
    const int line = line_;
    const size_t semi = text_.find(';', pos_);
    if (semi == std::string::npos || semi - pos_ > 12)
      Fail(line, where + ": '&' that starts no entity (write &amp;)");
    const std::string name = text_.substr(pos_ + 1, semi - pos_ - 1);
    pos_ = semi + 1;
    if (name == "lt") return "<";
    if (name == "gt") return ">";
    if (name == "amp") return "&";
    if (name == "quot") return "\"";
    if (name == "apos") return "'";
    if (name.size() > 1 && name[0] == '#') {
      const bool hex = name[1] == 'x';
      const char* first = name.data() + (hex ? 2 : 1);
      const char* last = name.data() + name.size();
      unsigned long code = 0;
      const auto [end, ec] = std::from_chars(first, last, code, hex ? 16 : 10);
      if (ec == std::errc() && end == last && first != last && code > 0 && code <= 0x10FFFF) {
        return Utf8(code);
      }
    }
    Fail(line, where + ": unknown entity '&" + name + ";'");
  }

  static std::string Utf8(unsigned long c) {
    std::string out;
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else if (c < 0x800) {
      out += static_cast<char>(0xC0 | (c >> 6));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
      out += static_cast<char>(0xE0 | (c >> 12));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (c >> 18));
      out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    }
    return out;
  }

  XmlElement ParseElement(int depth) {
    if (depth > 64) Fail(line_, "elements nested deeper than 64");
    XmlElement e;
    e.line = line_;
    ++pos_;  // '<'
    e.name = Name("an element name after '<'");
    const std::string where = "element <" + e.name + ">";
    while (true) {
      const bool blank = !AtEnd() && Blank(Peek());
      SkipBlanks();
      if (AtEnd()) Fail(e.line, where + ": start tag not closed (end of file)");
      if (Starts("/>")) {
        pos_ += 2;
        return e;
      }
      if (Peek() == '>') {
        ++pos_;
        break;
      }
      if (!blank)
        Fail(line_, where + ": expected a blank, '>' or '/>' after the name or an attribute");
      XmlAttribute a;
      a.line = line_;
      a.name = Name(where + ": an attribute name, '>' or '/>'");
      for (const XmlAttribute& other : e.attributes) {
        if (other.name == a.name) Fail(a.line, where + ": attribute '" + a.name + "' given twice");
      }
      SkipBlanks();
      if (Peek() != '=') Fail(line_, where + ": expected '=' after attribute '" + a.name + "'");
      ++pos_;
      SkipBlanks();
      const char quote = Peek();
      if (quote != '"' && quote != '\'')
        Fail(line_, where + ": attribute '" + a.name + "': value must be quoted");
      ++pos_;
      a.value = CharData(quote, where + ", attribute '" + a.name + "'");
      if (AtEnd()) Fail(a.line, where + ": attribute '" + a.name + "': value not closed");
      if (Peek() == '<')
        Fail(line_, where + ": attribute '" + a.name + "': '<' in a value (write &lt;)");
      ++pos_;  // closing quote
      e.attributes.push_back(std::move(a));
    }
    // Content.
    while (true) {
      if (AtEnd())
        Fail(e.line, where + ": not closed (no </" + e.name + "> before the end of the file)");
      if (Starts("</")) {
        const int line = line_;
        pos_ += 2;
        const std::string name = Name("an element name after '</'");
        SkipBlanks();
        if (Peek() != '>') Fail(line, "closing tag </" + name + ">: expected '>'");
        ++pos_;
        if (name != e.name) {
          Fail(line, where + " (opened at line " + std::to_string(e.line) + ") closed by </" +
                         name + ">");
        }
        return e;
      }
      if (Starts("<!--")) {
        SkipComment();
      } else if (Starts("<![CDATA[")) {
        const int line = line_;
        pos_ += 9;
        const size_t end = text_.find("]]>", pos_);
        if (end == std::string::npos) Fail(line, where + ": unterminated CDATA section");
        while (pos_ < end) e.text += Next();
        pos_ += 3;
      } else if (Starts("<?")) {
        SkipUntil("?>", "processing instruction");
      } else if (Starts("<!")) {
        Fail(line_, where + ": declarations are not supported inside elements");
      } else if (Peek() == '<') {
        e.children.push_back(ParseElement(depth + 1));
      } else {
        e.text += CharData('<', where);
      }
    }
  }

  std::string text_;
  std::string file_;
  size_t pos_ = 0;
  int line_ = 1;
};

// Names compare case-insensitively, ignoring '_' and '-' (staticFriction,
// static_friction, STATICFRICTION are one name).
std::string Key(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (c != '_' && c != '-') out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

// One value read from an element: an attribute or a child element's text.
struct XmlValue {
  std::string text;
  int line = 0;
  std::string
      where;  // "element <shape>, attribute 'boxparams'" or "element <position> in <object>"
};

// Reads an element's attributes and children by name; Finish() rejects the
// ones nobody asked for.
class ElementReader {
 public:
  ElementReader(const XmlElement& e, std::string file) : e_(e), file_(std::move(file)) {}

  [[noreturn]] void Fail(int line, const std::string& what) const {
    throw ConfigError(file_ + ":" + std::to_string(line) + ": element <" + e_.name + ">: " + what);
  }
  [[noreturn]] static void Fail(const std::string& file, const XmlValue& v,
                                const std::string& expected) {
    throw ConfigError(file + ":" + std::to_string(v.line) + ": " + v.where + ": expected " +
                      expected + ", got '" + v.text + "'");
  }
  const XmlElement& element() const { return e_; }
  const std::string& file() const { return file_; }

  /// An attribute or a child element (text only) named `name`; not both.
  std::optional<XmlValue> Take(const std::string& name) {
    used_.insert(Key(name));
    std::optional<XmlValue> out;
    for (const XmlAttribute& a : e_.attributes) {
      if (Key(a.name) == Key(name)) {
        out = XmlValue{Trim(a.value), a.line,
                       "element <" + e_.name + ">, attribute '" + a.name + "'"};
      }
    }
    for (const XmlElement& c : e_.children) {
      if (Key(c.name) != Key(name)) continue;
      if (out) Fail(c.line, "'" + name + "' given twice (as an attribute or element)");
      if (!c.children.empty() || !c.attributes.empty()) {
        Fail(c.line, "<" + c.name + "> holds only text (no attributes or elements)");
      }
      out = XmlValue{Trim(c.text), c.line, "element <" + c.name + "> in <" + e_.name + ">"};
    }
    return out;
  }

  std::vector<const XmlElement*> Children(const std::string& name) {
    used_.insert(Key(name));
    std::vector<const XmlElement*> out;
    for (const XmlElement& c : e_.children) {
      if (Key(c.name) == Key(name)) out.push_back(&c);
    }
    return out;
  }

  void Finish() const {
    std::string known;
    for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
    for (const XmlAttribute& a : e_.attributes) {
      if (used_.count(Key(a.name)) == 0 && Key(a.name).rfind("xmlns", 0) != 0) {
        Fail(a.line, "unknown attribute '" + a.name + "' (expected: " + known + ")");
      }
    }
    for (const XmlElement& c : e_.children) {
      if (used_.count(Key(c.name)) == 0)
        Fail(c.line, "unknown element <" + c.name + "> (expected: " + known + ")");
    }
    if (!Trim(e_.text).empty())
      Fail(e_.line, "unexpected text '" + Trim(e_.text).substr(0, 40) + "'");
  }

 private:
  const XmlElement& e_;
  std::string file_;
  std::set<std::string> used_;
};

// Exactly `count` finite numbers separated by blanks and/or commas, each in
// [min, max].
std::vector<double> XmlNumbers(const std::string& file, const XmlValue& v, size_t count, double min,
                               double max, const std::string& meaning) {
  std::ostringstream expected;
  expected << count << (count == 1 ? " number" : " numbers") << " in [" << min << ", " << max
           << "] (" << meaning << ")";
  std::vector<double> out;
  size_t i = 0;
  const std::string& s = v.text;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ',' || std::isspace(static_cast<unsigned char>(s[i])))) ++i;
    if (i == s.size()) break;
    size_t j = i;
    while (j < s.size() && s[j] != ',' && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
    const char* first = s.data() + i + (s[i] == '+' ? 1 : 0);
    const char* last = s.data() + j;
    double value = 0.0;
    const auto [end, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || end != last || first == last || !std::isfinite(value) || value < min ||
        value > max) {
      ElementReader::Fail(file, v, expected.str());
    }
    out.push_back(value);
    i = j;
  }
  if (out.size() != count) ElementReader::Fail(file, v, expected.str());
  return out;
}

Material ReadXmlMaterial(ElementReader& object) {
  const auto children = object.Children("materialparams");
  const auto attribute_form = [&]() -> std::optional<XmlValue> {
    for (const XmlAttribute& a : object.element().attributes) {
      if (Key(a.name) == "materialparams") {
        return XmlValue{Trim(a.value), a.line,
                        "element <" + object.element().name + ">, attribute '" + a.name + "'"};
      }
    }
    return std::nullopt;
  }();
  if (children.size() + (attribute_form ? 1 : 0) > 1) {
    object.Fail(children.empty() ? attribute_form->line : children.back()->line,
                "'materialparams' given twice");
  }
  const std::string triple = "restitution [0, 1], static friction, dynamic friction [0, 2]";
  const auto from_text = [&](const XmlValue& v) {
    const auto n = XmlNumbers(object.file(), v, 3, 0.0, kMaxFriction, triple);
    if (n[0] > 1.0) ElementReader::Fail(object.file(), v, "3 numbers: " + triple);
    return Material{n[0], n[1], n[2]};
  };
  if (attribute_form) return from_text(*attribute_form);
  if (children.empty()) return Material{};
  ElementReader m(*children.front(), object.file());
  auto restitution = m.Take("restitution");
  auto static_friction = m.Take("staticfriction");
  auto dynamic_friction = m.Take("dynamicfriction");
  const XmlElement& e = m.element();
  if (!restitution && !static_friction && !dynamic_friction && !Trim(e.text).empty()) {
    const Material out = from_text(XmlValue{Trim(e.text), e.line, "element <" + e.name + ">"});
    if (!e.attributes.empty() || !e.children.empty())
      m.Fail(e.line, "either text or attributes, not both");
    return out;
  }
  if (!restitution || !static_friction || !dynamic_friction) {
    m.Fail(e.line, "expected restitution, staticfriction and dynamicfriction");
  }
  Material out;
  out.restitution = XmlNumbers(m.file(), *restitution, 1, 0.0, 1.0, "restitution")[0];
  out.static_friction =
      XmlNumbers(m.file(), *static_friction, 1, 0.0, kMaxFriction, "static friction")[0];
  out.dynamic_friction =
      XmlNumbers(m.file(), *dynamic_friction, 1, 0.0, kMaxFriction, "dynamic friction")[0];
  m.Finish();
  return out;
}

Matrix3d ReadXmlRotation(ElementReader& r) {
  Matrix3d out = Matrix3d::Identity();
  if (const auto v = r.Take("rotation")) {
    const std::string problem = ToRotation(
        XmlNumbers(r.file(), *v, 9, -1.01, 1.01, "a 3×3 rotation matrix, row by row"), out);
    if (!problem.empty()) ElementReader::Fail(r.file(), *v, problem);
  }
  return out;
}

Vector3d ReadXmlPosition(ElementReader& r) {
  if (const auto v = r.Take("position")) {
    return ToVector(XmlNumbers(r.file(), *v, 3, -kMaxCoordinate, kMaxCoordinate, "x y z, m"));
  }
  return Vector3d::Zero();
}

SceneShape ReadXmlShape(ElementReader& s, bool dynamic) {
  SceneShape shape;
  const auto type = s.Take("type");
  if (!type) s.Fail(s.element().line, "expected a type: Plane, Sphere, Box or Capsule");
  const std::string kind = Key(type->text);
  const std::string file = s.file();
  if (kind == "box") {
    shape.kind = ShapeKind::kBox;
    const auto v = s.Take("boxparams");
    if (!v) s.Fail(s.element().line, "a Box needs boxparams=\"hx hy hz\" (half extents, m)");
    shape.half_extents =
        ToVector(XmlNumbers(file, *v, 3, kMinSize, kMaxSize, "half extents hx hy hz, m"));
  } else if (kind == "sphere") {
    shape.kind = ShapeKind::kSphere;
    const auto v = s.Take("sphereparams");
    if (!v) s.Fail(s.element().line, "a Sphere needs sphereparams=\"radius\"");
    shape.radius = XmlNumbers(file, *v, 1, kMinSize, kMaxSize, "radius, m")[0];
  } else if (kind == "capsule") {
    shape.kind = ShapeKind::kCapsule;
    const auto v = s.Take("capsuleparams");
    if (!v) s.Fail(s.element().line, "a Capsule needs capsuleparams=\"radius height\"");
    const auto n = XmlNumbers(file, *v, 2, 0.0, kMaxSize, "radius height, m");
    if (n[0] < kMinSize) ElementReader::Fail(file, *v, "a positive radius");
    shape.radius = n[0];
    shape.length = n[1];
  } else if (kind == "plane") {
    shape.kind = ShapeKind::kPlane;
    if (dynamic) s.Fail(type->line, "a Plane on a dynamic object (planes only on static objects)");
    const auto v = s.Take("planeparams");
    if (!v) s.Fail(s.element().line, "a Plane needs planeparams=\"nx ny nz d\"");
    const auto n =
        XmlNumbers(file, *v, 4, -kMaxCoordinate, kMaxCoordinate, "normal nx ny nz and offset d");
    const Vector3d normal(n[0], n[1], n[2]);
    if (normal.norm() < 1e-9) ElementReader::Fail(file, *v, "a non-zero normal");
    shape.normal = normal.normalized();
    shape.offset = n[3] / normal.norm();
  } else {
    ElementReader::Fail(file, *type, "one of Plane, Sphere, Box, Capsule");
  }
  shape.position = ReadXmlPosition(s);
  shape.rotation = ReadXmlRotation(s);
  if (shape.kind == ShapeKind::kCapsule) {
    // PhysX capsules lie along their local y axis; ours along z: a local
    // rotation of −90° about x takes z onto y.
    shape.rotation =
        shape.rotation *
        Eigen::AngleAxisd(-std::numbers::pi / 2.0, Vector3d::UnitX()).toRotationMatrix();
  }
  s.Finish();
  return shape;
}

std::string ReadFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file.string() + ": cannot open the file");
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

}  // namespace

Scene ImportMhapticXml(const std::filesystem::path& file) {
  const std::string name = file.string();
  const XmlElement root = XmlParser(ReadFile(file), name).ParseDocument();
  if (Key(root.name) != "mhaptic:scene") {
    throw ConfigError(name + ":" + std::to_string(root.line) + ": element <" + root.name +
                      ">: expected the root element <MHAPTIC:scene>");
  }
  ElementReader scene_reader(root, name);
  const auto objects = scene_reader.Children("object");
  scene_reader.Finish();
  if (objects.empty()) scene_reader.Fail(root.line, "expected at least one <object>");

  Scene scene;
  scene.file = file;
  std::set<std::string> names;
  for (size_t i = 0; i < objects.size(); ++i) {
    ElementReader o(*objects[i], name);
    SceneObject obj;
    const auto type = o.Take("type");
    if (!type) o.Fail(objects[i]->line, "expected type=\"Static\" or type=\"Dynamic\"");
    if (Key(type->text) != "static" && Key(type->text) != "dynamic") {
      ElementReader::Fail(name, *type, "Static or Dynamic");
    }
    obj.dynamic = Key(type->text) == "dynamic";
    const auto object_name = o.Take("name");
    obj.name = object_name ? object_name->text : "object" + std::to_string(i + 1);
    if (obj.name.empty()) ElementReader::Fail(name, *object_name, "a non-empty name");
    if (!names.insert(obj.name).second) {
      o.Fail(object_name ? object_name->line : objects[i]->line,
             "name '" + obj.name + "' is used twice");
    }
    obj.position = ReadXmlPosition(o);
    obj.rotation = ReadXmlRotation(o);

    const auto mass = o.Take("mass");
    const auto density = o.Take("density");
    const double m = mass ? XmlNumbers(name, *mass, 1, kMinMass, kMaxMass, "mass, kg")[0] : 0.0;
    const double d =
        density ? XmlNumbers(name, *density, 1, kMinDensity, kMaxDensity, "density, kg/m³")[0]
                : 0.0;
    if (obj.dynamic) {
      if (mass && density) o.Fail(density->line, "either <mass> or <density>, not both");
      if (!mass && !density)
        o.Fail(objects[i]->line, "a dynamic object needs a <mass> or a <density>");
      obj.mass = m;
      obj.density = d;
    }  // static objects: checked above, then ignored (they do not move)
    obj.material = ReadXmlMaterial(o);

    const auto shapes = o.Children("shape");
    if (shapes.empty()) o.Fail(objects[i]->line, "expected at least one <shape>");
    for (const XmlElement* s : shapes) {
      ElementReader shape_reader(*s, name);
      obj.shapes.push_back(ReadXmlShape(shape_reader, obj.dynamic));
    }
    o.Finish();
    if (obj.dynamic) {
      const std::string problem = CheckMassProperties(obj);
      if (!problem.empty()) o.Fail(objects[i]->line, "expected " + problem);
    }
    scene.objects.push_back(std::move(obj));
  }
  return scene;
}

Scene LoadSceneFile(const std::filesystem::path& file) {
  return file.extension() == ".xml" ? ImportMhapticXml(file) : LoadScene(file);
}

}  // namespace haptel
