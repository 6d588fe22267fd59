# ctest cli/help: what `viosfm --help` and `viosfm run --help` show a user.
# The top-level help lists the user's commands and hides the developer
# tools (`--help-all` shows them); `run --help` shows a short list of flags
# and the three examples, `run --help-all` every flag; the flags that set a
# run's options are bound once and shared by the stages' commands.
#   cmake -DVIOSFM=<viosfm binary> -P help_test.cmake
function(help out)
  execute_process(COMMAND "${VIOSFM}" ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE stdout
                  ERROR_VARIABLE stderr)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "viosfm ${ARGN}: exit code ${result}; stderr: ${stderr}")
  endif()
  set(${out} "${stdout}" PARENT_SCOPE)
endfunction()

function(expect_lines text name)
  foreach(pattern ${ARGN})
    string(REGEX MATCH "\n  ${pattern}" found "${text}")
    if(NOT found)
      message(FATAL_ERROR "${name}: no line for '${pattern}' in:\n${text}")
    endif()
  endforeach()
endfunction()

function(expect_no_lines text name)
  foreach(pattern ${ARGN})
    string(REGEX MATCH "\n  ${pattern}" found "${text}")
    if(found)
      message(FATAL_ERROR "${name}: '${pattern}' should not be listed in:\n${text}")
    endif()
  endforeach()
endfunction()

# Lines of at most 100 characters.
function(expect_width text name)
  # A backslash or a semicolon would join lines of the CMake list.
  string(REPLACE "\\" "/" text "${text}")
  string(REPLACE ";" "," text "${text}")
  string(REPLACE "\n" ";" lines "${text}")
  foreach(line ${lines})
    string(LENGTH "${line}" length)
    if(length GREATER 100)
      message(FATAL_ERROR "${name}: a line of ${length} characters: '${line}'")
    endif()
  endforeach()
endfunction()

set(user_commands "run " "report " "export " "convert " "eval " "replay " "vio ")
set(dev_commands "simulate " "emulate-vio " "features " "match " "check-pairs " "bench-report ")

help(top --help)
expect_lines("${top}" "viosfm --help" ${user_commands})
expect_no_lines("${top}" "viosfm --help" ${dev_commands})
expect_width("${top}" "viosfm --help")
# One line per command: its first sentence.
foreach(command ${user_commands})
  string(REGEX MATCH "\n  ${command}[^\n]*\n  [^ ]" one_line "${top}")
  if(NOT one_line AND NOT command STREQUAL "vio ")
    message(FATAL_ERROR "viosfm --help: '${command}' takes more than one line:\n${top}")
  endif()
endforeach()
help(top_all --help-all)
expect_lines("${top_all}" "viosfm --help-all" ${user_commands} ${dev_commands})

help(run_help run --help)
expect_width("${run_help}" "viosfm run --help")
expect_lines("${run_help}" "viosfm run --help" "--out" "--camera-yaml" "--timestamps"
             "--vio-trajectory" "--list-options" "viosfm run [^ ]+ --out"
             "viosfm run [^ ]+\\.mcap --out" "viosfm run photos/ --out")
expect_no_lines("${run_help}" "viosfm run --help" "--n1" "--ba-window" "--vio-yaw-per-sqrt-m")
string(REGEX MATCHALL "\n  --[a-z]" flags "${run_help}")
list(LENGTH flags num_flags)
if(num_flags GREATER 16)
  message(FATAL_ERROR "viosfm run --help: ${num_flags} flags, expected a short list:\n${run_help}")
endif()
help(run_all run --help-all)
expect_lines("${run_all}" "viosfm run --help-all" "--n1 INT=" "--ba-window" "--vio-yaw-per-sqrt-m"
             "--stream" "--no-progress")

# `match --n1` and `run --n1`: one flag, one help (its option's); the
# defaults may differ (run starts from its real-time preset).
help(match_help match --help)
foreach(flag "--n1" "--max-vio-time-difference" "--no-vio-prior" "--threads")
  string(REGEX MATCH "\n  ${flag} [^\n]*(\n    [^\n]*)*" in_run "${run_all}")
  string(REGEX MATCH "\n  ${flag} [^\n]*(\n    [^\n]*)*" in_match "${match_help}")
  string(REGEX REPLACE "=[^ \n]*" "" in_run "${in_run}")
  string(REGEX REPLACE "=[^ \n]*" "" in_match "${in_match}")
  if(NOT in_run OR NOT in_run STREQUAL in_match)
    message(FATAL_ERROR "${flag}: run's '${in_run}' and match's '${in_match}' differ")
  endif()
endforeach()
