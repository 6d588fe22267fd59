# ctest cli/exit_codes: the viosfm command's exit codes and error lines
# (docs/design.md, Failures): bad input and filesystem errors exit with 2
# and print "error: <path>...", never "internal error" (3).
#   cmake -DVIOSFM=<viosfm binary> -DWORK=<scratch folder> -P exit_codes_test.cmake
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
file(WRITE "${WORK}/a_file" "not a folder\n")

function(expect_exit code pattern)
  execute_process(COMMAND "${VIOSFM}" --log-level error ${ARGN}
                  RESULT_VARIABLE result ERROR_VARIABLE stderr OUTPUT_QUIET)
  if(NOT result EQUAL code)
    message(FATAL_ERROR "viosfm ${ARGN}: exit code ${result}, expected ${code}; stderr: ${stderr}")
  endif()
  if(NOT stderr MATCHES "${pattern}")
    message(FATAL_ERROR "viosfm ${ARGN}: stderr '${stderr}' does not match '${pattern}'")
  endif()
endfunction()

# A missing dataset: an input error naming the folder.
expect_exit(2 "^error: ${WORK}/absent: dataset folder not found" vio "${WORK}/absent" --out "${WORK}/out")
# An output folder below a regular file: a std::filesystem error, reported
# as bad input naming the path (it used to exit with 3, "internal error").
expect_exit(2 "^error: ${WORK}/a_file/sub[^ ]*: cannot create directories: Not a directory"
            simulate --duration 3 --no-images --out "${WORK}/a_file/sub")
# A minimal EuRoC dataset, then calibrations that do not exist or are bad:
# --calibration is read by the subcommands that read a dataset.
set(mav0 "${WORK}/dataset/mav0")
file(WRITE "${mav0}/cam0/data.csv" "#timestamp [ns],filename\n1000,a.png\n2000,b.png\n")
file(WRITE "${mav0}/cam0/data/a.png" "x")
file(WRITE "${mav0}/cam0/data/b.png" "x")
file(WRITE "${mav0}/cam0/sensor.yaml"
     "T_BS: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\nresolution: [640, 480]\n"
     "intrinsics: [500, 500, 320, 240]\n")
file(WRITE "${mav0}/imu0/sensor.yaml"
     "gyroscope_noise_density: 1e-4\ngyroscope_random_walk: 1e-5\n"
     "accelerometer_noise_density: 1e-3\naccelerometer_random_walk: 1e-3\n")
file(WRITE "${mav0}/imu0/data.csv" "500,0,0,0,0,0,9.81\n2500,0,0,0,0,0,9.81\n")
expect_exit(2 "^error: ${WORK}/absent.yaml: file does not exist" vio "${WORK}/dataset"
            --out "${WORK}/out" --calibration "${WORK}/absent.yaml")
file(WRITE "${WORK}/mirrored.yaml"
     "cam0:\n  T_cam_imu: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 0], [0, 0, 0, 1]]\n")
foreach(command vio run features)
  set(extra)
  if(command STREQUAL "features")
    set(extra --database "${WORK}/out_${command}/database.db")
  else()
    set(extra --out "${WORK}/out_${command}")
  endif()
  expect_exit(2 "^error: ${WORK}/mirrored.yaml:2: 'T_cam_imu': .*determinant is -1"
              ${command} "${WORK}/dataset" ${extra} --calibration "${WORK}/mirrored.yaml")
endforeach()
# A command line that cannot be parsed is a usage error: exit 2, naming the
# argument (CLI11's own codes, 106 and 109, were not the documented ones).
expect_exit(2 "^error: --out is required" run "${WORK}/dataset")
expect_exit(2 "^error: The following argument[s]? (was|were) not expected: --no-such-flag" run
            "${WORK}/dataset" --out "${WORK}/out_parse" --no-such-flag)
expect_exit(2 "^error: --first-octave: 5 not in" features "${WORK}/dataset" --database
            "${WORK}/parse.db" --first-octave 5)
if(EXISTS "${WORK}/out_parse" OR EXISTS "${WORK}/parse.db")
  message(FATAL_ERROR "a command line that could not be parsed left an output behind")
endif()
# vio --set: an unknown key and a bad value are input errors naming them.
expect_exit(2 "^error: unknown option 'time_offset.no_such_key'" vio "${WORK}/dataset"
            --out "${WORK}/out_set" --set time_offset.no_such_key=1)
expect_exit(2 "^error: option time_offset.max_frame_gap: 'three'" vio "${WORK}/dataset"
            --out "${WORK}/out_set" --set time_offset.max_frame_gap=three)
expect_exit(2 "^error: --set time_offset.max_frame_gap: expected KEY=VALUE" vio
            "${WORK}/dataset" --out "${WORK}/out_set" --set time_offset.max_frame_gap)
expect_exit(2 "^error: invalid vio options: .*max_frame_gap must be >= 1" vio "${WORK}/dataset"
            --out "${WORK}/out_set" --set time_offset.max_frame_gap=0)
# eval: a reference or a gyro is needed; the gyro check names what it
# could not compare and refuses a bad offset, before any output.
file(WRITE "${WORK}/est.tum" "0.000001 0 0 0 0 0 0 1\n0.000002 0.1 0 0 0 0 0 1\n")
expect_exit(2 "^error: give --ref \\(a reference trajectory\\), --gyro" eval --est "${WORK}/est.tum")
expect_exit(2 "^error: gyro check: no interval of 1.0+ s between the trajectory's 2 frames"
            eval --est "${WORK}/est.tum" --gyro "${WORK}/dataset" --json "${WORK}/gyro.json")
expect_exit(2 "^error: --gyro-time-offset: expected decimal seconds, got 'abc'"
            eval --est "${WORK}/est.tum" --gyro "${WORK}/dataset" --gyro-time-offset abc)
if(EXISTS "${WORK}/gyro.json")
  message(FATAL_ERROR "eval --gyro that failed left ${WORK}/gyro.json behind")
endif()
# emulate-vio: a ground truth it cannot drift along, refused by name, no
# file written.
file(WRITE "${WORK}/one.tum" "1.0 0 0 0 0 0 0 1\n")
expect_exit(2 "^error: ${WORK}/one.tum: needs at least 2 poses, has 1" emulate-vio
            "${WORK}/one.tum" --out "${WORK}/vio_one.tum")
file(WRITE "${WORK}/back.tum" "2.0 0 0 0 0 0 0 1\n1.0 0.1 0 0 0 0 0 1\n")
expect_exit(2 "^error: ${WORK}/back.tum:2: expected a timestamp not smaller" emulate-vio
            "${WORK}/back.tum" --out "${WORK}/vio_back.tum")
file(WRITE "${WORK}/same.tum" "1.0 0 0 0 0 0 0 1\n1.0 0.1 0 0 0 0 0 1\n")
expect_exit(2 "^error: ${WORK}/same.tum: pose 2: stamps must increase" emulate-vio
            "${WORK}/same.tum" --out "${WORK}/vio_same.tum")
expect_exit(2 "^error: --rate must be > 0" emulate-vio "${WORK}/est.tum" --rate 0
            --out "${WORK}/vio_rate.tum")
foreach(name vio_one vio_back vio_same vio_rate)
  if(EXISTS "${WORK}/${name}.tum")
    message(FATAL_ERROR "emulate-vio that failed left ${WORK}/${name}.tum behind")
  endif()
endforeach()
# run on a dataset that is not there: the error, and no output folder left.
expect_exit(2 "^error: ${WORK}/absent: dataset folder not found" run "${WORK}/absent"
            --out "${WORK}/out_absent")
expect_exit(2 "^error: ${WORK}/absent.bag: bag file not found" run "${WORK}/absent.bag"
            --out "${WORK}/out_absent")
if(EXISTS "${WORK}/out_absent")
  message(FATAL_ERROR "run on an absent dataset left ${WORK}/out_absent behind")
endif()
# A folder of photos whose names are not timestamps, with a VIO file: the
# images were numbered 1 s apart, so the VIO cannot pose them; the error
# names --timestamps, the flag that gives their stamps.
foreach(name photo_a photo_b photo_c)
  configure_file("${CMAKE_CURRENT_LIST_DIR}/../../../docs/images/sim_room.png"
                 "${WORK}/photos/${name}.png" COPYONLY)
endforeach()
file(WRITE "${WORK}/photos_vio.tum" "100.0 0 0 0 0 0 0 1\n101.0 0.1 0 0 0 0 0 1\n")
expect_exit(2 "^error: ${WORK}/photos_vio.tum: the VIO poses .* do not overlap .*the image names are not timestamps.*give their stamps with --timestamps FILE"
            run "${WORK}/photos" --out "${WORK}/out_photos" --vio-trajectory "${WORK}/photos_vio.tum")
# Two verification flags that exclude each other: refused before any work.
expect_exit(2 "^error: --fixed-band and --wide-band exclude each other" run "${WORK}/dataset"
            --out "${WORK}/out_bands" --fixed-band --wide-band)
if(EXISTS "${WORK}/out_bands")
  message(FATAL_ERROR "run with excluding flags left ${WORK}/out_bands behind")
endif()
# run --rolling-shutter-readout: a value that is not a number is refused,
# naming the flag, before any work.
expect_exit(2 "^error: --rolling-shutter-readout: option own_vio.rolling_shutter_readout_s: 'fast'"
            run "${WORK}/dataset" --out "${WORK}/out_readout" --rolling-shutter-readout fast)
expect_exit(2 "^error: invalid run options: rolling_shutter.readout_s must be in \\[0, 1\\) s"
            run "${WORK}/dataset" --out "${WORK}/out_readout" --vio-trajectory "${WORK}/v.tum"
            --rolling-shutter-readout 2)
if(EXISTS "${WORK}/out_readout")
  message(FATAL_ERROR "run with a bad readout left ${WORK}/out_readout behind")
endif()
# run --realtime: its settings, overridden by a flag given with it (whatever
# the flags' order) and by --set; the run's first line in its run.log says
# which apply (the console shows its start).
execute_process(COMMAND "${VIOSFM}" --log-level info run "${WORK}/dataset" --max-features 2000
                        --out "${WORK}/out_realtime" --realtime
                        --set mapper.ba_window_batches=3
                RESULT_VARIABLE result ERROR_VARIABLE stderr OUTPUT_VARIABLE stdout)
file(READ "${WORK}/out_realtime/run.log" log)
set(pattern "N1 10, N2 5, [0-9.]+ Hz, max 2000 features, batch size 50, BA window 3, guided matching,")
if(NOT log MATCHES "${pattern}")
  message(FATAL_ERROR "run --realtime: the log '${log}' does not match '${pattern}'")
endif()
# The default (--preset realtime; --realtime the same) lets the feature
# budget and the texture decide the feature count and the rate: 1000
# features a frame at 10 Hz, 2000 at 5 Hz; --rate (as --max-features above)
# or --set keeps the user's rate.
foreach(extra "" "--realtime;--rate;5" "--set;frame_selection.target_rate_hz=5")
  file(REMOVE_RECURSE "${WORK}/out_probe")
  execute_process(COMMAND "${VIOSFM}" --log-level info run "${WORK}/dataset" ${extra}
                          --out "${WORK}/out_probe"
                  RESULT_VARIABLE result ERROR_VARIABLE stderr OUTPUT_VARIABLE stdout)
  file(READ "${WORK}/out_probe/run.log" log)
  string(REGEX MATCH "[0-9]+ features a second \\(at most [0-9]+ a frame\\), batch size 50, BA window 4, [^,]*,"
         decision "${log}")
  string(REGEX MATCH "real-time budget: [^\n]*: [0-9]+ a frame" budget "${log}")
  if(extra STREQUAL "")
    set(expected "10000 features a second (at most 8192 a frame), batch size 50, BA window 4, rate and features by texture,")
    set(expected_budget "at 10 frames a second: 1000 a frame")
  else()
    set(expected "10000 features a second (at most 8192 a frame), batch size 50, BA window 4, guided matching,")
    set(expected_budget "at 5 frames a second: 2000 a frame")
  endif()
  if(NOT decision STREQUAL expected)
    message(FATAL_ERROR "run ${extra}: '${decision}', expected '${expected}'")
  endif()
  if(NOT budget MATCHES "${expected_budget}$")
    message(FATAL_ERROR "run ${extra}: '${budget}', expected '... ${expected_budget}'")
  endif()
endforeach()
# --preset takes realtime or paper.
expect_exit(2 "--preset: fast not in {realtime,paper}"
            run "${WORK}/dataset" --out "${WORK}/out_preset" --preset fast)
file(REMOVE_RECURSE "${WORK}")
