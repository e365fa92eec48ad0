# rsd-extract on a real phone recording (tests/data/real/phone-cc9: a phone in a car, its video
# with the frames' times and its gyro as text): an images recording whose pictures stay in the
# video, frame k of the video at line 98 + k of framestamp.txt, the gyro as the phone wrote it
# (columns wx,wy,wz,t). The options' mistakes are refused naming them.
set(PHONE ${CMAKE_BINARY_DIR}/phone)
set(PHONE_DATA ${PROJECT_SOURCE_DIR}/tests/data/real/phone-cc9)
file(MAKE_DIRECTORY ${PHONE})
rsd_cli_test(cli_extract_phone STATUS 0 LABELS cli
             MESSAGES "103 frames at 800x600 (times from line 98 of ${PHONE_DATA}/framestamp.txt on), 2225 gyro samples"
                      "wrote an images recording (103 of 103 frames, the pictures in ${PHONE_DATA}/video.avi; 2225 gyro samples)"
             COMMAND $<TARGET_FILE:rsd-extract> ${PHONE_DATA}/video.avi ${PHONE}/rec --frame-times ${PHONE_DATA}/framestamp.txt
                     --gyro-csv ${PHONE_DATA}/gyro.txt --gyro-columns wx,wy,wz,t --first-frame-index 98
                     --nominal ${PHONE_DATA}/nominal.yaml --imu-to-camera 0,-1,0,-1,0,0,0,0,-1)
set_tests_properties(cli_extract_phone PROPERTIES FIXTURES_SETUP phone_rec)
# Frame 0 is framestamp.txt's 99th line (4328043.690897 s), the gyro's first sample its first line.
add_test(NAME cli_extract_phone_files
         COMMAND sh -c "r=\"$0/rec\"; grep -q '^  video: .*tests/data/real/phone-cc9/video.avi$' \"$r/recording.yaml\" && grep -q 'imu_to_camera: \\[0, -1, 0, -1, 0, 0, 0, 0, -1\\]' \"$r/recording.yaml\" && test $(wc -l < \"$r/frames.csv\") -eq 104 && test $(wc -l < \"$r/gyro.csv\") -eq 2226 && sed -n 2p \"$r/frames.csv\" | grep -q '^0,4328043.690897$' && sed -n 2p \"$r/gyro.csv\" | grep -q '^4328042.692615,0.311849,-0.399041,-0.018819$'"
                 ${PHONE})
set_tests_properties(cli_extract_phone_files PROPERTIES FIXTURES_REQUIRED phone_rec LABELS cli)
rsd_cli_test(cli_extract_phone_too_few_times STATUS 1 LABELS cli
             MESSAGES "video.avi: 103 frames, but ${PHONE_DATA}/framestamp.txt lists 2146 times, 2100 of them before the video's first frame (--first-frame-index)"
             COMMAND $<TARGET_FILE:rsd-extract> ${PHONE_DATA}/video.avi ${PHONE}/late --frame-times ${PHONE_DATA}/framestamp.txt
                     --gyro-csv ${PHONE_DATA}/gyro.txt --gyro-columns wx,wy,wz,t --first-frame-index 2100 --nominal ${PHONE_DATA}/nominal.yaml)
rsd_cli_test(cli_extract_phone_bad_columns STATUS 2 LABELS cli MESSAGES "--gyro-columns: 'gx' is not t, wx, wy, wz or -"
             COMMAND $<TARGET_FILE:rsd-extract> ${PHONE_DATA}/video.avi ${PHONE}/bad --frame-times ${PHONE_DATA}/framestamp.txt
                     --gyro-csv ${PHONE_DATA}/gyro.txt --gyro-columns gx,gy,gz,t)
rsd_cli_test(cli_extract_phone_times_alone STATUS 2 LABELS cli MESSAGES "--frame-times goes with --gyro-csv"
             COMMAND $<TARGET_FILE:rsd-extract> ${PHONE_DATA}/video.avi ${PHONE}/alone --frame-times ${PHONE_DATA}/framestamp.txt)
