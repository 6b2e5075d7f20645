# The `udp` device driver (one computer per arm, haptics/PROTOCOL.md) and
# haptel-device-server, which serves one sim arm over that protocol.
# Included from haptics/CMakeLists.txt; paths are relative to this file.
add_library(haptel_udp
  ${CMAKE_CURRENT_LIST_DIR}/src/udp_protocol.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/udp_device.cpp)
target_include_directories(haptel_udp PUBLIC ${CMAKE_CURRENT_LIST_DIR}/include)
target_link_libraries(haptel_udp PUBLIC haptel_haptics haptel_config haptel_core PRIVATE haptel_warnings)

add_executable(haptel-device-server ${CMAKE_CURRENT_LIST_DIR}/src/device_server_main.cpp)
target_link_libraries(haptel-device-server PRIVATE haptel_udp haptel_warnings)
