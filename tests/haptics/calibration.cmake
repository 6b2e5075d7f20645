# Calibration: fitting maths, the procedure on the sim device, the calibration file.
haptel_add_test(test_calibration SOURCES test_calibration.cpp test_calibration_file.cpp LIBS haptel_calibration)
