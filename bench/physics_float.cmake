# haptel-physics-bench-float: the physics sources and the work-precision
# measurements built against Debian's float Bullet (BulletConfig.cmake), for
# `haptel bench physics` (physics_bench.hpp) to run as a child. A program of
# its own: it never links haptel_physics or anything else on double Bullet.
function(haptel_add_physics_float_bench)
  # Bullet_DIR is the folder physics/ found BulletConfig-float64.cmake in;
  # the float config sits next to it. Its variables stay in this function.
  include("${Bullet_DIR}/BulletConfig.cmake")
  if(BULLET_DEFINITIONS MATCHES "BT_USE_DOUBLE_PRECISION")
    message(FATAL_ERROR "Bullet: ${Bullet_DIR}/BulletConfig.cmake is not the float build")
  endif()
  haptel_import_bullet(haptel_bullet_float "" "${BULLET_ROOT_DIR}" "${BULLET_LIBRARY_DIRS}" "${BULLET_INCLUDE_DIRS}")

  add_library(haptel_physics_float STATIC ${HAPTEL_PHYSICS_SOURCES})
  target_include_directories(haptel_physics_float PUBLIC "${PROJECT_SOURCE_DIR}/physics/include")
  target_link_libraries(haptel_physics_float PUBLIC haptel_haptics haptel_config haptel_geometry haptel_core haptel_bullet_float
    PRIVATE haptel_warnings)

  add_executable(haptel-physics-bench-float
    ${CMAKE_CURRENT_SOURCE_DIR}/physics_float_main.cpp ${CMAKE_CURRENT_SOURCE_DIR}/physics_measure.cpp)
  # The test rigs as headers only: haptel_testing would link double Bullet.
  target_include_directories(haptel-physics-bench-float PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}
    ${PROJECT_SOURCE_DIR}/testing/include)
  target_link_libraries(haptel-physics-bench-float PRIVATE haptel_physics_float haptel_config haptel_core
    haptel_warnings)
endfunction()
haptel_add_physics_float_bench()
# `haptel bench physics` runs it: build it along with the benches.
add_dependencies(haptel_bench haptel-physics-bench-float)
