// Why this reader is hand-written and not libtinyobjloader-dev (issue 36 asked for the Debian library; decided
// against after measuring it). tinyobjloader 2.0.0~rc10 (Debian 12), ObjReader::ParseFromString with
// triangulate, on four-line files "v ...; v 0 0 0; v 1 1 1; f 1 2 3" (the program is in THIRD_PARTY.md):
//   "v 1 abc 3"   -> loads, vertex (1, 0, 3), no error, no warning
//   "v 1 2 3x"    -> loads, (1, 2, 3)               "v 1 2"      -> loads, (1, 2, 0)
//   "v nan 2 3"   -> loads, (0, 2, 3)               "v 1e999 2 3" -> loads, (inf, 2, 3)
//   "f 1 2 9"     -> loads the face, with only a warning "Vertex indices out of bounds"
// Its number parser turns what it cannot read into 0 and keeps going, so a corrupt file becomes a wrong mesh
// without a word, and its errors carry no file:line. Making it strict would need a pass over every line checking
// every token first: that pass is this reader. So this file keeps its own parser (bounded read, FILE:LINE errors,
// fuzzed by tests/io/fuzz_obj.cpp) and THIRD_PARTY.md records the decision.
#include "io/obj.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <ostream>
#include <sstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "io/text_util.h"

namespace hf {
namespace {

void append_float(std::string& out, float v) {
  char tmp[32];
  const auto r = std::to_chars(tmp, tmp + sizeof(tmp), v);  // shortest form that reads back to the same float
  out.append(tmp, r.ptr);
}

void write_all(std::string& s, std::ostream* out, const TriangleMesh& m, const ObjWriteOptions& o) {
  auto maybe_flush = [&] {
    if (out && s.size() > (1u << 20)) {
      out->write(s.data(), static_cast<std::streamsize>(s.size()));
      s.clear();
    }
  };
  if (!o.comment.empty()) {
    std::istringstream lines(o.comment);
    std::string line;
    while (std::getline(lines, line)) s += "# " + line + "\n";
  }
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    s += "v ";
    for (int k = 0; k < 3; ++k) {
      if (k) s += ' ';
      append_float(s, m.vertices[i][k]);
    }
    if (m.has_colors()) {
      const Rgb8 c = m.colors[i];
      for (const std::uint8_t ch : {c.r, c.g, c.b}) {
        s += ' ';
        append_float(s, static_cast<float>(ch) / 255.0f);
      }
    }
    s += '\n';
    maybe_flush();
  }
  for (const Eigen::Vector3f& n : m.normals) {
    s += "vn ";
    for (int k = 0; k < 3; ++k) {
      if (k) s += ' ';
      append_float(s, n[k]);
    }
    s += '\n';
    maybe_flush();
  }
  for (const Eigen::Vector3i& t : m.triangles) {
    s += 'f';
    for (int k = 0; k < 3; ++k) {
      const std::string idx = std::to_string(t[k] + 1);
      s += ' ';
      s += idx;
      if (m.has_normals()) s += "//" + idx;
    }
    s += '\n';
    maybe_flush();
  }
  if (out) {
    out->write(s.data(), static_cast<std::streamsize>(s.size()));
    s.clear();
  }
}

struct Parser {
  const std::string& file;
  int lineno = 0;

  [[noreturn]] void fail(const std::string& message) const { throw ParseError(file, lineno, message); }

  float number(std::string_view tok, const char* what) const {
    float f = 0;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), f);
    if (r.ptr != tok.data() + tok.size() || r.ec == std::errc::invalid_argument)
      fail(std::string("expected a number for ") + what + ", got " + quote_for_message(tok));
    if (r.ec == std::errc::result_out_of_range) {
      // Underflow to a denormal or zero is harmless; overflow is not a coordinate.
      const double d = std::strtod(std::string(tok).c_str(), nullptr);
      if (std::fabs(d) > 1.0) fail(std::string("expected a finite float for ") + what + ", got " + quote_for_message(tok));
      f = static_cast<float>(d);
    }
    if (!std::isfinite(f)) fail(std::string("expected a finite float for ") + what + ", got " + quote_for_message(tok));
    return f;
  }

  // An OBJ index (1-based, or negative relative to the `defined` elements so far) -> 0-based. Positive indices
  // beyond `defined` are returned as is and checked once the whole file is read (some writers reference ahead).
  std::int64_t index(std::string_view tok, std::int64_t defined, const char* what) const {
    std::int64_t i = 0;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), i);
    if (r.ec != std::errc() || r.ptr != tok.data() + tok.size())
      fail(std::string("expected an integer ") + what + " index, got " + quote_for_message(tok));
    if (i == 0) fail(std::string("expected a non-zero ") + what + " index (OBJ indices start at 1), got 0");
    if (i < 0) {
      if (-i > defined)
        fail(std::string("expected a relative ") + what + " index within the " + std::to_string(defined) + " defined so far, got " +
             std::to_string(i));
      return defined + i;
    }
    if (i > std::numeric_limits<int>::max()) fail(std::string("expected a ") + what + " index below 2^31, got " + quote_for_message(tok));
    return i - 1;
  }
};

}  // namespace

TriangleMesh parse_obj(std::string_view text, const std::string& file) {
  TriangleMesh mesh;
  std::vector<Eigen::Vector3f> vn;
  std::vector<Eigen::Vector3i> corner_normals;  // per triangle, -1 where a corner names no normal
  bool any_corner_normal = false;
  int color_line = 0;  // first "v" line, which decides whether vertices carry colours
  struct Forward {
    int line;
    std::int64_t index;
    bool normal;
  };
  std::vector<Forward> forward;  // positive indices not yet defined when their face was read
  Parser P{file};
  std::vector<std::int64_t> fv, fn;

  size_t pos = 0;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view line = text.substr(pos, nl - pos);
    pos = nl + 1;
    ++P.lineno;
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const std::vector<std::string_view> w = split_words(line);
    if (w.empty()) continue;
    const std::string_view key = w[0];
    if (key == "v") {
      const size_t n = w.size() - 1;
      if (n != 3 && n != 4 && n != 6 && n != 7)
        P.fail("expected 'v x y z [w]' or 'v x y z r g b', got " + std::to_string(n) + " numbers");
      mesh.vertices.emplace_back(P.number(w[1], "x"), P.number(w[2], "y"), P.number(w[3], "z"));
      const bool colored = n >= 6;
      if (color_line == 0) color_line = colored ? P.lineno : -P.lineno;
      if (colored != (color_line > 0))
        P.fail(std::string("expected ") + (colored ? "no colours" : "colours 'v x y z r g b'") + " as on the first vertex (line " +
               std::to_string(std::abs(color_line)) + ")");
      if (colored) {
        std::uint8_t c[3];
        for (int k = 0; k < 3; ++k) {
          const float f = P.number(w[4 + k], "a colour") * 255.0f;
          c[k] = f <= 0 ? 0 : f >= 255 ? 255 : static_cast<std::uint8_t>(std::lround(f));
        }
        mesh.colors.push_back(Rgb8{c[0], c[1], c[2]});
      }
      if (mesh.vertices.size() > static_cast<size_t>(std::numeric_limits<int>::max())) P.fail("expected fewer than 2^31 vertices");
    } else if (key == "vn") {
      if (w.size() != 4) P.fail("expected 'vn x y z', got " + std::to_string(w.size() - 1) + " numbers");
      vn.emplace_back(P.number(w[1], "nx"), P.number(w[2], "ny"), P.number(w[3], "nz"));
    } else if (key == "f") {
      if (w.size() < 4) P.fail("expected a face with at least 3 corners, got " + std::to_string(w.size() - 1));
      fv.clear();
      fn.clear();
      for (size_t k = 1; k < w.size(); ++k) {
        const std::string_view c = w[k];
        const size_t s1 = c.find('/');
        const std::string_view vtok = c.substr(0, s1);
        std::string_view ntok;
        if (s1 != std::string_view::npos) {
          const size_t s2 = c.find('/', s1 + 1);
          if (s2 != std::string_view::npos) ntok = c.substr(s2 + 1);
          if (c.find('/', s2 == std::string_view::npos ? c.size() : s2 + 1) != std::string_view::npos)
            P.fail("expected a corner 'v', 'v/t', 'v//n' or 'v/t/n', got " + quote_for_message(c));
        }
        const std::int64_t v = P.index(vtok, static_cast<std::int64_t>(mesh.vertices.size()), "vertex");
        if (v >= static_cast<std::int64_t>(mesh.vertices.size())) forward.push_back({P.lineno, v, false});
        fv.push_back(v);
        if (!ntok.empty()) {
          const std::int64_t n = P.index(ntok, static_cast<std::int64_t>(vn.size()), "normal");
          if (n >= static_cast<std::int64_t>(vn.size())) forward.push_back({P.lineno, n, true});
          fn.push_back(n);
          any_corner_normal = true;
        } else {
          fn.push_back(-1);
        }
      }
      for (size_t k = 2; k < fv.size(); ++k) {
        mesh.triangles.emplace_back(static_cast<int>(fv[0]), static_cast<int>(fv[k - 1]), static_cast<int>(fv[k]));
        corner_normals.emplace_back(static_cast<int>(fn[0]), static_cast<int>(fn[k - 1]), static_cast<int>(fn[k]));
      }
    }
    // Anything else (vt, vp, g, o, s, usemtl, mtllib, l, p, ...) carries nothing a TriangleMesh holds.
  }

  for (const Forward& f : forward) {
    const size_t defined = f.normal ? vn.size() : mesh.vertices.size();
    if (f.index >= static_cast<std::int64_t>(defined))
      throw ParseError(file, f.line,
                       std::string("expected ") + (f.normal ? "normal" : "vertex") + " indices in [1, " +
                           std::to_string(defined) + "], got " + std::to_string(f.index + 1));
  }

  if (any_corner_normal) {
    const size_t nv = mesh.vertices.size();
    std::vector<Eigen::Vector3f> sum(nv, Eigen::Vector3f::Zero());
    std::vector<int> first(nv, -1);
    std::vector<char> mixed(nv, 0);
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int n = corner_normals[t][k];
        if (n < 0) continue;
        const int v = mesh.triangles[t][k];
        if (first[v] < 0) first[v] = n;
        else if (first[v] != n) mixed[v] = 1;
        sum[v] += vn[n];
      }
    mesh.normals.assign(nv, Eigen::Vector3f::Zero());
    for (size_t v = 0; v < nv; ++v) {
      if (first[v] < 0) continue;
      if (!mixed[v]) mesh.normals[v] = vn[first[v]];
      else if (sum[v].norm() > 0) mesh.normals[v] = sum[v].normalized();
    }
  } else if (!vn.empty() && vn.size() == mesh.vertices.size()) {
    mesh.normals = std::move(vn);
  }
  return mesh;
}

TriangleMesh read_obj(const std::string& path) {
  return parse_obj(read_regular_file(path, "OBJ file", kMaxModelFileBytes), path);
}

std::string format_obj(const TriangleMesh& mesh, const ObjWriteOptions& options) {
  mesh.validate();
  std::string s;
  write_all(s, nullptr, mesh, options);
  return s;
}

void write_obj(const std::string& path, const TriangleMesh& mesh, const ObjWriteOptions& options) {
  mesh.validate();
  write_file_atomically(path, [&](std::ostream& out) {
    std::string s;
    write_all(s, &out, mesh, options);
  });
}

}  // namespace hf
