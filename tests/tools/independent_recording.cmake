# rsd-diagnose on recordings written from the recording format's text alone by
# independent_recording.py (plain Python, none of rsd's code: rsd's own simulator agrees with its
# model by construction). Label e2e: a pinhole phone whose gyro sits 2 degrees off a permutation
# of the camera's axes, with a readout the nominal model lacks, a 15 ms clock offset and a gyro
# bias; a fisheye (equidistant) action camera with a -30 ms offset and a bias: the named set the
# truth, its values within the benchmark's goals, the remainder noise, the gyro's axes the given
# ones. Label slow (the complete suite): a hand-held phone under parallax past points at many
# depths (five effects named, the remainder in translation), a video stabilised by another
# smoothing than rsd's (nothing named, the remainder in stabilisation) and a drone's forward
# flight past points 20-200 m away with a pan (the clock offset within 0.5 ms, no gyro bias
# beyond the goal: each match's depth its own). The script's exit status
# is the verdict; it prints each goal that does not hold.
foreach(case pinhole fisheye phone-parallax stabilised drone)
  add_test(NAME cli_diagnose_independent_${case}
           COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case ${case}
                   --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-recording)
  if(case MATCHES "^(pinhole|fisheye)$")
    set_tests_properties(cli_diagnose_independent_${case} PROPERTIES LABELS e2e TIMEOUT 300)
  else()
    set_tests_properties(cli_diagnose_independent_${case} PROPERTIES LABELS slow TIMEOUT 600)
  endif()
endforeach()
# The drone on its fifth seed, which named a focal length of 550.9 px for 540 beside the clock
# offset: 1.5 of its standard errors from the nominal, which a value must clear by 3 to be named.
add_test(NAME cli_diagnose_independent_drone_seed5
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --seed 5
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-recording-seed5)
set_tests_properties(cli_diagnose_independent_drone_seed5 PROPERTIES LABELS slow TIMEOUT 600)
# A variant (--set): an unknown key is refused with the case's keys (exit 2); a known one is
# written (60 fps over half a second: 30 frames, the recording's frame rate 60).
add_test(NAME cli_independent_recording_variant_bad_key
         COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/expect.sh 2 "--set fpss=60: no key 'fpss' in case drone" "fps, fwd"
                 -- python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --set fpss=60
                 --write-only --work ${CMAKE_BINARY_DIR}/independent-recording-variant)
add_test(NAME cli_independent_recording_variant_fps
         COMMAND sh -c "python3 \"$0\" --case pinhole --set fps=60 --set duration=0.5 --write-only --work \"$1\" &&
                        grep -qx '  frame_rate_hz: 60' \"$1/recording-pinhole/recording.yaml\" &&
                        test \"$(wc -l < \"$1/recording-pinhole/frames.csv\")\" -eq 31"
                 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py ${CMAKE_BINARY_DIR}/independent-recording-variant)
set_tests_properties(cli_independent_recording_variant_bad_key cli_independent_recording_variant_fps PROPERTIES LABELS cli)
# The drone's gimbal three times steadier (the rotation nearly all in the pan) on seed 6: the
# clock offset is named 6.8 ms from the truth, and the sigma the report states must cover that
# (within three of it: the profile's distance, docs/diagnosis.md, "Remaining"), goals aside.
add_test(NAME cli_diagnose_independent_drone_steady_gimbal
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --seed 6 --set rate=0.01
                 --set goals=false --set "honest=[\"time_offset_s\"]"
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-recording-steady-gimbal)
set_tests_properties(cli_diagnose_independent_drone_steady_gimbal PROPERTIES LABELS slow TIMEOUT 600)
# The steady gimbal on seed 2: the offset the fit found predicted the held-out frames worse with
# the parallax in (1.6602 -> 1.6623 px, as did the true offset: 1.663), and nothing was named.
# The held-out comparison takes each held-out pair's translation out (0.525 -> 0.503 px, 5.2
# standard errors better): the offset is named, within three of its stated sigmas.
add_test(NAME cli_diagnose_independent_drone_steady_gimbal_seed2
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --seed 2 --set rate=0.01
                 --set goals=false --set "honest=[\"time_offset_s\"]"
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-recording-steady-gimbal-seed2)
set_tests_properties(cli_diagnose_independent_drone_steady_gimbal_seed2 PROPERTIES LABELS slow TIMEOUT 600)
# The drone at 60 fps on seed 7, where a pair's translation moves the median match by about one
# noise: the own depths cut at a point at infinity (e >= -1) left what the noise carried past it
# pointing towards the focus of expansion, and the offset was named 11.1 ms early at a sigma of
# 1.0 ms. As far either way ([-3, 3], dsp/diagnosis/own_depth.hpp) it is 2.8 ms early, within
# three of its stated sigmas, goals aside (the 60 fps flight's bias: docs/diagnosis.md,
# "Remaining").
add_test(NAME cli_diagnose_independent_drone_60fps_seed7
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --seed 7 --set fps=60
                 --set goals=false --set "honest=[\"time_offset_s\"]"
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-recording-60fps-seed7)
set_tests_properties(cli_diagnose_independent_drone_60fps_seed7 PROPERTIES LABELS slow TIMEOUT 600)
# The drone at 60 fps on seed 4: the own depths' Gaussian prior about the plane leaves the offset
# 3.5 ms early at a fit's sigma of 0.79 ms (4.4 sigmas). With the scene as one plane the named
# effects put it 0.9 ms early; the stated sigma holds that distance too (docs/diagnosis.md,
# Method step 10, "Uncertainties under it"), and the named value lies within three of it.
add_test(NAME cli_diagnose_independent_drone_60fps_seed4
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --seed 4 --set fps=60
                 --set goals=false --set "honest=[\"time_offset_s\"]"
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-recording-60fps-seed4)
set_tests_properties(cli_diagnose_independent_drone_60fps_seed4 PROPERTIES LABELS slow TIMEOUT 600)
# Seed 1 at 60 fps takes the plane (its median match moves 0.98 noises, under the own depths'
# rule of one) and names the offset 1.95 ms late at a fit's sigma of 0.69 ms (2.8 sigmas). The
# stated sigma holds how far the offset moves with own depths (the other depth model's distance,
# either way: 1.91 ms): the named value within two of it, goals aside.
add_test(NAME cli_diagnose_independent_drone_60fps_seed1
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --seed 1 --set fps=60
                 --set goals=false --set "honest=[\"time_offset_s\"]" --set honest_within=2
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-recording-60fps-seed1)
set_tests_properties(cli_diagnose_independent_drone_60fps_seed1 PROPERTIES LABELS slow TIMEOUT 600)
# The tracker and the diagnosis on pictures rsd did not draw: the pinhole case's rig rendered
# (independent_pictures.py: a texture at infinity, each row at its own read time) at 640 x 360
# over 3 s, its readout 18 ms as the case's, tracked by rsd-diagnose; rsd-extract's matches of
# the same pictures held against the rig's truth (TRACKER_GOALS). Before the instrument's own
# bias bounded parallax and the remainder (dsp/diagnosis/instrument.hpp), the tracker's field of
# 0.02 px was taken for a near scene and the gyro bias went unnamed (measured over 5 s; 3 s keep
# the complete suite inside its budget, and every goal holds as at 5 s).
add_test(NAME cli_diagnose_independent_pictures_pinhole
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case pinhole --pictures
                 --set width=640 --set height=360 --set f=500 --set line_delay=5e-5 --set duration=3
                 --rsd-extract $<TARGET_FILE:rsd-extract>
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-pictures)
set_tests_properties(cli_diagnose_independent_pictures_pinhole PROPERTIES LABELS slow TIMEOUT 600)
# The fisheye's pictures (the cube's back faces past 90 degrees) at 640 x 480 over 3 s, the
# readout unknown to the nominal model and a bias twice the case's (the case's moves the
# predictions by 0.023 px at this size, under the instrument's own bias: rightly not named).
add_test(NAME cli_diagnose_independent_pictures_fisheye
         COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case fisheye --pictures --seed 2
                 --set width=640 --set height=480 --set f=210 --set line_delay=4e-5 --set nominal_line_delay=0
                 --set duration=3 --set "bias=[0.01,0.012,-0.009]"
                 --set "expect=[\"time_offset\",\"gyro_bias\",\"rolling_shutter\"]" --rsd-extract $<TARGET_FILE:rsd-extract>
                 --rsd-diagnose $<TARGET_FILE:rsd-diagnose> --work ${CMAKE_BINARY_DIR}/independent-pictures-fisheye)
set_tests_properties(cli_diagnose_independent_pictures_fisheye PROPERTIES LABELS slow TIMEOUT 600)
add_test(NAME cli_independent_recording_pictures_refuse_depths
         COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/expect.sh 2 "--case drone: pictures render a scene at infinity"
                 -- python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case drone --pictures
                 --write-only --work ${CMAKE_BINARY_DIR}/independent-recording-variant)
add_test(NAME cli_independent_recording_extract_needs_pictures
         COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/expect.sh 2 "--rsd-extract tracks pictures: it needs --pictures"
                 -- python3 ${CMAKE_CURRENT_SOURCE_DIR}/independent_recording.py --case pinhole --rsd-extract /bin/true
                 --write-only --work ${CMAKE_BINARY_DIR}/independent-recording-variant)
set_tests_properties(cli_independent_recording_pictures_refuse_depths cli_independent_recording_extract_needs_pictures
                     PROPERTIES LABELS cli)
