// The candump -L logs the CAN robot writes, read by the tools people use on
// them: python-can's can.LogReader and can-utils' log2asc (Debian's
// python3-can and can-utils, installed by scripts/lib.sh).
#include <catch2/catch.hpp>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "file_size_limit.hpp"
#include "haptel/vehicles/can_bus.hpp"
#include "haptel/vehicles/candump_log.hpp"
#include "haptel/vehicles/odrive_can.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::vehicles;

TEST_CASE("python-can's LogReader and log2asc read the robot's candump log") {
  const auto dir = test::ScratchDir("candump-tools");
  const auto log = dir / "robot1.log";
  {
    CandumpWriter writer(log, "can0");
    writer.Write(odrive::SetInputVel(1, 1.5F), 1'795'503'326'512'319'000);
    writer.Write(odrive::Heartbeat(2, 0x40, 8), 1'795'503'326'522'000'000);
    writer.Write(odrive::Estop(1), 1'795'503'326'530'000'000);
  }
  const auto out = dir / "python.txt";
  const std::string python =
      "/usr/bin/python3 -c \"import can, sys\n"
      "msgs = list(can.LogReader(sys.argv[1]))\n"
      "print(len(msgs))\n"
      "for m in msgs: print('%03X %s %.6f %s' % (m.arbitration_id, bytes(m.data).hex().upper(), "
      "m.timestamp, m.channel))\" " +
      log.string() + " > " + out.string() + " 2>&1";
  REQUIRE(std::system(python.c_str()) == 0);
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  INFO(text.str());
  CHECK(text.str().find("3\n") == 0);
  CHECK(text.str().find("02D 0000C03F00000000 1795503326.512319 can0") != std::string::npos);
  CHECK(text.str().find("041 4000000008000000") != std::string::npos);
  CHECK(text.str().find("022  ") != std::string::npos);  // no data

  const auto asc = dir / "robot1.asc";
  const std::string log2asc =
      "/usr/bin/log2asc -I " + log.string() + " -O " + asc.string() + " can0";
  REQUIRE(std::system(log2asc.c_str()) == 0);
  std::ifstream asc_in(asc);
  std::stringstream asc_text;
  asc_text << asc_in.rdbuf();
  INFO(asc_text.str());
  // Vector ASC: "<t> 1  2D  Rx   d 8 00 00 C0 3F 00 00 00 00"
  CHECK(asc_text.str().find("2D") != std::string::npos);
  CHECK(asc_text.str().find("00 00 C0 3F 00 00 00 00") != std::string::npos);
}

TEST_CASE(
    "a CAN log whose writes fail (/dev/full: ENOSPC) is ended, counted and says why; it never "
    "throws") {
  CandumpWriter writer("/dev/full", "can0");
  int64_t t = 1'795'503'326'000'000'000;
  constexpr uint64_t kFrames = 3 * CandumpWriter::kFlushEvery;
  for (uint64_t i = 0; i < kFrames; ++i) writer.Write(odrive::SetInputVel(1, 1.5F), t += 1'000'000);
  INFO(writer.error());
  CHECK(writer.error().find("cannot write /dev/full: " + std::string(std::strerror(ENOSPC))) !=
        std::string::npos);
  CHECK(writer.error().find("after 0 frames") != std::string::npos);
  CHECK(writer.lines() == kFrames);
  CHECK(writer.frames_written() == 0);
  CHECK(writer.frames_lost() == kFrames);  // every frame, none counted as saved
  CHECK_FALSE(writer.Close());
}

TEST_CASE(
    "a CAN log that cannot grow (a file size limit: EFBIG) keeps what it flushed and counts the "
    "rest as lost") {
  const auto file = test::ScratchDir("candump-full") / "robot1.log";
  CandumpWriter writer(file, "can0");
  constexpr rlim_t kLimit = 16 * 1024;  // bytes: a few hundred lines
  constexpr uint64_t kFrames = 2000;
  int64_t t = 1'795'503'326'000'000'000;
  {
    test::FileSizeLimit limit(kLimit);
    for (uint64_t i = 0; i < kFrames; ++i)
      writer.Write(odrive::Heartbeat(2, 0x40, 8), t += 1'000'000);
  }
  INFO(writer.error());
  CHECK(writer.error().find("cannot write " + file.string() + ": " + std::strerror(EFBIG)) !=
        std::string::npos);
  CHECK(writer.frames_written() > 0);
  CHECK(writer.frames_written() + writer.frames_lost() == kFrames);
  CHECK(writer.error().find("after " + std::to_string(writer.frames_written()) + " frames") !=
        std::string::npos);
  CHECK_FALSE(writer.Close());
  // What it counts as written is in the file, whole.
  size_t malformed = 0;
  const std::vector<LoggedFrame> frames = ReadCandumpLog(file, &malformed);
  CHECK(frames.size() >= writer.frames_written());
  CHECK(malformed <= 1);  // at most the line the limit cut
  CHECK(std::filesystem::file_size(file) <= kLimit);
}

TEST_CASE("a CAN log on a disk that takes it is whole: every frame written, none lost") {
  const auto file = test::ScratchDir("candump-whole") / "robot1.log";
  CandumpWriter writer(file, "can0");
  int64_t t = 1'795'503'326'000'000'000;
  for (int i = 0; i < 1000; ++i) writer.Write(odrive::Heartbeat(2, 0x40, 8), t += 1'000'000);
  CHECK(writer.Close());
  CHECK(writer.error().empty());
  CHECK(writer.frames_written() == 1000);
  CHECK(writer.frames_lost() == 0);
  CHECK(ReadCandumpLog(file).size() == 1000);
}
