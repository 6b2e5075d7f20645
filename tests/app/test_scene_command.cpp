// `haptel scene FILE [--json] [--config RUN.yaml]`: the thesis's example and
// the shipped scenes print and exit 0; a malformed scene is one line and exit 2.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/app/scene_command.hpp"
#include "haptel/config/paths.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

struct Outcome {
  int code = -1;
  std::string out;
  std::string err;
};

Outcome Run(std::vector<std::string> words) {
  words.insert(words.begin(), "scene");
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  std::ostringstream out;
  std::ostringstream err;
  Outcome o;
  o.code = haptel::app::SceneCommand(static_cast<int>(argv.size()), argv.data(), out, err);
  o.out = out.str();
  o.err = err.str();
  return o;
}

std::string Shipped(const std::string& relative) { return haptel::ShippedFile(relative).string(); }

}  // namespace

TEST_CASE("haptel scene: the thesis's example prints in the device frame, exit 0", "[scene]") {
  const Outcome o = Run({Shipped("tests/config/data/thesis_appendix_i.xml")});
  INFO(o.out << o.err);
  REQUIRE(o.code == 0);
  REQUIRE(o.err.empty());
  CHECK_THAT(o.out, Contains("1 object (0 dynamic, 1 static)") &&
                        Contains("groundLiving  static  at [4.12167, -1.76636, 0]") &&
                        Contains("plane, normal [0, 0, 1], offset -1e-06") &&
                        Contains("restitution 0.24, static friction 0.35, dynamic friction 0.2") &&
                        Contains("total mass (dynamic objects): 0 kg") &&
                        Contains("bounding box: none"));

  const Outcome json = Run({Shipped("tests/config/data/thesis_appendix_i.xml"), "--json"});
  REQUIRE(json.code == 0);
  REQUIRE(std::count(json.out.begin(), json.out.end(), '\n') == 1);
  CHECK_THAT(json.out, StartsWith("{\"file\":") &&
                           Contains("\"name\":\"groundLiving\",\"dynamic\":false") &&
                           Contains("\"normal\":[0,0,1],\"offset\":-1e-06") &&
                           Contains("\"total_mass_kg\":0,\"bounds\":null}"));
}

TEST_CASE(
    "haptel scene: mass and bounds of the shipped table, from YAML and XML alike; a "
    "run's placement",
    "[scene]") {
  const Outcome yaml = Run({Shipped("config/scenes/table.yaml"), "--json"});
  const Outcome xml = Run({Shipped("config/scenes/table.xml"), "--json"});
  REQUIRE(yaml.code == 0);
  REQUIRE(xml.code == 0);
  for (const std::string& out : {yaml.out, xml.out}) {
    INFO(out);
    CHECK_THAT(out, Contains("\"objects_dynamic\":1,\"objects_static\":2,\"total_mass_kg\":0.5") &&
                        Contains("\"bounds\":{\"min\":[-0.6,-0.4,0],\"max\":[0.6,0.4,0.85]}"));
  }

  const fs::path dir = haptel::test::ScratchDir("test_scene_command");
  const fs::path run = dir / "run.yaml";
  std::ofstream(run) << "track: t.yaml\nvehicle: v.yaml\n"
                        "scene_placement: {position: [0, 0, -0.75], rpy_deg: [0, 0, 0]}\n";
  const Outcome placed = Run({Shipped("config/scenes/table.yaml"), "--config", run.string()});
  INFO(placed.out << placed.err);
  REQUIRE(placed.code == 0);
  CHECK_THAT(placed.out,
             Contains("placed at [0, 0, -0.75]") &&
                 Contains("bounding box: min [-0.6, -0.4, -0.75], max [0.6, 0.4, 0.1]"));
  fs::remove_all(dir);
}

TEST_CASE("haptel scene: a malformed scene or a bad command line is one line, exit 2", "[scene]") {
  const std::string printed = Shipped("tests/config/data/thesis_appendix_i_as_printed.xml");
  const Outcome bad = Run({printed});
  REQUIRE(bad.code == 2);
  REQUIRE(bad.out.empty());
  CHECK(bad.err == "haptel: " + printed +
                       ":47: </MHAPTIC:materialparams>: unexpected after the root element "
                       "<MHAPTIC:scene> ended (expected the end of the file)\n");

  const Outcome missing = Run({"no/such/scene.xml"});
  REQUIRE(missing.code == 2);
  CHECK(missing.err == "haptel: no/such/scene.xml: cannot open the file\n");

  for (const auto& words :
       std::vector<std::vector<std::string>>{{}, {"a.xml", "b.xml"}, {"a.xml", "--colour"}}) {
    const Outcome usage = Run(words);
    REQUIRE(usage.code == 2);
    REQUIRE(std::count(usage.err.begin(), usage.err.end(), '\n') == 1);
    CHECK_THAT(usage.err, StartsWith("haptel scene: "));
  }
  const Outcome help = Run({"--help"});
  CHECK(help.code == 0);
  CHECK_THAT(help.out, Contains("usage: haptel scene FILE"));
}
