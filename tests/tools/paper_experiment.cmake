# rsd-paper-experiment with 2 trials per cell: a CSV row per cell and model (24 x 2 + header),
# a non-trivial PNG and an SVG; the result does not depend on how cells are spread over
# threads; --trials 0 is a bad argument (exit status 2).
set(out ${CMAKE_BINARY_DIR}/paper-experiment-smoke)
add_test(NAME cli_paper_experiment COMMAND rsd-paper-experiment --out ${out} --trials 2)
add_test(NAME cli_paper_experiment_files
         COMMAND sh -c "test $(wc -l < \"$0/paper-experiment.csv\") -eq 49 && sh \"$1\" \"$0/paper-experiment.png\" 50000 && test -s \"$0/paper-experiment.svg\""
                 ${out} ${CMAKE_CURRENT_SOURCE_DIR}/check_png.sh)
add_test(NAME cli_paper_experiment_one_thread COMMAND rsd-paper-experiment --out ${out}-1 --trials 2 --threads 1)
add_test(NAME cli_paper_experiment_thread_independent
         COMMAND ${CMAKE_COMMAND} -E compare_files ${out}/paper-experiment.csv ${out}-1/paper-experiment.csv)
set_tests_properties(cli_paper_experiment PROPERTIES FIXTURES_SETUP paper_experiment_out LABELS cli)
set_tests_properties(cli_paper_experiment_one_thread PROPERTIES FIXTURES_SETUP paper_experiment_out_1 LABELS cli)
set_tests_properties(cli_paper_experiment_files PROPERTIES FIXTURES_REQUIRED paper_experiment_out LABELS cli)
set_tests_properties(cli_paper_experiment_thread_independent PROPERTIES
                     FIXTURES_REQUIRED "paper_experiment_out;paper_experiment_out_1" LABELS cli)
rsd_cli_test(cli_paper_experiment_bad_trials STATUS 2 MESSAGES "--trials"
             COMMAND $<TARGET_FILE:rsd-paper-experiment> --out ${CMAKE_BINARY_DIR} --trials 0)
