# Shared by the command tests (*CommandTest.cmake): runs `TOOL SUBCOMMAND ARGS...` and
# requires a failure reported as exactly one line "virtual-unwrap: error: ..." matching
# pattern on stderr.
function(vu_expect_failure subcommand name pattern)
  execute_process(COMMAND ${TOOL} ${subcommand} ${ARGN} RESULT_VARIABLE result ERROR_VARIABLE error OUTPUT_QUIET)
  if(result EQUAL 0)
    message(FATAL_ERROR "${name}: expected failure, got success")
  endif()
  string(REGEX MATCHALL "\n" newlines "${error}")
  list(LENGTH newlines lines)
  if(NOT lines EQUAL 1 OR NOT error MATCHES "^virtual-unwrap: error: .*${pattern}")
    message(FATAL_ERROR "${name}: expected one error line matching '${pattern}', got:\n${error}")
  endif()
endfunction()

# Requires every file named after dir to exist in dir.
function(vu_expect_files dir)
  foreach(file ${ARGN})
    if(NOT EXISTS ${dir}/${file})
      message(FATAL_ERROR "missing ${file}")
    endif()
  endforeach()
endfunction()

# Sets out to the time stamp and MD5 of every file below dir: equal lists before and after a
# command tell that it left those files untouched.
function(vu_file_stamps dir out)
  file(GLOB_RECURSE files ${dir}/*)
  set(stamps "")
  foreach(f ${files})
    file(TIMESTAMP ${f} t)
    file(MD5 ${f} h)
    list(APPEND stamps "${t}${h}")
  endforeach()
  set(${out} "${stamps}" PARENT_SCOPE)
endfunction()
