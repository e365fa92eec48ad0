# Images recordings end to end (docs/replay.md): the simulated camera with hidden rig physics
# (IMU clock 12 ms ahead, gyro bias) recorded -> rsd-extract --images (PNG frames, gyro.csv)
# -> rsd --replay DIR --output-dir (every rectified frame, named by its frame number) ->
# rsd-extract DIR (matches made from the pictures) and rsd-diagnose DIR --write-calibration ->
# rsd --replay DIR --calibration CAL --output-video. Misuse is refused with a clear message.
set(IMG ${CMAKE_BINARY_DIR}/images-replay)
file(MAKE_DIRECTORY ${IMG})
file(WRITE ${IMG}/hidden.yaml
"source:\n  driver: sim\n  sim:\n    width: 160\n    height: 120\n    line_delay_s: 0.0002\n    velocity_m_s: [0, 0, 0]\n    angular_rate_rad_s: [0.4, 1.2, 0.6]\n    imu_time_offset_s: 0.012\n    gyro_bias_rad_s: [0.01, 0, 0]\n    velocity_rate_hz: 400\n    realtime: false\n")
file(WRITE ${IMG}/nominal.yaml
"camera: {width: 160, height: 120, fx: 138.564, fy: 138.564, cx: 79.5, cy: 59.5, distortion: [0, 0, 0, 0]}\ntiming: {frame_rate_hz: 30, line_delay_s: 0.0002, readout: top_to_bottom, time_offset_s: 0}\nmotion: {imu_to_camera: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n")
set(rsd_exe $<TARGET_FILE:rsd>)
set(extract $<TARGET_FILE:rsd-extract>)

add_test(NAME images_record COMMAND sh -c "rm -rf \"$1\"/pics \"$1\"/out \"$1\"/matches && \"$0\" -q -c \"$1/hidden.yaml\" --frames 30 --record \"$1/run.lcmlog\""
         ${rsd_exe} ${IMG})
set_tests_properties(images_record PROPERTIES FIXTURES_SETUP images_log LABELS e2e)
rsd_cli_test(images_extract_pictures STATUS 0 LABELS e2e MESSAGES "wrote an images recording (" "frames as PNG"
             COMMAND ${extract} ${IMG}/run.lcmlog ${IMG}/pics --nominal ${IMG}/nominal.yaml --images)
set_tests_properties(images_extract_pictures PROPERTIES FIXTURES_REQUIRED images_log FIXTURES_SETUP images_pics)

# Every frame comes out as OUT/<frame>.png, numbered as images.csv numbers it.
rsd_cli_test(images_replay_output_dir STATUS 0 LABELS e2e MESSAGES "frames from ${IMG}/pics" "drops 0" "rectified frames to ${IMG}/out/"
             COMMAND ${rsd_exe} --replay ${IMG}/pics --speed fast --output-dir ${IMG}/out)
set_tests_properties(images_replay_output_dir PROPERTIES FIXTURES_REQUIRED images_pics FIXTURES_SETUP images_out)
add_test(NAME images_replay_output_names
         COMMAND sh -c "cd \"$0\" && tail -n +2 pics/images.csv | while IFS=, read f file; do n=$(printf 'out/%06d.png' \"$f\"); sh \"$1\" \"$n\" 2000 || exit 1; done && test $(ls out | wc -l) -eq $(tail -n +2 pics/images.csv | wc -l)"
                 ${IMG} ${PROJECT_SOURCE_DIR}/tests/tools/check_png.sh)
set_tests_properties(images_replay_output_names PROPERTIES FIXTURES_REQUIRED images_out LABELS e2e)

rsd_cli_test(images_extract_matches STATUS 0 LABELS e2e MESSAGES "wrote a matches recording"
             COMMAND ${extract} ${IMG}/pics ${IMG}/matches)
set_tests_properties(images_extract_matches PROPERTIES FIXTURES_REQUIRED images_pics FIXTURES_SETUP images_matches)
rsd_cli_test(images_diagnose_calibration STATUS 0 LABELS e2e MESSAGES "wrote the calibration" "time_offset"
             COMMAND $<TARGET_FILE:rsd-diagnose> ${IMG}/pics --json ${IMG}/d.json --write-calibration ${IMG}/cal.yaml)
set_tests_properties(images_diagnose_calibration PROPERTIES FIXTURES_REQUIRED images_pics FIXTURES_SETUP images_cal TIMEOUT 300)
rsd_cli_test(images_replay_calibrated_video STATUS 0 LABELS e2e MESSAGES "frames from ${IMG}/pics" "drops 0" "rectified frames to ${IMG}/out.avi"
             COMMAND ${rsd_exe} --replay ${IMG}/pics --calibration ${IMG}/cal.yaml --speed fast --output-video ${IMG}/out.avi)
set_tests_properties(images_replay_calibrated_video PROPERTIES FIXTURES_REQUIRED images_cal)

# Misuse: files out of a live camera; a recording of observations played as pictures.
rsd_cli_test(images_output_needs_replay STATUS 2 MESSAGES "--output-dir and --output-video apply to replays"
             COMMAND ${rsd_exe} --output-dir ${IMG}/never)
rsd_cli_test(images_replay_observations_refused STATUS 2 MESSAGES "observations.kind is matches, not images"
             COMMAND ${rsd_exe} --replay ${IMG}/matches --speed fast)
set_tests_properties(images_replay_observations_refused PROPERTIES FIXTURES_REQUIRED images_matches LABELS e2e)
