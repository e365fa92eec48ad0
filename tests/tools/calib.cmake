# rsd-calib led: synthetic LED captures written at test time by rsd-calib synth-led (timing
# known exactly), calibrated through the CLI; bad input fails naming the file.
set(LED ${CMAKE_BINARY_DIR}/led_captures)
set(calib $<TARGET_FILE:rsd-calib>)
add_test(NAME cli_led_synth_d0
         COMMAND rsd-calib synth-led --out ${LED}/d0 --fps 7.5 --freq 20 --frames 8 --width 64
                 --exposure 0.005 --vignetting 0.4 --noise 2)
add_test(NAME cli_led_synth_blanking
         COMMAND rsd-calib synth-led --out ${LED}/blanking --fps 7.5 --freq 50 --frames 8 --width 64
                 --readout-fraction 0.8 --exposure 0.002 --noise 2)
add_test(NAME cli_led_synth_small_and_flat
         COMMAND sh -c "\"$0\" synth-led --out \"$1/small\" --frames 1 --width 32 --height 200 && \"$0\" synth-led --out \"$1/flat\" --frames 3 --width 32 --dark 0.3 --bright 0.3"
                 ${calib} ${LED})
set_tests_properties(cli_led_synth_d0 PROPERTIES FIXTURES_SETUP led_d0 LABELS cli)
set_tests_properties(cli_led_synth_blanking PROPERTIES FIXTURES_SETUP led_blanking LABELS cli)
set_tests_properties(cli_led_synth_small_and_flat PROPERTIES FIXTURES_SETUP led_other LABELS cli)

# JSON has exactly the five keys; line delay within 1% of 1/(240 x 7.5) s; d = 0 within 1% of
# the frame period; a positive uncertainty below 1%.
add_test(NAME cli_led_json_d0
         COMMAND sh -c "out=$(\"$0\" led --json --freq 20 --fps 7.5 \"$1\") || exit 1; echo \"$out\"; test $(echo \"$out\" | grep -c '\": ') -eq 5 || exit 1; echo \"$out\" | awk -F': ' '/line_delay_s/ {d = $2 + 0} /blanking_s/ {b = $2 + 0} /uncertainty_s/ {u = $2 + 0} END {t = 1 / (240 * 7.5); exit !(d > 0.99 * t && d < 1.01 * t && b > -0.00133 && b < 0.00133 && u > 0 && u < 0.01 * t)}'"
                 ${calib} ${LED}/d0)
set_tests_properties(cli_led_json_d0 PROPERTIES FIXTURES_REQUIRED led_d0 LABELS cli)
# Readout 80% of the frame period: d = 0.2 / 7.5 s within 1% of the period, line delay within 1%.
add_test(NAME cli_led_json_blanking
         COMMAND sh -c "out=$(\"$0\" led --json --freq 50 --fps 7.5 \"$1\") || exit 1; echo \"$out\"; echo \"$out\" | awk -F': ' '/line_delay_s/ {d = $2 + 0} /blanking_s/ {b = $2 + 0} END {t = 0.8 / (240 * 7.5); exit !(d > 0.99 * t && d < 1.01 * t && b > 0.02533 && b < 0.02800)}'"
                 ${calib} ${LED}/blanking)
set_tests_properties(cli_led_json_blanking PROPERTIES FIXTURES_REQUIRED led_blanking LABELS cli)
add_test(NAME cli_led_text_d0 COMMAND rsd-calib led --freq 20 --fps 7.5 ${LED}/d0)
set_tests_properties(cli_led_text_d0 PROPERTIES FIXTURES_REQUIRED led_d0 LABELS cli
                     PASS_REGULAR_EXPRESSION "Line delay +55[5-6]\\.[0-9]+ \\+- .*Verdict on d +d = 0 within uncertainty")
add_test(NAME cli_led_text_blanking COMMAND rsd-calib led --freq 50 --fps 7.5 ${LED}/blanking)
set_tests_properties(cli_led_text_blanking PROPERTIES FIXTURES_REQUIRED led_blanking LABELS cli
                     PASS_REGULAR_EXPRESSION "d > 0: the readout takes (79\\.[5-9]|80(\\.[0-4])?)[0-9]*% of the frame period")
# A single frame, no frame rate: fitted alone, still within 1% (550 to 561 us).
add_test(NAME cli_led_single_frame COMMAND rsd-calib led --freq 20 ${LED}/d0/frame_0003.png)
set_tests_properties(cli_led_single_frame PROPERTIES FIXTURES_REQUIRED led_d0 LABELS cli
                     PASS_REGULAR_EXPRESSION "1 frame of 64 x 240.*frame by frame.*Line delay +(55[0-9]|560)\\.[0-9]+ \\+- ")

# Bad input: exit status 1 (bad data) or 2 (bad arguments), naming the file or option.
add_test(NAME cli_led_unreadable_image_prepare
         COMMAND sh -c "mkdir -p \"$0/bad\" && cp \"$0/d0/frame_0000.png\" \"$0/bad/frame_0.png\" && printf garbage > \"$0/bad/frame_1.png\"" ${LED})
set_tests_properties(cli_led_unreadable_image_prepare PROPERTIES FIXTURES_REQUIRED led_d0 FIXTURES_SETUP led_bad LABELS cli)
rsd_cli_test(cli_led_unreadable_image_named STATUS 1 MESSAGES "bad/frame_1.png: neither PNG nor binary PGM"
             COMMAND ${calib} led --freq 20 ${LED}/bad)
set_tests_properties(cli_led_unreadable_image_named PROPERTIES FIXTURES_REQUIRED led_bad)
rsd_cli_test(cli_led_mismatched_sizes_named STATUS 1 MESSAGES "small/frame_0000.png: frame is 32 x 200, the first was 64 x 240"
             COMMAND ${calib} led --freq 20 ${LED}/d0/frame_0000.png ${LED}/small/frame_0000.png)
set_tests_properties(cli_led_mismatched_sizes_named PROPERTIES FIXTURES_REQUIRED "led_d0;led_other")
rsd_cli_test(cli_led_flat_image STATUS 1 MESSAGES "flat (3 frames): no LED modulation found"
             COMMAND ${calib} led --freq 20 --fps 7.5 ${LED}/flat)
set_tests_properties(cli_led_flat_image PROPERTIES FIXTURES_REQUIRED led_other)
rsd_cli_test(cli_led_bad_freq STATUS 2 MESSAGES "--freq: expected a positive number"
             COMMAND ${calib} led --freq -5 ${PROJECT_SOURCE_DIR})
rsd_cli_test(cli_led_missing_input STATUS 2 MESSAGES "INPUT: '${LED}/none' does not exist"
             COMMAND ${calib} led --freq 20 ${LED}/none)

# --write-calibration: the line delay within 1% of 1/(240 x 7.5) s, with its sigma; into a copy
# of the camera's calibration (intrinsics kept) when one is given, refused when its resolution
# is not the frames'.
file(WRITE ${CMAKE_BINARY_DIR}/led-camera.yaml
"cam0:\n  camera_model: pinhole\n  intrinsics: [71, 72, 31.5, 119.5]\n  distortion_model: radtan\n  distortion_coeffs: [0.1, 0, 0, 0]\n  resolution: [64, 240]\n")
file(WRITE ${CMAKE_BINARY_DIR}/led-other-camera.yaml
"cam0:\n  camera_model: pinhole\n  intrinsics: [71, 72, 31.5, 119.5]\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\n")
rsd_cli_test(cli_led_write_calibration STATUS 0 MESSAGES "Line delay"
             COMMAND ${calib} led --freq 20 --fps 7.5 ${LED}/d0 --write-calibration ${LED}/cal.yaml
                     --calibration ${CMAKE_BINARY_DIR}/led-camera.yaml)
set_tests_properties(cli_led_write_calibration PROPERTIES FIXTURES_REQUIRED led_d0 FIXTURES_SETUP led_cal)
add_test(NAME cli_led_write_calibration_file
         COMMAND sh -c "c=\"$0\"; cat \"$c\"; grep -q 'format: rsd-calibration/1' \"$c\" && grep -q 'intrinsics: \\[71, 72, 31.5, 119.5\\]' \"$c\" && grep -q 'distortion_coeffs: \\[0.1, 0, 0, 0\\]' \"$c\" && grep -A1 '^    sigma:' \"$c\" | grep -q 'line_delay_s: [0-9]' && grep -m1 '^    line_delay_s:' \"$c\" | awk '{d = $2 + 0} END {t = 1 / (240 * 7.5); exit !(d > 0.99 * t && d < 1.01 * t)}'"
                 ${LED}/cal.yaml)
set_tests_properties(cli_led_write_calibration_file PROPERTIES FIXTURES_REQUIRED led_cal LABELS cli)
rsd_cli_test(cli_led_write_calibration_wrong_camera STATUS 1
             MESSAGES "led-other-camera.yaml: 'cam0.resolution' is [640, 480], but the camera delivers 64x240"
             COMMAND ${calib} led --freq 20 --fps 7.5 ${LED}/d0 --write-calibration ${LED}/cal-wrong.yaml
                     --calibration ${CMAKE_BINARY_DIR}/led-other-camera.yaml)
set_tests_properties(cli_led_write_calibration_wrong_camera PROPERTIES FIXTURES_REQUIRED led_d0)

# rsd-calib import-lens: a gyroflow profile (its layout, made-up numbers) at half its calibrated
# resolution: K scaled about the pixel grid's edge, the readout over the rows.
set(LENS_DIR ${CMAKE_BINARY_DIR}/import-lens)
file(MAKE_DIRECTORY ${LENS_DIR})
file(WRITE ${LENS_DIR}/profile.json
"{\"name\": \"Test fisheye\", \"calib_dimension\": {\"w\": 1920, \"h\": 1080}, \"frame_readout_time\": 21.6,
 \"use_opencv_fisheye\": true, \"fisheye_params\": {\"RMS_error\": 0.5, \"camera_matrix\": [[1000, 0, 959.5], [0, 1000, 539.5], [0, 0, 1]],
 \"distortion_coeffs\": [0.05, -0.01, 0.002, -0.0003], \"radial_distortion_limit\": null}}\n")
file(WRITE ${LENS_DIR}/anamorphic.json
"{\"calib_dimension\": {\"w\": 1920, \"h\": 1080}, \"input_horizontal_stretch\": 1.33,
 \"fisheye_params\": {\"camera_matrix\": [[1000, 0, 959.5], [0, 1000, 539.5], [0, 0, 1]], \"distortion_coeffs\": [0, 0, 0, 0]}}\n")
rsd_cli_test(cli_import_lens STATUS 0 MESSAGES "Wrote ${LENS_DIR}/cal.yaml: Test fisheye at 960x540" "fx 500.00, fy 500.00, cx 479.50, cy 269.50"
                                             "pinhole-equi k1..k4 0.05, -0.01, 0.002, -0.0003" "frame readout 21.6 ms over 540 rows"
             COMMAND ${calib} import-lens ${LENS_DIR}/profile.json --width 960 --height 540 -o ${LENS_DIR}/cal.yaml)
set_tests_properties(cli_import_lens PROPERTIES FIXTURES_SETUP lens_cal)
add_test(NAME cli_import_lens_file
         COMMAND sh -c "c=\"$0\"; cat \"$c\"; grep -q 'format: rsd-calibration/1' \"$c\" && grep -q 'distortion_model: equidistant' \"$c\" && grep -q 'distortion_coeffs: \\[0.05, -0.01, 0.002, -3e-04\\]' \"$c\" && grep -q 'intrinsics: \\[500, 500, 479.5, 269.5\\]' \"$c\" && grep -q 'resolution: \\[960, 540\\]' \"$c\" && grep -m1 '^    line_delay_s:' \"$c\" | awk '{d = $2 + 0} END {exit !(d > 0.9999999e-4 * 0.4 && d < 1.0000001e-4 * 0.4)}'"
                 ${LENS_DIR}/cal.yaml)
set_tests_properties(cli_import_lens_file PROPERTIES FIXTURES_REQUIRED lens_cal LABELS cli)
rsd_cli_test(cli_import_lens_other_aspect STATUS 1
             MESSAGES "profile.json: 'calib_dimension' is 1920x1080, another aspect ratio than 960x720"
             COMMAND ${calib} import-lens ${LENS_DIR}/profile.json --width 960 --height 720 -o ${LENS_DIR}/cal-4by3.yaml)
rsd_cli_test(cli_import_lens_anamorphic STATUS 1 MESSAGES "anamorphic.json:1:"
             "'input_horizontal_stretch' is not 1: an anamorphic (stretched) input is not rsd's camera model"
             COMMAND ${calib} import-lens ${LENS_DIR}/anamorphic.json --width 1920 --height 1080 -o ${LENS_DIR}/cal-a.yaml)
rsd_cli_test(cli_import_lens_missing_size STATUS 2 MESSAGES "--height is required"
             COMMAND ${calib} import-lens ${LENS_DIR}/profile.json --width 1920 -o ${LENS_DIR}/cal-b.yaml)
