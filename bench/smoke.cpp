#include "smoke.hpp"

#include <cstdarg>
#include <cstdio>

#include "plot.hpp"

namespace haptel::bench {

std::filesystem::path OutputDir(bool smoke) {
  if (!smoke) return BenchDir();
  const std::filesystem::path dir = BenchDir() / "smoke";
  std::filesystem::create_directories(dir);
  return dir;
}

void PrintSmokeNote(const char* bench, bool smoke, const char* format, ...) {
  if (!smoke) return;
  char shortened[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(shortened, sizeof shortened, format, args);
  va_end(args);
  std::printf("haptel bench %s: SMOKE run (--smoke): %s; its figures are no measurements\n", bench,
              shortened);
  std::fflush(stdout);
}

std::string JsonLine(const std::string& object, bool smoke) {
  if (!smoke || object.size() < 2 || object.front() != '{') return object;
  return object == "{}" ? "{\"smoke\":true}" : "{\"smoke\":true," + object.substr(1);
}

}  // namespace haptel::bench
