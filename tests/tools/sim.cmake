# rsd-sim: every example scenario simulates and writes a recording (naming the effects the
# nominal model leaves out), which then reads back equal to the same simulation done
# in-process (test_sim_scenarios); a scenario with an unknown key fails naming file, line and
# key; the paper's figure 1 is drawn.
file(GLOB RSD_SCENARIOS ${PROJECT_SOURCE_DIR}/config/scenarios/*.yaml)
foreach(scenario ${RSD_SCENARIOS})
  get_filename_component(name ${scenario} NAME_WE)
  rsd_cli_test(cli_sim_recording_${name} STATUS 0 MESSAGES "effects the nominal model leaves out:"
               COMMAND $<TARGET_FILE:rsd-sim> recording ${scenario} ${CMAKE_BINARY_DIR}/sim/${name})
  set_tests_properties(cli_sim_recording_${name} PROPERTIES FIXTURES_SETUP sim_recordings)
endforeach()
add_executable(test_sim_scenarios test_sim_scenarios.cpp)
target_link_libraries(test_sim_scenarios PRIVATE rsd_formats_scenario GTest::gtest GTest::gtest_main)
rsd_test_compile(test_sim_scenarios)
target_compile_definitions(test_sim_scenarios PRIVATE RSD_SCENARIO_DIR="${PROJECT_SOURCE_DIR}/config/scenarios"
                           RSD_SIM_OUT="${CMAKE_BINARY_DIR}/sim")
gtest_discover_tests(test_sim_scenarios DISCOVERY_TIMEOUT 60
                     PROPERTIES LABELS cli FIXTURES_REQUIRED sim_recordings)

file(WRITE ${CMAKE_BINARY_DIR}/bad-scenario.yaml "camera: {width: 640, hieght: 480}\n")
rsd_cli_test(cli_sim_bad_scenario STATUS 1 MESSAGES "bad-scenario.yaml:1:22: unknown key 'camera.hieght'"
             COMMAND $<TARGET_FILE:rsd-sim> recording ${CMAKE_BINARY_DIR}/bad-scenario.yaml ${CMAKE_BINARY_DIR}/bad-scenario)
rsd_cli_test(cli_sim_figure1 STATUS 0 MESSAGES "figure1-one-rev-per-s.png"
             COMMAND $<TARGET_FILE:rsd-sim> figure1 ${CMAKE_BINARY_DIR}/figure1)
