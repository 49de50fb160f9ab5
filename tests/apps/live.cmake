# Issue 18 through the executable (tests/apps/live_cli.sh): live inputs on OpenNI2's Dummy driver, devices,
# record -> run replay, one-line errors, SIGINT, and the headless viewer under xvfb-run (skipped without it).
foreach(case devices bad_inputs record_replay live_run_interrupt screenshot)
  add_test(NAME app_live_${case}
    COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/live_cli.sh $<TARGET_FILE:hashfusion> ${CMAKE_CURRENT_BINARY_DIR} ${case})
  set_tests_properties(app_live_${case} PROPERTIES LABELS apps TIMEOUT 300 SKIP_RETURN_CODE 77)
endforeach()
