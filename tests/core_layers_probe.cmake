# The test core_layers_probe: that core/check_layers.cmake catches an include that runs back up.
# A copy of core/ in which core/base/names.cpp (the lowest floor) includes a header of
# core/pipeline/ (near the top) must fail the check, naming that file and line; the same copy
# without it must pass. Run as: cmake -DSOURCE=<repository> -DWORK=<scratch folder> -P this file.
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
file(COPY ${SOURCE}/core DESTINATION ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} -P ${WORK}/core/check_layers.cmake
                RESULT_VARIABLE clean_result OUTPUT_VARIABLE clean_out ERROR_VARIABLE clean_err)
if(NOT clean_result EQUAL 0)
  message(FATAL_ERROR "the untouched copy of core/ fails the check:\n${clean_out}${clean_err}")
endif()
file(READ ${WORK}/core/base/names.cpp names)
file(WRITE ${WORK}/core/base/names.cpp "#include \"core/pipeline/pipeline.h\"\n${names}")
execute_process(COMMAND ${CMAKE_COMMAND} -P ${WORK}/core/check_layers.cmake
                RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(result EQUAL 0)
  message(FATAL_ERROR "an include of core/pipeline/ from core/base/ passed the check:\n${out}${err}")
endif()
string(FIND "${out}${err}" "core/base/names.cpp:1" named)
if(named EQUAL -1)
  message(FATAL_ERROR "the check failed without naming core/base/names.cpp:1:\n${out}${err}")
endif()
file(REMOVE_RECURSE ${WORK})
message(STATUS "an include running back up (core/base -> core/pipeline) fails the check, named")
