# The Aravis (GigE Vision) camera source and its tests. Included from drivers/CMakeLists.txt.
# Debian packages: libaravis-dev (with libusb-1.0-0-dev, which its pkg-config file requires),
# aravis-tools (arv-fake-gv-camera-0.8 for the GigE tests), util-linux (unshare), iproute2.
pkg_check_modules(ARAVIS REQUIRED IMPORTED_TARGET aravis-0.8)

add_library(rsd_drivers_aravis STATIC
  ${CMAKE_CURRENT_LIST_DIR}/aravis_source.cpp
  ${CMAKE_CURRENT_LIST_DIR}/aravis_timestamps.cpp)
target_include_directories(rsd_drivers_aravis PUBLIC ${PROJECT_SOURCE_DIR})
target_link_libraries(rsd_drivers_aravis PUBLIC rsd_dsp PRIVATE PkgConfig::ARAVIS)

include(GoogleTest)

# Stamp mapping, frame counter: synthetic stamp sequences with known offset, drift, jitter.
add_executable(test_aravis_timestamps ${PROJECT_SOURCE_DIR}/tests/test_aravis_timestamps.cpp)
target_link_libraries(test_aravis_timestamps PRIVATE rsd_drivers_aravis GTest::gtest GTest::gtest_main)
gtest_discover_tests(test_aravis_timestamps DISCOVERY_TIMEOUT 60)

# End to end. AravisFake.*: Aravis' in-process fake camera, no network. AravisGigE.*: the
# real GigE Vision fake camera (arv-fake-gv-camera-0.8) on 127.0.0.1, only ever inside a
# private network namespace of its own (tests/run_in_netns.sh), so that nothing it or
# Aravis sends leaves loopback and no other session's camera on 127.0.0.1 answers.
add_executable(test_aravis_fake ${PROJECT_SOURCE_DIR}/tests/test_aravis_fake.cpp)
target_link_libraries(test_aravis_fake PRIVATE rsd_drivers_aravis PkgConfig::ARAVIS GTest::gtest GTest::gtest_main)
gtest_discover_tests(test_aravis_fake DISCOVERY_TIMEOUT 60 TEST_FILTER "AravisFake.*")
add_test(NAME aravis_gige_in_netns
         COMMAND sh ${PROJECT_SOURCE_DIR}/tests/run_in_netns.sh
                 $<TARGET_FILE:test_aravis_fake> --gtest_filter=AravisGigE.*)
# A skipped GigE test (run outside a private network namespace) is a failure here.
set_tests_properties(aravis_gige_in_netns PROPERTIES TIMEOUT 180
                     FAIL_REGULAR_EXPRESSION "\\[  SKIPPED \\]")

# The daemon's pipeline behind Aravis: in-process fake camera, and the GigE fake in a netns.
add_executable(test_aravis_pipeline ${PROJECT_SOURCE_DIR}/tests/test_aravis_pipeline.cpp)
target_link_libraries(test_aravis_pipeline PRIVATE rsd_daemon rsd_drivers_aravis GTest::gtest GTest::gtest_main)
gtest_discover_tests(test_aravis_pipeline DISCOVERY_TIMEOUT 60 TEST_FILTER "AravisPipeline.*")
add_test(NAME aravis_gige_pipeline_in_netns
         COMMAND sh ${PROJECT_SOURCE_DIR}/tests/run_in_netns.sh
                 $<TARGET_FILE:test_aravis_pipeline> --gtest_filter=AravisPipelineGigE.*)
set_tests_properties(aravis_gige_pipeline_in_netns PROPERTIES TIMEOUT 180
                     FAIL_REGULAR_EXPRESSION "\\[  SKIPPED \\]")
