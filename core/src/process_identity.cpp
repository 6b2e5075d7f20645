#include "haptel/core/process_identity.hpp"

#include <unistd.h>

namespace haptel {

std::string HostName() {
  char host[64] = {};
  if (gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') return "?";
  return host;
}

}  // namespace haptel
