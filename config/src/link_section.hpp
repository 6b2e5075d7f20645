#pragma once
#include <stdexcept>
#include <string>

#include "haptel/config/link.hpp"
#include "yaml_map.hpp"

namespace haptel::config_detail {

/// Reads a `link:` section (and finishes it); `dir` is the file's folder,
/// which `security` is relative to. LinkConfig::ValidateOrThrow, run by the
/// enclosing config's, checks the values.
inline LinkConfig ReadLink(YamlMap& link, const std::filesystem::path& dir) {
  LinkConfig c;
  c.domain_id = link.Integer("domain_id", c.domain_id);
  c.interfaces = link.Strings("interfaces", c.interfaces);
  c.peers = link.Strings("peers", c.peers);
  c.command_deadline_s = link.Number("command_deadline_s", c.command_deadline_s);
  if (link.Has("fault")) {
    const std::string text = link.RequireString("fault");
    try {
      c.fault = ParseLinkFault(text);
    } catch (const std::invalid_argument& e) {
      link.Fail("fault", e.what());
    }
  }
  if (link.Has("security")) c.security = dir / link.RequireString("security");
  c.discovery_server = link.String("discovery_server", c.discovery_server);
  link.Finish();
  return c;
}

}  // namespace haptel::config_detail
