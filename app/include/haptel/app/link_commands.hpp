#pragma once
/// @file The commands that set a link up across hosts: `haptel security
/// init` (DDS Security's folder) and `haptel discovery-server`.

namespace haptel::app {

/// `haptel security init DIR [--vehicles A,B] [--days N]`: makes the folder
/// DDS Security needs (link/security.hpp): a CA, the operator's and each
/// vehicle's identity, the signed governance and permissions. Then
/// `--security DIR` (or link.security) on haptel run and haptel-vehicle.
/// `argv[0]` is "security". Exit 0 done, 2 bad arguments or a folder that
/// already holds a CA, 1 when openssl fails.
int SecurityCommand(int argc, const char* const* argv);

/// `haptel discovery-server [--listen ADDR:PORT]` (default 127.0.0.1:11811):
/// serves Fast DDS discovery until SIGINT or SIGTERM, for links whose hosts
/// cannot find each other (no multicast, addresses not known in advance):
/// `--discovery-server ADDR:PORT` on haptel run and haptel-vehicle.
int DiscoveryServerCommand(int argc, const char* const* argv);

}  // namespace haptel::app
