#include "haptel/config/truth_format.hpp"

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace haptel {

namespace {
constexpr const char* kFirstLine = "# haptel truth record 1";
constexpr const char* kColumns = "operator_ns,x,y,z,heading,speed,yaw_rate";

/// "%.17g": a double read back is the double written.
std::string Exact(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}
}  // namespace

std::string TruthHeaderText(const DrawnReality& reality) {
  std::string out = std::string(kFirstLine) + "\n";
  out += "# reality " + reality.name + "\n";
  out += "# seed " + std::to_string(reality.seed) + "\n";
  DrawnReality::ForEach(reality, [&](const char* name, double value) {
    out += std::string("# ") + name + " " + Exact(value) + "\n";
  });
  for (const FloorPatch& p : reality.floor_patches) {
    out += "# floor_patch " + Exact(p.x) + " " + Exact(p.y) + " " + Exact(p.radius) + " " +
           Exact(p.traction) + "\n";
  }
  for (const Segment2& w : reality.true_walls) {
    out += "# wall " + Exact(w.a.x()) + " " + Exact(w.a.y()) + " " + Exact(w.b.x()) + " " +
           Exact(w.b.y()) + "\n";
  }
  for (const CircleObstacle& c : reality.true_posts) {
    out +=
        "# post " + Exact(c.center.x()) + " " + Exact(c.center.y()) + " " + Exact(c.radius) + "\n";
  }
  out += std::string(kColumns) + "\n";
  return out;
}

size_t FormatTruthRow(const TruthRow& r, char* out, size_t size) {
  const int n = std::snprintf(out, size, "%" PRId64 ",%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n",
                              r.operator_ns, r.x, r.y, r.z, r.heading, r.speed, r.yaw_rate);
  return n > 0 && static_cast<size_t>(n) < size ? static_cast<size_t>(n) : 0;
}

bool IsTruthColumnLine(const std::string& line) { return line == kColumns; }

bool ParseTruthHeaderLine(const std::string& line, DrawnReality& reality) {
  if (line.rfind("# ", 0) != 0) return false;
  if (line == kFirstLine) return true;
  std::istringstream in(line.substr(2));
  std::string key;
  in >> key;
  if (key == "reality") {
    in >> reality.name;
    return true;
  }
  if (key == "seed") {
    if (!(in >> reality.seed)) throw std::invalid_argument("'# seed N', a whole number");
    return true;
  }
  if (key == "floor_patch") {
    FloorPatch p;
    if (!(in >> p.x >> p.y >> p.radius >> p.traction))
      throw std::invalid_argument("'# floor_patch X Y RADIUS TRACTION', four numbers");
    reality.floor_patches.push_back(p);
    return true;
  }
  if (key == "wall") {
    double ax, ay, bx, by;
    if (!(in >> ax >> ay >> bx >> by))
      throw std::invalid_argument("'# wall AX AY BX BY', four numbers");
    reality.true_walls.push_back({Vec2(ax, ay), Vec2(bx, by)});
    return true;
  }
  if (key == "post") {
    double x, y, radius;
    if (!(in >> x >> y >> radius))
      throw std::invalid_argument("'# post X Y RADIUS', three numbers");
    reality.true_posts.push_back({Vec2(x, y), radius});
    return true;
  }
  bool known = false;
  DrawnReality::ForEach(reality, [&](const char* name, double& value) {
    if (known || key != name) return;
    known = true;
    if (!(in >> value)) throw std::invalid_argument("'# " + key + " VALUE', a number");
  });
  if (!known) throw std::invalid_argument("a known header key, not '" + key + "'");
  return true;
}

TruthRow ParseTruthRow(const std::string& line) {
  TruthRow r;
  char* end = nullptr;
  const char* p = line.c_str();
  r.operator_ns = std::strtoll(p, &end, 10);
  double* fields[] = {&r.x, &r.y, &r.z, &r.heading, &r.speed, &r.yaw_rate};
  bool ok = end != p;
  for (double* f : fields) {
    if (!ok || *end != ',') {
      ok = false;
      break;
    }
    p = end + 1;
    *f = std::strtod(p, &end);
    ok = end != p;
  }
  if (!ok || *end != '\0')
    throw std::invalid_argument(std::string("a row of 7 comma-separated numbers (") + kColumns +
                                ")");
  return r;
}

}  // namespace haptel
