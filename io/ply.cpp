#include "io/ply.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <ostream>
#include <sstream>
#include <string>
#include <unordered_set>

#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "io/text_util.h"

namespace hf {
namespace {

// ---------------------------------------------------------------------------------------------------------------
// Scalar types and the header model.

enum class Scalar : std::uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

int scalar_size(Scalar t) {
  switch (t) {
    case Scalar::i8:
    case Scalar::u8: return 1;
    case Scalar::i16:
    case Scalar::u16: return 2;
    case Scalar::i32:
    case Scalar::u32:
    case Scalar::f32: return 4;
    case Scalar::f64: return 8;
  }
  return 1;
}

bool is_integer(Scalar t) { return t != Scalar::f32 && t != Scalar::f64; }

bool parse_scalar(std::string_view s, Scalar* t) {
  struct Name {
    std::string_view name;
    Scalar type;
  };
  static constexpr std::array<Name, 16> kNames = {{{"char", Scalar::i8},    {"int8", Scalar::i8},
                                                   {"uchar", Scalar::u8},   {"uint8", Scalar::u8},
                                                   {"short", Scalar::i16},  {"int16", Scalar::i16},
                                                   {"ushort", Scalar::u16}, {"uint16", Scalar::u16},
                                                   {"int", Scalar::i32},    {"int32", Scalar::i32},
                                                   {"uint", Scalar::u32},   {"uint32", Scalar::u32},
                                                   {"float", Scalar::f32},  {"float32", Scalar::f32},
                                                   {"double", Scalar::f64}, {"float64", Scalar::f64}}};
  for (const Name& n : kNames)
    if (n.name == s) {
      *t = n.type;
      return true;
    }
  return false;
}

// Inclusive value range of an integer type (for ASCII range checks).
void integer_range(Scalar t, std::int64_t* lo, std::int64_t* hi) {
  switch (t) {
    case Scalar::i8: *lo = -128, *hi = 127; return;
    case Scalar::u8: *lo = 0, *hi = 255; return;
    case Scalar::i16: *lo = -32768, *hi = 32767; return;
    case Scalar::u16: *lo = 0, *hi = 65535; return;
    case Scalar::i32: *lo = std::numeric_limits<std::int32_t>::min(), *hi = std::numeric_limits<std::int32_t>::max(); return;
    case Scalar::u32: *lo = 0, *hi = std::numeric_limits<std::uint32_t>::max(); return;
    default: *lo = *hi = 0; return;
  }
}

const char* scalar_name(Scalar t) {
  switch (t) {
    case Scalar::i8: return "char";
    case Scalar::u8: return "uchar";
    case Scalar::i16: return "short";
    case Scalar::u16: return "ushort";
    case Scalar::i32: return "int";
    case Scalar::u32: return "uint";
    case Scalar::f32: return "float";
    case Scalar::f64: return "double";
  }
  return "?";
}

struct Property {
  std::string name;
  Scalar type = Scalar::f32;  // item type for lists
  bool is_list = false;
  Scalar count_type = Scalar::u8;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  int header_line = 0;
};

struct Header {
  PlyFormat format = PlyFormat::ascii;
  std::vector<Element> elements;
  size_t body_offset = 0;
  int end_header_line = 0;
};

Header parse_header(std::string_view bytes, const std::string& file) {
  Header h;
  size_t pos = 0;
  int lineno = 0;
  bool have_format = false;
  // Names seen, for the duplicate checks: a header of n properties costs O(n), not O(n^2) (issue 35's leftover:
  // a 10 MB header of distinct properties took minutes).
  std::unordered_set<std::string> element_names, property_names;  // property_names: of the last element
  for (;;) {
    const size_t nl = bytes.find('\n', pos);
    if (nl == std::string_view::npos) {
      if (lineno == 0 && bytes.substr(0, 3) != "ply")
        throw ParseError(file, 1, "expected 'ply' as the first line, got " + quote_for_message(bytes));
      throw ParseError(file, lineno + 1, "expected 'end_header' before the end of the file");
    }
    std::string_view line = bytes.substr(pos, nl - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = nl + 1;
    ++lineno;
    if (lineno == 1) {
      if (line != "ply") throw ParseError(file, 1, "expected 'ply' as the first line, got " + quote_for_message(line));
      continue;
    }
    const std::vector<std::string_view> w = split_words(line);
    if (w.empty()) continue;
    const std::string_view key = w[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      if (have_format) throw ParseError(file, lineno, "expected one 'format' line, got a second one");
      if (w.size() != 3 || w[2] != "1.0")
        throw ParseError(file, lineno, "expected 'format ascii|binary_little_endian|binary_big_endian 1.0', got " +
                                           quote_for_message(line));
      if (w[1] == "ascii") h.format = PlyFormat::ascii;
      else if (w[1] == "binary_little_endian") h.format = PlyFormat::binary_little_endian;
      else if (w[1] == "binary_big_endian") h.format = PlyFormat::binary_big_endian;
      else
        throw ParseError(file, lineno,
                         "expected format ascii, binary_little_endian or binary_big_endian, got " + quote_for_message(w[1]));
      have_format = true;
    } else if (key == "element") {
      if (w.size() != 3) throw ParseError(file, lineno, "expected 'element NAME COUNT', got " + quote_for_message(line));
      Element e;
      e.name = std::string(w[1]);
      e.header_line = lineno;
      const auto r = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
      if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size())
        throw ParseError(file, lineno, "expected a non-negative element count, got " + quote_for_message(w[2]));
      if (!element_names.insert(e.name).second)
        throw ParseError(file, lineno, "expected one element '" + e.name + "', got a second one");
      property_names.clear();
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) throw ParseError(file, lineno, "expected 'element' before the first 'property'");
      Property p;
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5)
          throw ParseError(file, lineno, "expected 'property list COUNT_TYPE ITEM_TYPE NAME', got " + quote_for_message(line));
        if (!parse_scalar(w[2], &p.count_type) || !is_integer(p.count_type))
          throw ParseError(file, lineno, "expected an integer list count type (uchar, ushort, uint, ...), got " +
                                             quote_for_message(w[2]));
        if (!parse_scalar(w[3], &p.type))
          throw ParseError(file, lineno, "expected a PLY scalar type (char uchar short ushort int uint float double), got " +
                                             quote_for_message(w[3]));
        p.is_list = true;
        p.name = std::string(w[4]);
      } else {
        if (w.size() != 3) throw ParseError(file, lineno, "expected 'property TYPE NAME', got " + quote_for_message(line));
        if (!parse_scalar(w[1], &p.type))
          throw ParseError(file, lineno, "expected a PLY scalar type (char uchar short ushort int uint float double), got " +
                                             quote_for_message(w[1]));
        p.name = std::string(w[2]);
      }
      if (!property_names.insert(p.name).second)
        throw ParseError(file, lineno, "expected one property '" + p.name + "' in element '" +
                                           h.elements.back().name + "', got a second one");
      h.elements.back().properties.push_back(std::move(p));
    } else if (key == "end_header") {
      if (!have_format) throw ParseError(file, lineno, "expected a 'format' line before 'end_header'");
      h.body_offset = pos;
      h.end_header_line = lineno;
      return h;
    } else {
      throw ParseError(file, lineno, "expected 'format', 'element', 'property', 'comment' or 'end_header', got " +
                                         quote_for_message(key));
    }
  }
}

// The fewest body bytes one instance of `e` can take: fixed sizes plus list counts (binary), or one character and
// one separator per property (ascii).
std::uint64_t min_instance_bytes(const Element& e, PlyFormat format) {
  std::uint64_t n = 0;
  for (const Property& p : e.properties)
    n += format == PlyFormat::ascii ? 2 : static_cast<std::uint64_t>(scalar_size(p.is_list ? p.count_type : p.type));
  return n;
}

// Rejects counts the remaining bytes cannot possibly hold, before anything is allocated from them.
void check_counts_fit(const Header& h, size_t body_bytes, const std::string& file) {
  std::uint64_t total = 0;
  for (const Element& e : h.elements) {
    const std::uint64_t per = min_instance_bytes(e, h.format);
    if (per == 0) continue;
    const std::uint64_t left = body_bytes - std::min<std::uint64_t>(total, body_bytes);
    if (e.count > left / per)
      throw ParseError(file, e.header_line,
                       "expected at most " + std::to_string(left / per) + " '" + e.name + "' elements in the " +
                           std::to_string(left) + " bytes left in the file, got a count of " + std::to_string(e.count) +
                           " (truncated file?)");
    total += e.count * per;
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Body readers. Both offer begin()/end() around one element instance, value(type) for a scalar as double,
// integer(type) for list counts and indices, skip(type) and fail(message), so one walker serves both encodings.

class BinaryBody {
 public:
  BinaryBody(std::string_view body, bool big_endian, const std::string& file)
      : p_(reinterpret_cast<const unsigned char*>(body.data())),
        end_(p_ + body.size()),
        swap_(big_endian != (std::endian::native == std::endian::big)),
        file_(file) {}

  void begin(const std::string& element, std::uint64_t index) {
    element_ = &element;
    index_ = index;
  }
  void end() {}

  double value(Scalar t) {
    need(scalar_size(t));
    double v = 0;
    switch (t) {
      case Scalar::i8: v = static_cast<std::int8_t>(*p_); break;
      case Scalar::u8: v = *p_; break;
      case Scalar::i16: v = load<std::int16_t>(); break;
      case Scalar::u16: v = load<std::uint16_t>(); break;
      case Scalar::i32: v = load<std::int32_t>(); break;
      case Scalar::u32: v = load<std::uint32_t>(); break;
      case Scalar::f32: v = load<float>(); break;
      case Scalar::f64: v = load<double>(); break;
    }
    p_ += scalar_size(t);
    return v;
  }
  // Integer types only (the header parser guarantees it for counts; callers check it for indices).
  std::int64_t integer(Scalar t) { return static_cast<std::int64_t>(value(t)); }
  void skip(Scalar t) {
    need(scalar_size(t));
    p_ += scalar_size(t);
  }
  // Skips `n` items of a list at once, after checking they are there.
  void skip_items(Scalar t, std::int64_t n) {
    if (static_cast<std::uint64_t>(n) > static_cast<std::uint64_t>(end_ - p_) / scalar_size(t))
      fail("unexpected end of file (list of " + std::to_string(n) + " " + scalar_name(t) + ")");
    p_ += n * scalar_size(t);
  }
  // Whether `n` list items of type t can still be read (so callers may reserve for them).
  bool has_items(Scalar t, std::int64_t n) const {
    return static_cast<std::uint64_t>(n) <= static_cast<std::uint64_t>(end_ - p_) / scalar_size(t);
  }

  [[noreturn]] void fail(const std::string& message) const {
    throw ParseError(file_, 0, *element_ + " " + std::to_string(index_) + ": " + message);
  }

  void finish() {}  // trailing bytes after the last element are tolerated (some writers pad)

 private:
  void need(int n) {
    if (end_ - p_ < n) fail("unexpected end of file");
  }
  template <class T>
  T load() {
    unsigned char b[sizeof(T)];
    std::memcpy(b, p_, sizeof(T));
    if (swap_) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }

  const unsigned char* p_;
  const unsigned char* end_;
  bool swap_;
  const std::string& file_;
  const std::string* element_ = nullptr;
  std::uint64_t index_ = 0;
};

class AsciiBody {
 public:
  AsciiBody(std::string_view body, int first_line, const std::string& file)
      : body_(body), lineno_(first_line - 1), file_(file) {}

  void begin(const std::string& element, std::uint64_t index) {
    element_ = &element;
    index_ = index;
    for (;;) {
      if (pos_ >= body_.size()) {
        ++lineno_;
        fail("expected a line of values, got the end of the file");
      }
      size_t nl = body_.find('\n', pos_);
      if (nl == std::string_view::npos) nl = body_.size();
      line_ = body_.substr(pos_, nl - pos_);
      pos_ = nl + 1;
      ++lineno_;
      if (line_.find_first_not_of(" \t\r") != std::string_view::npos) break;
    }
    col_ = 0;
  }
  void end() {
    const std::string_view extra = token_or_empty();
    if (!extra.empty()) fail("expected the end of the line, got " + quote_for_message(extra));
  }

  double value(Scalar t) {
    const std::string_view tok = token();
    if (is_integer(t)) return static_cast<double>(parse_integer(tok, t));
    const char* b = tok.data();
    const char* e = b + tok.size();
    if (t == Scalar::f32) {
      float f = 0;
      const auto r = std::from_chars(b, e, f);
      if (r.ptr != e || r.ec == std::errc::invalid_argument) fail("expected a float, got " + quote_for_message(tok));
      if (r.ec == std::errc::result_out_of_range) return parse_out_of_range(tok);
      return f;
    }
    double d = 0;
    const auto r = std::from_chars(b, e, d);
    if (r.ptr != e || r.ec == std::errc::invalid_argument) fail("expected a double, got " + quote_for_message(tok));
    if (r.ec == std::errc::result_out_of_range) return parse_out_of_range(tok);
    return d;
  }
  std::int64_t integer(Scalar t) { return parse_integer(token(), t); }
  void skip(Scalar t) { value(t); }
  void skip_items(Scalar t, std::int64_t n) {
    for (std::int64_t i = 0; i < n; ++i) value(t);
  }
  bool has_items(Scalar, std::int64_t n) const { return static_cast<std::uint64_t>(n) <= line_.size() / 2 + 1; }

  [[noreturn]] void fail(const std::string& message) const {
    throw ParseError(file_, lineno_, *element_ + " " + std::to_string(index_) + ": " + message);
  }

  void finish() {
    const size_t rest = body_.find_first_not_of(" \t\r\n", std::min(pos_, body_.size()));
    if (rest != std::string_view::npos) {
      const int line = lineno_ + 1 + static_cast<int>(std::count(body_.begin() + pos_, body_.begin() + rest, '\n'));
      throw ParseError(file_, line, "expected the end of the file after the last element, got " +
                                        quote_for_message(body_.substr(rest, body_.find('\n', rest) - rest)));
    }
  }

 private:
  std::string_view token_or_empty() {
    while (col_ < line_.size() && (line_[col_] == ' ' || line_[col_] == '\t' || line_[col_] == '\r')) ++col_;
    const size_t start = col_;
    while (col_ < line_.size() && line_[col_] != ' ' && line_[col_] != '\t' && line_[col_] != '\r') ++col_;
    return line_.substr(start, col_ - start);
  }
  std::string_view token() {
    const std::string_view tok = token_or_empty();
    if (tok.empty()) fail("expected more values on the line");
    return tok;
  }
  std::int64_t parse_integer(std::string_view tok, Scalar t) {
    std::int64_t v = 0, lo = 0, hi = 0;
    integer_range(t, &lo, &hi);
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (r.ec != std::errc() || r.ptr != tok.data() + tok.size() || v < lo || v > hi)
      fail(std::string("expected an integer of type ") + scalar_name(t) + " (" + std::to_string(lo) + ".." +
           std::to_string(hi) + "), got " + quote_for_message(tok));
    return v;
  }
  // from_chars reports overflow and underflow alike; keep the sign and the magnitude class.
  static double parse_out_of_range(std::string_view tok) {
    const std::string s(tok);
    return std::strtod(s.c_str(), nullptr);  // +-HUGE_VAL or a denormal/zero, as strtod defines
  }

  std::string_view body_;
  size_t pos_ = 0;
  int lineno_;
  std::string_view line_;
  size_t col_ = 0;
  const std::string& file_;
  const std::string* element_ = nullptr;
  std::uint64_t index_ = 0;
};

// ---------------------------------------------------------------------------------------------------------------
// The walker: maps header properties to mesh fields and reads every element in file order.

enum class Role : std::uint8_t { none, x, y, z, nx, ny, nz, r, g, b };

std::uint8_t to_color(double v, Scalar t) {
  double c = 0;
  switch (t) {
    case Scalar::f32:
    case Scalar::f64: c = v * 255.0; break;
    case Scalar::u16:
    case Scalar::i16: c = v * (255.0 / 65535.0); break;
    default: c = v; break;
  }
  if (!(c > 0)) return 0;  // also NaN
  if (c >= 255) return 255;
  return static_cast<std::uint8_t>(std::lround(c));
}

bool finite_float(double v) { return std::isfinite(v) && std::fabs(v) <= FLT_MAX; }

struct ReadLayout {
  const Element* vertex = nullptr;
  std::vector<Role> vertex_roles;
  bool normals = false, colors = false;
};

int find_property(const Element& e, std::initializer_list<const char*> names) {
  for (const char* n : names)
    for (size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].name == n) return static_cast<int>(i);
  return -1;
}

ReadLayout plan_vertex(const Header& h, const std::string& file) {
  ReadLayout L;
  for (const Element& e : h.elements)
    if (e.name == "vertex") L.vertex = &e;
  if (!L.vertex) throw ParseError(file, h.end_header_line, "expected an element 'vertex' in the header");
  const Element& v = *L.vertex;
  if (v.count > static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
    throw ParseError(file, v.header_line, "expected at most 2^31-1 vertices, got " + std::to_string(v.count));
  L.vertex_roles.assign(v.properties.size(), Role::none);

  auto assign = [&](std::initializer_list<std::initializer_list<const char*>> names, std::initializer_list<Role> roles,
                    const char* what, bool required) {
    std::vector<int> idx;
    for (const auto& n : names) idx.push_back(find_property(v, n));
    const auto found = std::count_if(idx.begin(), idx.end(), [](int i) { return i >= 0; });
    if (found == 0) {
      if (required) throw ParseError(file, v.header_line, std::string("expected properties ") + what + " in element 'vertex'");
      return false;
    }
    if (found != static_cast<long>(idx.size()))
      throw ParseError(file, v.header_line, std::string("expected all or none of the properties ") + what +
                                                " in element 'vertex'");
    auto role = roles.begin();
    for (int i : idx) {
      if (v.properties[i].is_list)
        throw ParseError(file, v.header_line, "expected property '" + v.properties[i].name + "' to be a scalar, got a list");
      L.vertex_roles[i] = *role++;
    }
    return true;
  };
  assign({{"x"}, {"y"}, {"z"}}, {Role::x, Role::y, Role::z}, "x, y, z", true);
  L.normals = assign({{"nx", "normal_x"}, {"ny", "normal_y"}, {"nz", "normal_z"}}, {Role::nx, Role::ny, Role::nz},
                     "nx, ny, nz", false);
  L.colors = assign({{"red", "r", "diffuse_red"}, {"green", "g", "diffuse_green"}, {"blue", "b", "diffuse_blue"}},
                    {Role::r, Role::g, Role::b}, "red, green, blue", false);
  return L;
}

// Index of the vertex-index list of a face-like element, or throws.
int plan_index_list(const Element& e, const std::string& file) {
  const int i = find_property(e, {"vertex_indices", "vertex_index"});
  if (i < 0) throw ParseError(file, e.header_line, "expected a list property 'vertex_indices' in element '" + e.name + "'");
  const Property& p = e.properties[i];
  if (!p.is_list || !is_integer(p.type))
    throw ParseError(file, e.header_line, "expected '" + p.name + "' to be a list of integers");
  return i;
}

template <class Body>
void read_body(Body& in, const Header& h, const ReadLayout& L, TriangleMesh* out, bool keep_faces,
               const std::string& file) {
  const std::int64_t nverts = static_cast<std::int64_t>(L.vertex->count);
  std::vector<std::int64_t> list;
  for (const Element& e : h.elements) {
    if (e.properties.empty()) continue;  // nothing stored, whatever the count
    const bool is_vertex = &e == L.vertex;
    const bool is_face = e.name == "face";
    const bool is_strips = e.name == "tristrips";
    const int list_prop = (is_face || is_strips) ? plan_index_list(e, file) : -1;
    if (is_vertex) {
      out->vertices.reserve(e.count);
      if (L.normals) out->normals.reserve(e.count);
      if (L.colors) out->colors.reserve(e.count);
    }
    for (std::uint64_t k = 0; k < e.count; ++k) {
      in.begin(e.name, k);
      double xyz[3] = {0, 0, 0}, n[3] = {0, 0, 0};
      std::uint8_t rgb[3] = {0, 0, 0};
      for (size_t pi = 0; pi < e.properties.size(); ++pi) {
        const Property& p = e.properties[pi];
        if (p.is_list) {
          const std::int64_t count = in.integer(p.count_type);
          if (count < 0) in.fail("expected a non-negative list length for '" + p.name + "', got " + std::to_string(count));
          if (static_cast<int>(pi) != list_prop) {
            in.skip_items(p.type, count);
            continue;
          }
          if (!in.has_items(p.type, count)) in.fail("unexpected end of " + std::string(std::is_same_v<Body, BinaryBody> ? "file" : "line") +
                                                    " in a list of " + std::to_string(count) + " vertex indices");
          list.resize(static_cast<size_t>(count));
          for (std::int64_t j = 0; j < count; ++j) {
            const std::int64_t idx = in.integer(p.type);
            const bool restart = is_strips && idx == -1;
            if (!restart && (idx < 0 || idx >= nverts))
              in.fail("expected vertex indices in [0, " + std::to_string(nverts) + "), got " + std::to_string(idx));
            list[j] = idx;
          }
          continue;
        }
        if (!is_vertex) {
          in.skip(p.type);
          continue;
        }
        const double v = in.value(p.type);
        switch (L.vertex_roles[pi]) {
          case Role::x: xyz[0] = v; break;
          case Role::y: xyz[1] = v; break;
          case Role::z: xyz[2] = v; break;
          case Role::nx: n[0] = v; break;
          case Role::ny: n[1] = v; break;
          case Role::nz: n[2] = v; break;
          case Role::r: rgb[0] = to_color(v, p.type); break;
          case Role::g: rgb[1] = to_color(v, p.type); break;
          case Role::b: rgb[2] = to_color(v, p.type); break;
          case Role::none: break;
        }
      }
      in.end();
      if (is_vertex) {
        if (!finite_float(xyz[0]) || !finite_float(xyz[1]) || !finite_float(xyz[2]))
          in.fail("expected finite float coordinates, got (" + std::to_string(xyz[0]) + ", " + std::to_string(xyz[1]) +
                  ", " + std::to_string(xyz[2]) + ")");
        out->vertices.emplace_back(static_cast<float>(xyz[0]), static_cast<float>(xyz[1]), static_cast<float>(xyz[2]));
        if (L.normals) {
          if (!finite_float(n[0]) || !finite_float(n[1]) || !finite_float(n[2]))
            in.fail("expected a finite float normal, got (" + std::to_string(n[0]) + ", " + std::to_string(n[1]) + ", " +
                    std::to_string(n[2]) + ")");
          out->normals.emplace_back(static_cast<float>(n[0]), static_cast<float>(n[1]), static_cast<float>(n[2]));
        }
        if (L.colors) out->colors.push_back(Rgb8{rgb[0], rgb[1], rgb[2]});
      } else if (is_face && keep_faces) {
        for (size_t j = 2; j < list.size(); ++j)  // fan (0, j-1, j); fewer than 3 corners have no area
          out->triangles.emplace_back(static_cast<int>(list[0]), static_cast<int>(list[j - 1]), static_cast<int>(list[j]));
      } else if (is_strips && keep_faces) {
        size_t start = 0;
        for (size_t j = 0; j <= list.size(); ++j) {
          if (j < list.size() && list[j] != -1) continue;
          for (size_t t = start; t + 2 < j; ++t) {
            int a = static_cast<int>(list[t]), b = static_cast<int>(list[t + 1]);
            const int c = static_cast<int>(list[t + 2]);
            if ((t - start) % 2 == 1) std::swap(a, b);
            if (a != b && b != c && a != c) out->triangles.emplace_back(a, b, c);
          }
          start = j + 1;
        }
      }
    }
  }
  in.finish();
}

TriangleMesh parse(std::string_view bytes, const std::string& file, bool keep_faces) {
  const Header h = parse_header(bytes, file);
  const std::string_view body = bytes.substr(h.body_offset);
  check_counts_fit(h, body.size(), file);
  const ReadLayout L = plan_vertex(h, file);
  for (const Element& e : h.elements)  // report a bad face declaration before reading any body
    if (e.name == "face" || e.name == "tristrips") plan_index_list(e, file);
  TriangleMesh mesh;
  if (h.format == PlyFormat::ascii) {
    AsciiBody in(body, h.end_header_line + 1, file);
    read_body(in, h, L, &mesh, keep_faces, file);
  } else {
    BinaryBody in(body, h.format == PlyFormat::binary_big_endian, file);
    read_body(in, h, L, &mesh, keep_faces, file);
  }
  return mesh;
}

std::string read_all(const std::string& path) { return read_regular_file(path, "PLY file", kMaxModelFileBytes); }

// ---------------------------------------------------------------------------------------------------------------
// Writing. Bytes go to a buffer that is handed to the stream every MiB, so large meshes are not held twice.

class Sink {
 public:
  Sink(PlyFormat format, std::ostream* out) : format_(format), out_(out) {}
  std::string& text() { return buf_; }

  void f32(float v, char sep) {
    if (format_ == PlyFormat::ascii) {
      char tmp[32];
      const auto r = std::to_chars(tmp, tmp + sizeof(tmp), v);  // shortest round-trip form
      buf_.append(tmp, r.ptr);
      buf_ += sep;
    } else {
      raw(v);
    }
  }
  void u8(std::uint8_t v, char sep) {
    if (format_ == PlyFormat::ascii) {
      buf_ += std::to_string(v);
      buf_ += sep;
    } else {
      buf_ += static_cast<char>(v);
    }
  }
  void i32(std::int32_t v, char sep) {
    if (format_ == PlyFormat::ascii) {
      buf_ += std::to_string(v);
      buf_ += sep;
    } else {
      raw(v);
    }
  }
  void maybe_flush() {
    if (out_ && buf_.size() > (1u << 20)) flush();
  }
  void flush() {
    if (out_) {
      out_->write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
      buf_.clear();
    }
  }

 private:
  template <class T>
  void raw(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    const bool big = format_ == PlyFormat::binary_big_endian;
    if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
    buf_.append(b, sizeof(T));
  }

  PlyFormat format_;
  std::ostream* out_;
  std::string buf_;
};

void write_all(Sink& s, const PlyWriteOptions& o, const std::vector<Eigen::Vector3f>& positions,
               const std::vector<Eigen::Vector3f>& normals, const std::vector<Rgb8>& colors,
               const std::vector<Eigen::Vector3i>* triangles) {
  std::string& h = s.text();
  h += "ply\nformat ";
  h += o.format == PlyFormat::ascii                  ? "ascii"
       : o.format == PlyFormat::binary_little_endian ? "binary_little_endian"
                                                      : "binary_big_endian";
  h += " 1.0\n";
  if (!o.comment.empty()) {
    std::istringstream lines(o.comment);
    std::string line;
    while (std::getline(lines, line)) h += "comment " + line + "\n";
  }
  h += "element vertex " + std::to_string(positions.size()) + "\n";
  h += "property float x\nproperty float y\nproperty float z\n";
  if (!normals.empty()) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (!colors.empty()) h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (triangles) {
    h += "element face " + std::to_string(triangles->size()) + "\n";
    h += "property list uchar int vertex_indices\n";
  }
  h += "end_header\n";

  const bool has_n = !normals.empty(), has_c = !colors.empty();
  for (size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector3f& p = positions[i];
    const char last = (has_n || has_c) ? ' ' : '\n';
    s.f32(p.x(), ' ');
    s.f32(p.y(), ' ');
    s.f32(p.z(), last);
    if (has_n) {
      s.f32(normals[i].x(), ' ');
      s.f32(normals[i].y(), ' ');
      s.f32(normals[i].z(), has_c ? ' ' : '\n');
    }
    if (has_c) {
      s.u8(colors[i].r, ' ');
      s.u8(colors[i].g, ' ');
      s.u8(colors[i].b, '\n');
    }
    s.maybe_flush();
  }
  if (triangles) {
    for (const Eigen::Vector3i& t : *triangles) {
      s.u8(3, ' ');
      s.i32(t.x(), ' ');
      s.i32(t.y(), ' ');
      s.i32(t.z(), '\n');
      s.maybe_flush();
    }
  }
  s.flush();
}

}  // namespace

TriangleMesh parse_ply_mesh(std::string_view bytes, const std::string& name_for_errors) {
  return parse(bytes, name_for_errors, true);
}

TriangleMesh read_ply_mesh(const std::string& path) { return parse_ply_mesh(read_all(path), path); }

PointCloud parse_ply_point_cloud(std::string_view bytes, const std::string& name_for_errors) {
  TriangleMesh m = parse(bytes, name_for_errors, false);
  PointCloud c;
  c.positions = std::move(m.vertices);
  c.normals = std::move(m.normals);
  c.colors = std::move(m.colors);
  return c;
}

PointCloud read_ply_point_cloud(const std::string& path) { return parse_ply_point_cloud(read_all(path), path); }

std::string format_ply(const TriangleMesh& mesh, const PlyWriteOptions& options) {
  mesh.validate();
  Sink s(options.format, nullptr);
  write_all(s, options, mesh.vertices, mesh.normals, mesh.colors, &mesh.triangles);
  return std::move(s.text());
}

std::string format_ply(const PointCloud& cloud, const PlyWriteOptions& options) {
  cloud.validate();
  Sink s(options.format, nullptr);
  write_all(s, options, cloud.positions, cloud.normals, cloud.colors, nullptr);
  return std::move(s.text());
}

void write_ply(const std::string& path, const TriangleMesh& mesh, const PlyWriteOptions& options) {
  mesh.validate();
  write_file_atomically(
      path,
      [&](std::ostream& out) {
        Sink s(options.format, &out);
        write_all(s, options, mesh.vertices, mesh.normals, mesh.colors, &mesh.triangles);
      },
      true);
}

void write_ply(const std::string& path, const PointCloud& cloud, const PlyWriteOptions& options) {
  cloud.validate();
  write_file_atomically(
      path,
      [&](std::ostream& out) {
        Sink s(options.format, &out);
        write_all(s, options, cloud.positions, cloud.normals, cloud.colors, nullptr);
      },
      true);
}

}  // namespace hf
