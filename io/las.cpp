#include "io/las.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <tuple>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/number_text.h"
#include "core/regular_path.h"
#include "io/las_limits.h"

namespace hf {
namespace {

// LAS is little-endian; values are assembled byte by byte so the reader does not depend on the host's order.
std::uint64_t get_le(const char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<std::uint8_t>(p[i]);
  return v;
}
std::uint16_t get_u16(const char* p) { return static_cast<std::uint16_t>(get_le(p, 2)); }
std::uint32_t get_u32(const char* p) { return static_cast<std::uint32_t>(get_le(p, 4)); }
std::int32_t get_i32(const char* p) { return static_cast<std::int32_t>(get_u32(p)); }
double get_f64(const char* p) { return std::bit_cast<double>(get_le(p, 8)); }
std::string get_text(const char* p, int bytes) {
  std::string s(p, static_cast<size_t>(bytes));
  s.resize(std::strlen(s.c_str()));
  return s;
}

void put_le(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void put_f64(std::string& out, double v) { put_le(out, std::bit_cast<std::uint64_t>(v), 8); }
void put_text(std::string& out, const std::string& s, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(i < static_cast<int>(s.size()) ? s[static_cast<size_t>(i)] : '\0');
}

[[noreturn]] void fail(const std::string& name, std::uint64_t byte, const std::string& what) {
  throw Error(name + ": byte " + std::to_string(byte) + ": " + what);
}

bool has_gps(int f) { return f == 1 || f >= 3; }
bool has_rgb(int f) { return f == 2 || f == 3 || f == 5 || f == 7 || f == 8 || f == 10; }
bool has_nir(int f) { return f == 8 || f == 10; }
// Offset of the GPS time / RGB inside a record, after the fields that precede it.
int gps_at(int f) { return f >= 6 ? 22 : 20; }
int rgb_at(int f) { return f >= 6 ? 30 : (f == 2 ? 20 : 28); }

constexpr int kVlrHeader = 54;
constexpr std::uint16_t kLaszipRecordId = 22204;  // the LASzip VLR ("laszip encoded")

void decode_point(const char* r, const LasHeader& h, LasPoint& p) {
  const int f = h.point_format;
  p.x = get_i32(r) * h.scale[0] + h.offset[0];
  p.y = get_i32(r + 4) * h.scale[1] + h.offset[1];
  p.z = get_i32(r + 8) * h.scale[2] + h.offset[2];
  p.intensity = get_u16(r + 12);
  const auto b14 = static_cast<std::uint8_t>(r[14]);
  const auto b15 = static_cast<std::uint8_t>(r[15]);
  if (f <= 5) {
    p.return_number = b14 & 7;
    p.number_of_returns = (b14 >> 3) & 7;
    p.classification = b15 & 31;
    p.synthetic = b15 & 32;
    p.key_point = b15 & 64;
    p.withheld = b15 & 128;
    p.overlap = false;
    p.scanner_channel = 0;
    p.scan_angle_deg = static_cast<float>(static_cast<std::int8_t>(r[16]));
    p.user_data = static_cast<std::uint8_t>(r[17]);
    p.point_source_id = get_u16(r + 18);
  } else {
    p.return_number = b14 & 15;
    p.number_of_returns = b14 >> 4;
    p.synthetic = b15 & 1;
    p.key_point = b15 & 2;
    p.withheld = b15 & 4;
    p.overlap = b15 & 8;
    p.scanner_channel = (b15 >> 4) & 3;
    p.classification = static_cast<std::uint8_t>(r[16]);
    p.user_data = static_cast<std::uint8_t>(r[17]);
    p.scan_angle_deg = static_cast<float>(static_cast<std::int16_t>(get_u16(r + 18)) * 0.006);
    p.point_source_id = get_u16(r + 20);
  }
  p.gps_time = has_gps(f) ? get_f64(r + gps_at(f)) : 0.0;
  if (has_rgb(f)) {
    p.red = get_u16(r + rgb_at(f));
    p.green = get_u16(r + rgb_at(f) + 2);
    p.blue = get_u16(r + rgb_at(f) + 4);
  } else {
    p.red = p.green = p.blue = 0;
  }
  p.nir = has_nir(f) ? get_u16(r + 36) : 0;
}

}  // namespace

int las_min_record_length(int point_format) {
  static constexpr int kLengths[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return point_format >= 0 && point_format <= 10 ? kLengths[point_format] : -1;
}

int las_header_size(int version_minor) { return version_minor >= 4 ? 375 : (version_minor == 3 ? 235 : 227); }

LasReader::LasReader(const std::string& path) : name_(path) {
  require_regular_path(path, "LAS file");  // an ifstream on a FIFO blocks in open() forever
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary | std::ios::ate);
  if (!*file) throw Error(path + ": cannot open LAS file");
  const std::streamoff end = file->tellg();
  if (end < 0) throw Error(path + ": cannot determine the file size");
  size_ = static_cast<std::uint64_t>(end);
  file->seekg(0);
  owned_ = std::move(file);
  in_ = owned_.get();
  read_header();
}

LasReader::LasReader(std::istream& in, std::uint64_t size, std::string name) : in_(&in), size_(size), name_(std::move(name)) {
  read_header();
}

LasReader::~LasReader() = default;

void LasReader::read_header() {
  LasHeader& h = header_;
  char b[375] = {};
  const std::uint64_t head = std::min<std::uint64_t>(size_, 375);
  in_->seekg(0);
  in_->read(b, static_cast<std::streamsize>(head));
  if (static_cast<std::uint64_t>(in_->gcount()) != head) fail(name_, 0, "cannot read the header");
  if (head < 4 || std::memcmp(b, "LASF", 4) != 0) fail(name_, 0, "not a LAS file (no 'LASF' signature)");
  if (head < 227) fail(name_, head, "header truncated (" + std::to_string(head) + " of at least 227 bytes)");
  h.file_source_id = get_u16(b + 4);
  h.global_encoding = get_u16(b + 6);
  h.version_major = static_cast<std::uint8_t>(b[24]);
  h.version_minor = static_cast<std::uint8_t>(b[25]);
  if (h.version_major != 1 || h.version_minor > 4)
    fail(name_, 24, "unsupported LAS version " + std::to_string(h.version_major) + "." + std::to_string(h.version_minor) +
                        " (1.0-1.4 are read)");
  h.system_id = get_text(b + 26, 32);
  h.generating_software = get_text(b + 58, 32);
  h.header_size = get_u16(b + 94);
  h.offset_to_point_data = get_u32(b + 96);
  const std::uint32_t vlr_count = get_u32(b + 100);
  const int format_byte = static_cast<std::uint8_t>(b[104]);
  h.record_length = get_u16(b + 105);
  h.point_count = get_u32(b + 107);
  for (int i = 0; i < 3; ++i) {
    h.scale[i] = get_f64(b + 131 + 8 * i);
    h.offset[i] = get_f64(b + 155 + 8 * i);
    h.max[i] = get_f64(b + 179 + 16 * i);
    h.min[i] = get_f64(b + 187 + 16 * i);
  }
  const int min_header = las_header_size(h.version_minor);
  if (h.header_size < min_header)
    fail(name_, 94, "header size " + std::to_string(h.header_size) + " below the " + std::to_string(min_header) +
                        " bytes of LAS 1." + std::to_string(h.version_minor));
  if (h.version_minor >= 4) {
    if (size_ < 375) fail(name_, size_, "LAS 1.4 header truncated");
    const std::uint64_t count64 = get_le(b + 247, 8);
    if (count64 != 0 || h.point_count == 0) h.point_count = count64;
  }
  if (h.offset_to_point_data < h.header_size)
    fail(name_, 96, "point data offset " + std::to_string(h.offset_to_point_data) + " inside the header");
  if (h.offset_to_point_data > size_)
    fail(name_, 96, "point data offset " + std::to_string(h.offset_to_point_data) + " beyond the end of the file (" +
                        std::to_string(size_) + " bytes)");

  // VLRs lie between the header and the point data; the LASzip one marks a compressed file.
  bool laszip = (format_byte & 0x80) != 0;
  std::uint64_t at = h.header_size;
  for (std::uint32_t i = 0; i < vlr_count; ++i) {
    if (at + kVlrHeader > h.offset_to_point_data)
      fail(name_, at, "VLR " + std::to_string(i + 1) + " of " + std::to_string(vlr_count) + " runs into the point data");
    char v[kVlrHeader];
    in_->seekg(static_cast<std::streamoff>(at));
    in_->read(v, kVlrHeader);
    if (in_->gcount() != kVlrHeader) fail(name_, at, "VLR header truncated");
    LasVlr vlr;
    vlr.user_id = get_text(v + 2, 16);
    vlr.record_id = get_u16(v + 18);
    const std::uint16_t length = get_u16(v + 20);
    vlr.description = get_text(v + 22, 32);
    if (at + kVlrHeader + length > h.offset_to_point_data)
      fail(name_, at + 20, "VLR " + std::to_string(i + 1) + " length " + std::to_string(length) + " runs into the point data");
    vlr.data.resize(length);
    in_->read(reinterpret_cast<char*>(vlr.data.data()), length);
    if (in_->gcount() != length) fail(name_, at + kVlrHeader, "VLR data truncated");
    if (vlr.user_id == "laszip encoded" && vlr.record_id == kLaszipRecordId) laszip = true;
    h.vlrs.push_back(std::move(vlr));
    at += kVlrHeader + length;
  }
  if (laszip)
    throw Error(name_ + ": LAZ-compressed point data; decompress it first (e.g. `laszip -i " + name_ + " -o out.las`)");

  h.point_format = format_byte & 0x3f;
  const int min_length = las_min_record_length(h.point_format);
  if (min_length < 0) fail(name_, 104, "unsupported point data format " + std::to_string(h.point_format) + " (0-10 are read)");
  if (h.point_format >= 6 && h.version_minor < 4)
    fail(name_, 104, "point data format " + std::to_string(h.point_format) + " needs LAS 1.4");
  if (h.record_length < min_length)
    fail(name_, 105, "point record length " + std::to_string(h.record_length) + " below the " + std::to_string(min_length) +
                         " bytes of format " + std::to_string(h.point_format));
  // Physical bounds (io/las.h): a scale of 1e300 is finite, yet makes every coordinate and grid size absurd.
  static const char* const kAxis[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    const std::string axis = kAxis[i];
    if (!(std::fabs(h.scale[i]) >= kLasMinScale && std::fabs(h.scale[i]) <= kLasMaxScale))
      fail(name_, 131 + 8 * i,
           axis + " scale factor " + number_for_message(h.scale[i]) + " outside " + number_for_message(kLasMinScale) +
               ".." + number_for_message(kLasMaxScale) + " (units per integer step)");
    if (!(std::fabs(h.offset[i]) <= kLasMaxOffset))
      fail(name_, 155 + 8 * i, axis + " offset " + number_for_message(h.offset[i]) + " beyond " +
                                   number_for_message(kLasMaxOffset));
    for (const auto& [value, at, what] : {std::tuple{h.max[i], 179 + 16 * i, " bounding box maximum "},
                                          std::tuple{h.min[i], 187 + 16 * i, " bounding box minimum "}})
      if (!(std::fabs(value) <= kLasMaxCoordinate))
        fail(name_, std::uint64_t(at), axis + what + number_for_message(value) + " beyond " +
                                           number_for_message(kLasMaxCoordinate));
  }
  // A count that lies is caught here, before any point is read: the records must fit in the file.
  const std::uint64_t room = size_ - h.offset_to_point_data;
  if (h.point_count > room / h.record_length) {
    const std::uint64_t whole = room / h.record_length;
    fail(name_, h.offset_to_point_data + whole * h.record_length,
         "point record " + std::to_string(whole + 1) + " of " + std::to_string(h.point_count) + " truncated (file is " +
             std::to_string(size_) + " bytes)");
  }
  in_->seekg(h.offset_to_point_data);
}

bool LasReader::read_chunk(std::vector<LasPoint>& out, std::size_t max_points) {
  out.clear();
  const std::uint64_t left = header_.point_count - next_;
  const std::uint64_t n = std::min<std::uint64_t>(left, std::max<std::size_t>(max_points, 1));
  if (n == 0) return false;
  const std::size_t length = header_.record_length;
  raw_.resize(static_cast<std::size_t>(n) * length);
  const std::uint64_t at = header_.offset_to_point_data + next_ * length;
  in_->seekg(static_cast<std::streamoff>(at));
  in_->read(raw_.data(), static_cast<std::streamsize>(raw_.size()));
  if (static_cast<std::uint64_t>(in_->gcount()) != raw_.size())
    fail(name_, at + static_cast<std::uint64_t>(std::max<std::streamsize>(in_->gcount(), 0)),
         "point data truncated while reading (the file changed?)");
  out.resize(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < out.size(); ++i) decode_point(raw_.data() + i * length, header_, out[i]);
  next_ += n;
  return true;
}

int las_epsg(const LasHeader& header) {
  int geographic = 0;
  for (const LasVlr& v : header.vlrs) {
    if (v.user_id != "LASF_Projection" || v.record_id != 34735 || v.data.size() < 8) continue;
    const auto key = [&](size_t i) { return get_u16(reinterpret_cast<const char*>(v.data.data()) + 2 * i); };
    const size_t keys = std::min<size_t>(key(3), v.data.size() / 8 - 1);
    for (size_t k = 1; k <= keys; ++k) {
      // Each key: id, tag location (0 = the value is inline), count, value.
      if (key(4 * k + 1) != 0) continue;
      if (key(4 * k) == 3072) return key(4 * k + 3);  // ProjectedCSTypeGeoKey
      if (key(4 * k) == 2048) geographic = key(4 * k + 3);  // GeographicTypeGeoKey
    }
  }
  return geographic;
}

std::vector<LasPoint> read_las(const std::string& path, LasHeader* header) {
  LasReader reader(path);
  std::vector<LasPoint> all, chunk;
  all.reserve(static_cast<std::size_t>(reader.header().point_count));
  while (reader.read_chunk(chunk)) all.insert(all.end(), chunk.begin(), chunk.end());
  if (header) *header = reader.header();
  return all;
}

std::string format_las(const LasHeader& h, const std::vector<LasPoint>& points, const std::string& name) {
  const int f = h.point_format;
  const int min_length = las_min_record_length(f);
  const int length = std::max<int>(min_length, h.record_length);  // a longer record carries zeroed extra bytes
  if (min_length < 0) throw Error(name + ": cannot write point data format " + std::to_string(f));
  if (h.version_minor < 0 || h.version_minor > 4) throw Error(name + ": cannot write LAS 1." + std::to_string(h.version_minor));
  if (f >= 6 && h.version_minor < 4) throw Error(name + ": point data format " + std::to_string(f) + " needs LAS 1.4");
  for (double s : h.scale)
    if (!std::isfinite(s) || s == 0.0) throw Error(name + ": scale factor must be finite and non-zero");
  const int header_size = las_header_size(h.version_minor);
  std::uint64_t vlr_bytes = 0;
  for (const LasVlr& v : h.vlrs) {
    if (v.data.size() > 65535) throw Error(name + ": VLR data over 65535 bytes");
    vlr_bytes += kVlrHeader + v.data.size();
  }
  if (points.size() > std::numeric_limits<std::uint32_t>::max() && h.version_minor < 4)
    throw Error(name + ": more than 2^32 points need LAS 1.4");

  // Integer coordinates first: the header's bounding box is that of the stored (rounded) positions.
  std::vector<std::int32_t> xyz(points.size() * 3);
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  std::uint64_t by_return[15] = {};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double v[3] = {points[i].x, points[i].y, points[i].z};
    for (int k = 0; k < 3; ++k) {
      const double q = std::round((v[k] - h.offset[k]) / h.scale[k]);
      if (!(q >= std::numeric_limits<std::int32_t>::min() && q <= std::numeric_limits<std::int32_t>::max()))
        throw Error(name + ": point " + std::to_string(i) + " does not fit the 32-bit coordinate range at this scale/offset");
      xyz[i * 3 + k] = static_cast<std::int32_t>(q);
      const double stored = q * h.scale[k] + h.offset[k];
      lo[k] = i == 0 ? stored : std::min(lo[k], stored);
      hi[k] = i == 0 ? stored : std::max(hi[k], stored);
    }
    const int r = points[i].return_number;
    if (r >= 1 && r <= 15) ++by_return[r - 1];
  }

  std::string out;
  out.reserve(header_size + vlr_bytes + points.size() * length);
  out += "LASF";
  put_le(out, h.file_source_id, 2);
  put_le(out, h.global_encoding, 2);
  put_text(out, "", 16);  // GUID
  out.push_back(1);
  out.push_back(static_cast<char>(h.version_minor));
  put_text(out, h.system_id, 32);
  put_text(out, h.generating_software.empty() ? "hashfusion" : h.generating_software, 32);
  put_le(out, 1, 2);     // creation day of year
  put_le(out, 2026, 2);  // creation year
  put_le(out, header_size, 2);
  put_le(out, header_size + vlr_bytes, 4);
  put_le(out, h.vlrs.size(), 4);
  out.push_back(static_cast<char>(f));
  put_le(out, length, 2);
  const bool legacy = points.size() <= std::numeric_limits<std::uint32_t>::max() && f <= 5;
  put_le(out, legacy ? points.size() : 0, 4);
  for (int r = 0; r < 5; ++r) put_le(out, legacy ? by_return[r] : 0, 4);
  for (double s : h.scale) put_f64(out, s);
  for (double o : h.offset) put_f64(out, o);
  for (int k = 0; k < 3; ++k) {
    put_f64(out, hi[k]);
    put_f64(out, lo[k]);
  }
  if (h.version_minor >= 3) put_le(out, 0, 8);  // start of waveform data packet record
  if (h.version_minor >= 4) {
    put_le(out, 0, 8);  // start of the first EVLR
    put_le(out, 0, 4);  // number of EVLRs
    put_le(out, points.size(), 8);
    for (std::uint64_t n : by_return) put_le(out, n, 8);
  }
  for (const LasVlr& v : h.vlrs) {
    put_le(out, 0, 2);
    put_text(out, v.user_id, 16);
    put_le(out, v.record_id, 2);
    put_le(out, v.data.size(), 2);
    put_text(out, v.description, 32);
    out.append(reinterpret_cast<const char*>(v.data.data()), v.data.size());
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const LasPoint& p = points[i];
    const std::size_t start = out.size();
    for (int k = 0; k < 3; ++k) put_le(out, static_cast<std::uint32_t>(xyz[i * 3 + k]), 4);
    put_le(out, p.intensity, 2);
    if (f <= 5) {
      out.push_back(static_cast<char>((p.return_number & 7) | ((p.number_of_returns & 7) << 3)));
      out.push_back(static_cast<char>((p.classification & 31) | (p.synthetic ? 32 : 0) | (p.key_point ? 64 : 0) |
                                      (p.withheld ? 128 : 0)));
      out.push_back(static_cast<char>(static_cast<std::int8_t>(std::clamp(std::lround(p.scan_angle_deg), -128L, 127L))));
      out.push_back(static_cast<char>(p.user_data));
      put_le(out, p.point_source_id, 2);
    } else {
      out.push_back(static_cast<char>((p.return_number & 15) | ((p.number_of_returns & 15) << 4)));
      out.push_back(static_cast<char>((p.synthetic ? 1 : 0) | (p.key_point ? 2 : 0) | (p.withheld ? 4 : 0) |
                                      (p.overlap ? 8 : 0) | ((p.scanner_channel & 3) << 4)));
      out.push_back(static_cast<char>(p.classification));
      out.push_back(static_cast<char>(p.user_data));
      const long angle = std::clamp(std::lround(p.scan_angle_deg / 0.006), -30000L, 30000L);
      put_le(out, static_cast<std::uint16_t>(static_cast<std::int16_t>(angle)), 2);
      put_le(out, p.point_source_id, 2);
    }
    if (has_gps(f)) put_f64(out, p.gps_time);
    if (has_rgb(f)) {
      put_le(out, p.red, 2);
      put_le(out, p.green, 2);
      put_le(out, p.blue, 2);
    }
    if (has_nir(f)) put_le(out, p.nir, 2);
    out.resize(start + static_cast<std::size_t>(length), '\0');  // waveform packet fields left zero
  }
  return out;
}

void write_las(const std::string& path, const LasHeader& header, const std::vector<LasPoint>& points) {
  const std::string bytes = format_las(header, points, path);
  write_file_atomically(path, [&](std::ostream& os) { os.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); },
                        true);
}

}  // namespace hf
