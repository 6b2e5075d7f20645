#pragma once
// Loopback UDP sockets for the UDP device's tests (test_udp_device.cpp,
// test_udp_passivity.cpp).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <catch2/catch.hpp>

#include "haptel/core/unique_fd.hpp"

namespace haptel::test {

/// A UDP socket bound to 127.0.0.1 on an ephemeral port, which it stores in `port`.
inline UniqueFd BoundLoopback(int& port) {
  UniqueFd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  REQUIRE(fd.get() >= 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  REQUIRE(::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  socklen_t len = sizeof addr;
  REQUIRE(::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&addr), &len) == 0);
  port = ntohs(addr.sin_port);
  return fd;
}

}  // namespace haptel::test
