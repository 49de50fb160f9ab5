// Fuzzes every photogrammetry parser (photogrammetry/scene_readers.h, photogrammetry/sketch.h and the binary
// scene.mvs of photogrammetry/scene_mvs.h): any bytes either parse into values that pass Network::validate() / the sketch's documented invariants, or raise hf::Error
// with a one-line printable message naming the file (tests/io/fuzz_message_check.h).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "photogrammetry/scene_mvs.h"
#include "photogrammetry/scene_readers.h"
#include "photogrammetry/sketch.h"
#include "tests/io/fuzz_message_check.h"

namespace pg = hf::photogrammetry;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto guarded = [&](const std::string& file, auto parse) {
    try {
      parse(file);
    } catch (const hf::Error& e) {
      hf::fuzz::check_message(e, file);
    }
  };
  guarded("cameras.txt", [&](const std::string& f) {
    pg::Network n;
    n.source = f;
    n.shots = pg::parse_openmvs_cameras(text, f, "/nonexistent");
    n.validate();
  });
  guarded("points.txt", [&](const std::string& f) {
    const pg::Cloud c = pg::parse_openmvs_points(text, f, 11);
    for (const auto& v : c.views)
      for (const int s : v)
        if (s < 0 || s >= 11) std::abort();
    for (const auto& p : c.positions)
      if (!p.allFinite()) std::abort();
  });
  guarded("par.txt", [&](const std::string& f) {
    pg::Network n;
    n.source = f;
    n.shots = pg::parse_middlebury_par(text, f, "/nonexistent");
    n.validate();
  });
  guarded("scene.mvs", [&](const std::string& f) {
    const pg::Network n = pg::parse_scene_mvs(text, f, "/nonexistent");  // validated inside
    for (const auto& v : n.cloud.views)
      for (const int s : v)
        if (s < 0 || size_t(s) >= n.shots.size()) std::abort();
    for (const auto& p : n.cloud.positions)
      if (!p.allFinite()) std::abort();
    if (!n.cloud.colors.empty() && n.cloud.colors.size() != n.cloud.size()) std::abort();
  });
  guarded("report.json", [&](const std::string& f) {
    const pg::RunReport r = pg::parse_run_report(text, f);
    if (!(r.camera.fx > 0) || !(r.camera.fy > 0) || r.camera.width <= 0) std::abort();
  });
  guarded("sketch.json", [&](const std::string& f) {
    const pg::Sketch s = pg::parse_sketch(text, f);
    for (const auto& p : s.polygons) {
      if (p.views.empty()) std::abort();
      for (const auto& v : p.views)
        if (v.points.size() != p.views[0].points.size() || v.points.size() < 3 || pg::self_intersecting(v.points))
          std::abort();
      for (const auto& v : p.views)  // issue 35: every point within the stated bound
        for (const auto& q : v.points)
          if (!(std::abs(q.x()) <= pg::kMaxSketchPixel && std::abs(q.y()) <= pg::kMaxSketchPixel)) std::abort();
    }
  });
  hf::fuzz::check_long_first_line_refused(text, [](const std::string& t) {
    pg::parse_middlebury_par(t, "par.txt", "/nonexistent");
  });
  return 0;
}
