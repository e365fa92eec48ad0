# rsd-extract on a real GoPro clip (tests/data/real/gpmf/karma.mp4, the Karma drone's gimbal
# camera): an images recording whose pictures stay in the clip, the frames the gyro covers, the
# gyro from its GPMF track, on the axes GoPro documents for the HERO5 its firmware names. A file that
# looks like an MP4 but is not one is refused naming it.
set(GOPRO ${CMAKE_BINARY_DIR}/gopro)
file(MAKE_DIRECTORY ${GOPRO})
file(WRITE ${GOPRO}/nominal.yaml
     "camera: {width: 854, height: 480, fx: 400, fy: 400, cx: 426.5, cy: 239.5, model: pinhole-equi, distortion: [0, 0, 0, 0]}\n")
rsd_cli_test(cli_extract_gopro STATUS 0 LABELS cli
             MESSAGES "362 frames at 854x480, 4795 gyro samples in 13 GPMF payloads (Camera, ORIN '', firmware 'HD5.02.02.00.00')"
                      "the gyro's axes in the camera: ZXY from the order GoPro documents for the HERO5 Black (firmware HD5.02.02.00.00), imu_to_camera 0,-1,0,-1,0,0,0,0,-1"
                      "wrote an images recording (358 of 362 frames, the pictures in ${PROJECT_SOURCE_DIR}/tests/data/real/gpmf/karma.mp4; 4795 gyro samples)"
             COMMAND $<TARGET_FILE:rsd-extract> ${PROJECT_SOURCE_DIR}/tests/data/real/gpmf/karma.mp4 ${GOPRO}/karma
                     --nominal ${GOPRO}/nominal.yaml)
set_tests_properties(cli_extract_gopro PROPERTIES FIXTURES_SETUP gopro_rec)
add_test(NAME cli_extract_gopro_files
         COMMAND sh -c "r=\"$0/karma\"; grep -q '^  video: .*tests/data/real/gpmf/karma.mp4$' \"$r/recording.yaml\" && grep -q 'model: pinhole-equi' \"$r/recording.yaml\" && test $(wc -l < \"$r/frames.csv\") -eq 359 && test $(wc -l < \"$r/gyro.csv\") -eq 4796 && sed -n 2p \"$r/frames.csv\" | grep -q '^2,0.0667'"
                 ${GOPRO})
set_tests_properties(cli_extract_gopro_files PROPERTIES FIXTURES_REQUIRED gopro_rec LABELS cli)
file(WRITE ${GOPRO}/fake.mp4 "xxxxftypisom, but nothing an MP4 holds after it")
rsd_cli_test(cli_extract_gopro_not_an_mp4 STATUS 1 LABELS cli MESSAGES "fake.mp4: cannot open as an MP4: "
             COMMAND $<TARGET_FILE:rsd-extract> ${GOPRO}/fake.mp4 ${GOPRO}/fake --nominal ${GOPRO}/nominal.yaml)
