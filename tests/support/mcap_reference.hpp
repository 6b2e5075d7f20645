#pragma once
/// @file An MCAP file read by the TypeScript reference reader (@mcap/core,
/// installed by scripts/test into build/node-tools; the test's environment
/// names it in HAPTEL_NODE_TOOLS) through tests/mcap/mcap_reference_reader.mjs:
/// its JSON line (per-topic counts of the indexed and the stream readers,
/// CRCs, and with `decode` every omgidl/cdr message decoded against the
/// file's own schema by @foxglove/omgidl-serialization). The test fails,
/// saying why, when node, the packages or the file's reading fail.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace haptel::test {

/// The JSON lines tests/mcap/mcap_reference_reader.mjs prints for `file`
/// with `options` (e.g. "--decode --dump /hands"); the test fails, saying
/// why, when node or the packages are missing (scripts/test installs them).
inline std::string ReferenceRead(const std::filesystem::path& file,
                                 const std::string& options = "") {
  const char* tools = std::getenv("HAPTEL_NODE_TOOLS");
  REQUIRE(tools != nullptr);
  INFO("the reference reader is installed by scripts/test into " << tools);
  REQUIRE(
      std::filesystem::exists(std::filesystem::path(tools) / "node_modules" / "@mcap" / "core"));
  const std::string command =
      "node tests/mcap/mcap_reference_reader.mjs '" + file.string() + "' " + options + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  std::string out;
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  const int status = pclose(pipe);
  INFO(out);
  REQUIRE(status == 0);
  return out;
}

}  // namespace haptel::test
