# Installs hashfusion's public headers (run by `cmake --install`, from the install(CODE) of cmake/hf_package.cmake)
# with their project includes rewritten: `#include "core/se3.h"` becomes `#include <hashfusion/core/se3.h>`, so
# the installed tree includes itself as consumers include it and never picks up a consumer's own "core/se3.h".
# The source tree keeps its short includes. Inputs:
#   HF_SOURCE_DIR   the source root
#   HF_HEADER_LIST  a file listing the headers to install, one path relative to HF_SOURCE_DIR a line
#   HF_STAGING_DIR  a build-tree folder for the rewritten copies
#   HF_INCLUDE_DIR  the include folder relative to the install prefix (the headers go to its hashfusion/)
# A quoted include that names no installed header stops the install: the installed header would not compile.
cmake_policy(PUSH)
cmake_policy(VERSION 3.25)  # install scripts run with no policies set (IN_LIST)
file(STRINGS ${HF_HEADER_LIST} hf_headers)
foreach(rel IN LISTS hf_headers)
  file(READ ${HF_SOURCE_DIR}/${rel} text)
  string(REGEX MATCHALL "#[ \t]*include[ \t]*\"[^\"]+\"" includes "${text}")
  list(REMOVE_DUPLICATES includes)
  foreach(line IN LISTS includes)
    string(REGEX REPLACE "^.*\"([^\"]+)\"$" "\\1" target "${line}")
    if(NOT target IN_LIST hf_headers)
      message(FATAL_ERROR "${HF_SOURCE_DIR}/${rel}: #include \"${target}\" names no installed header")
    endif()
    string(REPLACE "${line}" "#include <hashfusion/${target}>" text "${text}")
  endforeach()
  set(staged ${HF_STAGING_DIR}/hashfusion/${rel})
  # Rewritten only when the text changes, so an unchanged header keeps its time stamp and is not re-copied.
  set(old)
  if(EXISTS ${staged})
    file(READ ${staged} old)
  endif()
  if(NOT old STREQUAL text)
    file(WRITE ${staged} "${text}")
  endif()
  get_filename_component(rel_dir ${rel} DIRECTORY)
  file(INSTALL DESTINATION "${CMAKE_INSTALL_PREFIX}/${HF_INCLUDE_DIR}/hashfusion/${rel_dir}" TYPE FILE
       FILES ${staged})
endforeach()
cmake_policy(POP)
