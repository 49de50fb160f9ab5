# End to end through the CLI (ctest -P script): `hashfusion head-features` on a real head when ../shared is present
# (every output written, no temporary left), and on bad input (an empty file, an unknown operator): exit status 1
# and one line naming the problem.
# Variables: HASHFUSION (the executable), MESH (a head mesh; skipped when absent), WORK (a scratch folder).
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

file(WRITE ${WORK}/empty.obj "")
execute_process(COMMAND ${HASHFUSION} head-features --input ${WORK}/empty.obj --out ${WORK}/empty_out
                RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 1 OR NOT err MATCHES "empty.obj: the mesh has no triangles")
  message(FATAL_ERROR "empty mesh: expected exit 1 and a message naming the file, got ${rc}: ${err}")
endif()
string(REGEX MATCHALL "\n" lines "${err}")
list(LENGTH lines n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "empty mesh: expected one line on stderr, got: ${err}")
endif()

if(NOT EXISTS ${MESH})
  message(STATUS "skipped the real head: ${MESH} not found (../shared absent)")
  return()
endif()
execute_process(COMMAND ${HASHFUSION} head-features --input ${MESH} --out ${WORK}/bad --morphology grow:3
                RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 1 OR NOT err MATCHES "unknown operator 'grow'")
  message(FATAL_ERROR "bad --morphology: expected exit 1 naming the operator, got ${rc}: ${err}")
endif()
execute_process(COMMAND ${HASHFUSION} head-features --input ${MESH} --out ${WORK}/out --auto
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "head-features failed (${rc}): ${err}")
endif()
foreach(f evaluations.ply mean_curvature.ply gaussian_curvature.ply k1.ply k2.ply laplace.ply features.ply
          control_points.json report.json report.md features.png evaluation.png)
  if(NOT EXISTS ${WORK}/out/${f})
    message(FATAL_ERROR "missing output ${f}")
  endif()
endforeach()
file(GLOB leftovers ${WORK}/out/*.tmp*)
if(leftovers)
  message(FATAL_ERROR "temporaries left behind: ${leftovers}")
endif()
file(READ ${WORK}/out/control_points.json cp)
string(JSON count LENGTH "${cp}" control_points)
if(count LESS 40)
  message(FATAL_ERROR "expected at least 40 control points on ${MESH}, got ${count}")
endif()
message(STATUS "${out}")
