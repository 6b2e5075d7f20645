# Calibration: fitting maths, the `haptel calibrate` procedure and its command line.
add_library(haptel_calibration src/calibration.cpp src/calibration_procedure.cpp)
target_include_directories(haptel_calibration PUBLIC include)
target_link_libraries(haptel_calibration PUBLIC haptel_haptics haptel_config haptel_core Eigen3::Eigen
  PRIVATE haptel_warnings)
