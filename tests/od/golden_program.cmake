# Runs PROGRAM OPTION OUT (ecat-slave --write-esi/--write-sii of the built-in firmware) and byte-compares
# OUT with GOLDEN.
execute_process(COMMAND ${PROGRAM} ${OPTION} ${OUT} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${PROGRAM} ${OPTION} failed (${rc}): ${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT} ${GOLDEN} RESULT_VARIABLE same)
if(NOT same EQUAL 0)
  message(FATAL_ERROR "${OUT} differs from ${GOLDEN}")
endif()
