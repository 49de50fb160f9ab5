# A missing dataset folder: non-zero exit, exactly one line on stderr naming the folder, no crash.
execute_process(COMMAND ${HASHFUSION} run --input ${DIR}/no_such_dataset --out ${DIR}/run_missing
                RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_VARIABLE out)
if(rc EQUAL 0 OR NOT rc EQUAL 1)
  message(FATAL_ERROR "expected exit 1, got ${rc}")
endif()
string(STRIP "${err}" err)
string(REGEX MATCHALL "\n" newlines "${err}")
list(LENGTH newlines n)
if(NOT n EQUAL 0 OR NOT err MATCHES "no_such_dataset")
  message(FATAL_ERROR "expected one line naming the folder, got: ${err}")
endif()
