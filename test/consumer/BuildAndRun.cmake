# Configures, builds and runs the consumer project; fails on any step.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${BINARY_DIR}
  -DCMAKE_BUILD_TYPE=Release -DVirtualUnwrapping_DIR=${VirtualUnwrapping_DIR}
  RESULT_VARIABLE result)
if(result)
  message(FATAL_ERROR "consumer configure failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY_DIR} RESULT_VARIABLE result)
if(result)
  message(FATAL_ERROR "consumer build failed")
endif()
execute_process(COMMAND ${BINARY_DIR}/consumer RESULT_VARIABLE result)
if(result)
  message(FATAL_ERROR "consumer run failed")
endif()
