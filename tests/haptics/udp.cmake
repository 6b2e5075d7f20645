# Tests of the UDP device protocol, UdpDevice and haptel-device-server.
# Included from tests/haptics/CMakeLists.txt; paths are relative to this file.
haptel_add_test(test_udp
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_udp_protocol.cpp ${CMAKE_CURRENT_LIST_DIR}/test_udp_device.cpp
  LIBS haptel_udp)
# The end-to-end cases run the server executable.
add_dependencies(test_udp haptel-device-server)
