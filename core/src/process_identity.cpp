#include "haptel/core/process_identity.hpp"

#include <pwd.h>
#include <unistd.h>

#include <cstdlib>
#include <random>

namespace haptel {

std::string HostName() {
  char host[64] = {};
  if (gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') return "?";
  return host;
}

std::string UserName() {
  const char* user = std::getenv("USER");
  if (user == nullptr) {
    const passwd* entry = getpwuid(getuid());
    if (entry != nullptr) user = entry->pw_name;
  }
  return user != nullptr ? user : "?";
}

uint64_t NewSessionId() {
  std::random_device random;
  uint64_t id = 0;
  while (id == 0) id = (static_cast<uint64_t>(random()) << 32) ^ random();
  return id;
}

std::string ProcessOperatorName(const std::string& program) {
  std::string name =
      program + ", " + UserName() + "@" + HostName() + " pid " + std::to_string(getpid());
  if (name.size() > 63) name.resize(63);
  return name;
}

}  // namespace haptel
