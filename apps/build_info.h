// The version (CMake's PROJECT_VERSION) and the git commit the `hashfusion` executable was built from: "unknown"
// outside a git checkout, "<sha>-dirty" when tracked files differed from it at build time. Defined in a file
// generated at every build (cmake/hf_build_info.cmake), so the commit is the build's, not the last configure's.
#pragma once

namespace hf::apps {

const char* build_version();
const char* build_commit();

}  // namespace hf::apps
