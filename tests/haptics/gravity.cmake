# Gravity compensation: grid file, interpolation and fade, the sampler on the
# sim device, and the drift the sampled grid removes (with the bench's helpers).
haptel_add_test(test_gravity SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_gravity.cpp LIBS haptel_haptics haptel_bench)
