// GDAL reports errors through a handler that prints "ERROR n: ..." to stderr; our CLI promises one line per
// failure, so calls into GDAL run under QuietGdal and put GDAL's last message into our hf::Error instead.
#pragma once

#include <cpl_error.h>

#include <string>

namespace hf::lidar {

class QuietGdal {
 public:
  QuietGdal() {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietGdal() { CPLPopErrorHandler(); }
  QuietGdal(const QuietGdal&) = delete;
  QuietGdal& operator=(const QuietGdal&) = delete;
  // ": <GDAL's last message>", or `otherwise` when it left none.
  static std::string why(const std::string& otherwise) {
    const std::string m = CPLGetLastErrorMsg();
    return m.empty() ? otherwise : ": " + m;
  }
};

}  // namespace hf::lidar
