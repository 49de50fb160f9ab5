// ASPRS LAS 1.0-1.4 point clouds: header, variable length records, point data formats 0-10, read in chunks.
//
// Coordinates on disk are 32-bit integers; a point's position is X * scale + offset (metres in the file's CRS,
// which LAS keeps in a VLR or not at all). Classification is the 5-bit field of formats 0-5 or the 8-bit
// extended field of formats 6-10 (ASPRS codes: 2 ground, 6 building, ...). Extra bytes beyond a format's
// minimum record length are skipped; waveform packets are not decoded.
//
// Streaming: LasReader keeps one chunk of raw records in memory, so files larger than memory can be read.
// LAZ (LASzip-compressed) files are detected (point format bit 7, or the LASzip VLR) and refused with one line
// that names the file and says to decompress first (e.g. `laszip -i in.laz -o out.las`).
//
// Failures: every malformed input throws hf::Error whose message starts "FILE: byte N: " (N = the offset of the
// offending field or record): bad signature, unsupported version or point format, header or VLRs running past
// the point data, a record length below the format's minimum, zero or non-finite scale, and a point count that
// promises more records than the file holds (checked before any point is read). Never a crash.
// Thread-safety: a LasReader is used from one thread; distinct readers share nothing.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace hf {

struct LasVlr {
  std::string user_id;      // up to 16 characters, e.g. "LASF_Projection"
  std::uint16_t record_id = 0;
  std::string description;  // up to 32 characters
  std::vector<std::uint8_t> data;
};

struct LasHeader {
  int version_major = 1, version_minor = 2;
  std::uint16_t file_source_id = 0, global_encoding = 0;
  std::string system_id, generating_software;
  std::uint16_t header_size = 0;          // bytes of the public header block on disk
  std::uint32_t offset_to_point_data = 0;
  int point_format = 0;                   // 0-10
  std::uint16_t record_length = 0;        // bytes per point record (>= las_min_record_length(point_format))
  std::uint64_t point_count = 0;          // the 64-bit count of LAS 1.4, else the legacy 32-bit one
  double scale[3] = {0.01, 0.01, 0.01};   // metres per integer unit, x y z
  double offset[3] = {0, 0, 0};
  double min[3] = {0, 0, 0}, max[3] = {0, 0, 0};  // bounding box the header states (metres)
  std::vector<LasVlr> vlrs;
};

struct LasPoint {
  double x = 0, y = 0, z = 0;  // scaled and offset: metres in the file's CRS
  std::uint16_t intensity = 0;
  std::uint8_t return_number = 0, number_of_returns = 0;
  std::uint8_t classification = 0;  // 0-31 for formats 0-5, 0-255 for formats 6-10
  bool synthetic = false, key_point = false, withheld = false, overlap = false;  // overlap: formats 6-10 only
  std::uint8_t scanner_channel = 0;  // formats 6-10
  float scan_angle_deg = 0;          // formats 0-5: the rank in whole degrees; 6-10: 0.006 degree units
  std::uint8_t user_data = 0;
  std::uint16_t point_source_id = 0;
  double gps_time = 0;                       // formats 1, 3-10
  std::uint16_t red = 0, green = 0, blue = 0;  // formats 2, 3, 5, 7, 8, 10
  std::uint16_t nir = 0;                     // formats 8, 10
};

// Minimum record length of a point data format (20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67); -1 for others.
int las_min_record_length(int point_format);
// Size of the public header block of a LAS minor version (227 for 1.0-1.2, 235 for 1.3, 375 for 1.4).
int las_header_size(int version_minor);

class LasReader {
 public:
  // Opens and validates `path` (header, VLRs, the point count against the file size). Throws hf::Error.
  explicit LasReader(const std::string& path);
  // Reads from a stream of `size` bytes (tests, fuzzing); `name` appears in error messages. The stream must
  // outlive the reader.
  LasReader(std::istream& in, std::uint64_t size, std::string name);
  ~LasReader();
  LasReader(const LasReader&) = delete;
  LasReader& operator=(const LasReader&) = delete;

  const LasHeader& header() const { return header_; }
  const std::string& name() const { return name_; }
  std::uint64_t points_read() const { return next_; }

  // Replaces `out` with the next up to `max_points` points; returns false (and clears `out`) at the end.
  bool read_chunk(std::vector<LasPoint>& out, std::size_t max_points = 1 << 16);

 private:
  std::unique_ptr<std::istream> owned_;
  std::istream* in_ = nullptr;
  std::uint64_t size_ = 0;
  std::string name_;
  LasHeader header_;
  std::uint64_t next_ = 0;
  std::vector<char> raw_;
  void read_header();
};

// The EPSG code of the projected (else geographic) CRS in the GeoTIFF key directory VLR (LASF_Projection 34735),
// 0 when the file states none (AHN3's crops, for one) or states it only as WKT.
int las_epsg(const LasHeader& header);

// Reads a whole file (convenience for small files; large ones stream through LasReader).
std::vector<LasPoint> read_las(const std::string& path, LasHeader* header = nullptr);

// Writes points as LAS 1.<header.version_minor> with header.point_format, scale and offset (record length and
// header size are derived; min/max and counts are computed from the points; VLRs are written as given).
// Coordinates are rounded to the nearest integer unit; one out of the 32-bit range throws hf::Error. Atomic.
void write_las(const std::string& path, const LasHeader& header, const std::vector<LasPoint>& points);
// The same bytes in memory (tests, fuzz seeds).
std::string format_las(const LasHeader& header, const std::vector<LasPoint>& points, const std::string& name);

}  // namespace hf
