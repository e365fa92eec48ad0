# rsd-applicability: the plot is written and is a non-trivial PNG; the JSON against the
# closed form; bad input fails with exit status 2 naming the option.
# The plot solves the rolling-shutter constraint some 10^6 times (1.8 s here, 37 s under
# ASan+UBSan, the sanitizer tree's longest test): the normal tree only. The sanitizer trees run
# the same solver in test_applicability and test_rs_projection, and the tool's other paths below.
if(NOT RSD_SANITIZE)
  set(png ${CMAKE_BINARY_DIR}/applicability.png)
  add_test(NAME cli_applicability_plot_clean COMMAND ${CMAKE_COMMAND} -E rm -f ${png})
  add_test(NAME cli_applicability_plot COMMAND rsd-applicability --plot ${png} --v 0,1,0 --depth 10)
  add_test(NAME cli_applicability_plot_file COMMAND sh ${CMAKE_CURRENT_SOURCE_DIR}/check_png.sh ${png} 20000)
  set_tests_properties(cli_applicability_plot_clean PROPERTIES FIXTURES_SETUP applicability_clean LABELS cli)
  set_tests_properties(cli_applicability_plot PROPERTIES FIXTURES_REQUIRED applicability_clean
                       FIXTURES_SETUP applicability_png LABELS cli)
  set_tests_properties(cli_applicability_plot_file PROPERTIES FIXTURES_REQUIRED applicability_png LABELS cli)
endif()
rsd_cli_test(cli_applicability_json STATUS 0 MESSAGES "\"max_correction_px\": 3.3496503"
             COMMAND $<TARGET_FILE:rsd-applicability> --json --v 0,1,0 --depth 10 --fy 500 --fx 500)
rsd_cli_test(cli_applicability_bad_vector STATUS 2 MESSAGES "--v: expected three"
             COMMAND $<TARGET_FILE:rsd-applicability> --v 1,2)
rsd_cli_test(cli_applicability_bad_depth STATUS 2 MESSAGES "--depth: expected a positive number"
             COMMAND $<TARGET_FILE:rsd-applicability> --v 0,1,0 --depth -1)
rsd_cli_test(cli_applicability_bad_fps STATUS 2 MESSAGES "--fps: expected a positive number"
             COMMAND $<TARGET_FILE:rsd-applicability> --fps 0)
