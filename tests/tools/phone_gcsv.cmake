# rsd-extract on a video with gyroflow's .gcsv sidecar (formats/gcsv.hpp): the phone recording's
# gyro written as a .gcsv (phone_gcsv.sh: times from the video's first frame, 4328043.690897 s on
# the phone's clock, in microseconds; rates in 1e-4 rad/s; the source's 33.312 ms readout), with
# a nominal model that states the camera only. The frames' times are the AVI's (30 fps from 0),
# the gyro the log's scaled back, the line delay the log's readout over 600 rows.
set(PHONE_GCSV ${CMAKE_BINARY_DIR}/phone-gcsv)
set(PHONE_DATA ${PROJECT_SOURCE_DIR}/tests/data/real/phone-cc9)
file(MAKE_DIRECTORY ${PHONE_GCSV})
file(WRITE ${PHONE_GCSV}/camera.yaml
     "camera: {width: 800, height: 600, fx: 573.8534, fy: 575.0448, cx: 406.0101, cy: 309.0112, distortion: [0, 0, 0, 0]}\n")
add_test(NAME cli_extract_gcsv_prepare
         COMMAND sh ${CMAKE_CURRENT_SOURCE_DIR}/phone_gcsv.sh ${PHONE_DATA}/gyro.txt 4328043.690897 ${PHONE_GCSV}/video.gcsv)
set_tests_properties(cli_extract_gcsv_prepare PROPERTIES FIXTURES_SETUP phone_gcsv LABELS cli)
rsd_cli_test(cli_extract_gcsv STATUS 0 LABELS cli
             MESSAGES "103 frames at 800x600 from ${PHONE_DATA}/video.avi, 2225 gyro samples from ${PHONE_GCSV}/video.gcsv (id 'phone-cc9', orientation 'XYZ'"
                      "line delay 5.552e-05 s from the log's metadata (line_delay_ns, or a .gcsv's frame_readout_time)"
                      "wrote an images recording (103 of 103 frames"
             COMMAND $<TARGET_FILE:rsd-extract> ${PHONE_DATA}/video.avi ${PHONE_GCSV}/rec --gcsv ${PHONE_GCSV}/video.gcsv
                     --nominal ${PHONE_GCSV}/camera.yaml)
set_tests_properties(cli_extract_gcsv PROPERTIES FIXTURES_REQUIRED phone_gcsv FIXTURES_SETUP phone_gcsv_rec)
# Frame 0 at 0 and frame 102 at 3.4 s (30 fps); the first gyro sample 0.998282 s before it, as
# gyro.txt's first line (4328042.692615 s, 0.311849 -0.399041 -0.018819 rad/s) rounded to 1e-4.
add_test(NAME cli_extract_gcsv_files
         COMMAND sh -c "r=\"$0/rec\"; sed -n 2p \"$r/frames.csv\" | grep -q '^0,0$' && sed -n 104p \"$r/frames.csv\" | grep -q '^102,3.4$' && sed -n 2p \"$r/gyro.csv\" | grep -q '^-0.998282,0.3118,-0.399,-0.0188$' && grep -q 'line_delay_s: 5.552' \"$r/recording.yaml\" && grep -q 'readout: top_to_bottom' \"$r/recording.yaml\""
                 ${PHONE_GCSV})
set_tests_properties(cli_extract_gcsv_files PROPERTIES FIXTURES_REQUIRED phone_gcsv_rec LABELS cli)
rsd_cli_test(cli_extract_gcsv_not_a_log STATUS 1 LABELS cli
             MESSAGES "${PHONE_DATA}/gyro.txt:1: not a gyroflow .gcsv log"
             COMMAND $<TARGET_FILE:rsd-extract> ${PHONE_DATA}/video.avi ${PHONE_GCSV}/bad --gcsv ${PHONE_DATA}/gyro.txt
                     --nominal ${PHONE_GCSV}/camera.yaml)
rsd_cli_test(cli_extract_gcsv_and_csv STATUS 2 LABELS cli MESSAGES "--gcsv is the video's gyro: not with --gyro-csv or --frame-times"
             COMMAND $<TARGET_FILE:rsd-extract> ${PHONE_DATA}/video.avi ${PHONE_GCSV}/both --gcsv ${PHONE_DATA}/gyro.txt
                     --gyro-csv ${PHONE_DATA}/gyro.txt)
