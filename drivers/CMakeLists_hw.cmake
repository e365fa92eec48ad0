# Hardware camera sources that build on any machine and say "no camera" where there is none:
# V4L2 (kernel headers only) and libcamera 0.0.3 (Debian: libcamera-dev). Their
# device-independent logic is unit-tested here through fake devices.
pkg_check_modules(LIBCAMERA REQUIRED IMPORTED_TARGET libcamera)

add_library(rsd_drivers_hw STATIC
  ${CMAKE_CURRENT_LIST_DIR}/v4l2_logic.cpp
  ${CMAKE_CURRENT_LIST_DIR}/v4l2_source.cpp
  ${CMAKE_CURRENT_LIST_DIR}/libcamera_logic.cpp
  ${CMAKE_CURRENT_LIST_DIR}/libcamera_source.cpp
)
target_include_directories(rsd_drivers_hw PUBLIC ${PROJECT_SOURCE_DIR})
# libcamera is public: libcamera_logic.hpp speaks its pixel formats and stream roles.
target_link_libraries(rsd_drivers_hw PUBLIC rsd_dsp PkgConfig::LIBCAMERA Threads::Threads)

include(GoogleTest)
foreach(test_name test_v4l2_logic test_libcamera_logic)
  add_executable(${test_name} ${PROJECT_SOURCE_DIR}/tests/${test_name}.cpp)
  target_link_libraries(${test_name} PRIVATE rsd_drivers_hw GTest::gtest GTest::gtest_main)
  # The live "no camera" tests must end quickly even if a camera stack misbehaves.
  gtest_discover_tests(${test_name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 60)
endforeach()
