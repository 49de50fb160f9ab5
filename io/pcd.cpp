#include "io/pcd.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cmath>
#include <exception>
#include <fstream>
#include <iterator>
#include <map>
#include <ostream>
#include <sstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"

namespace hf {
namespace {

template <class PointT>
void save(const std::string& tmp_path, const PointCloud& c) {
  pcl::PointCloud<PointT> out;
  out.resize(c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    PointT& p = out[i];
    p.x = c.positions[i].x();
    p.y = c.positions[i].y();
    p.z = c.positions[i].z();
    if constexpr (pcl::traits::has_normal_v<PointT>) {
      p.normal_x = c.normals[i].x();
      p.normal_y = c.normals[i].y();
      p.normal_z = c.normals[i].z();
      p.curvature = 0.0f;
    }
    if constexpr (pcl::traits::has_color_v<PointT>) {
      p.r = c.colors[i].r;
      p.g = c.colors[i].g;
      p.b = c.colors[i].b;
      p.a = 255;
    }
  }
  if (pcl::io::savePCDFileBinary(tmp_path, out) != 0) throw Error(tmp_path + ": PCL could not write the PCD file");
}

template <class PointT>
PointCloud load(const pcl::PCLPointCloud2& blob) {
  pcl::PointCloud<PointT> in;
  pcl::fromPCLPointCloud2(blob, in);
  PointCloud c;
  constexpr bool normals = pcl::traits::has_normal_v<PointT>;
  constexpr bool colors = pcl::traits::has_color_v<PointT>;
  c.positions.reserve(in.size());
  if (normals) c.normals.reserve(in.size());
  if (colors) c.colors.reserve(in.size());
  for (const PointT& p : in) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    c.positions.emplace_back(p.x, p.y, p.z);
    if constexpr (normals) {
      const Eigen::Vector3f n(p.normal_x, p.normal_y, p.normal_z);
      c.normals.push_back(n.allFinite() ? n : Eigen::Vector3f::Zero());
    }
    if constexpr (colors) c.colors.push_back(Rgb8{p.r, p.g, p.b});
  }
  return c;
}

bool has_field(const pcl::PCLPointCloud2& blob, const char* name) {
  return std::any_of(blob.fields.begin(), blob.fields.end(), [&](const pcl::PCLPointField& f) { return f.name == name; });
}

// PCL's reader trusts the header (a file of plain text makes it crash), so the header is checked here first: the
// fields PCL needs, consistent per-field lists, point counts that fit the bytes present.
// Returns the number of points the header declares.
std::uint64_t check_header(const std::string& path) {
  const std::string bytes = read_regular_file(path, "PCD file", kMaxModelFileBytes);
  std::map<std::string, std::vector<std::string>> keys;
  std::map<std::string, int> key_line;
  size_t pos = 0;
  int lineno = 0;
  for (;;) {
    if (pos >= bytes.size()) throw ParseError(path, lineno + 1, "expected a 'DATA ascii|binary|binary_compressed' line");
    size_t nl = bytes.find('\n', pos);
    if (nl == std::string::npos) nl = bytes.size();
    std::string line = bytes.substr(pos, nl - pos);
    pos = nl + 1;
    ++lineno;
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::string key, word;
    if (!(ls >> key)) continue;
    static const char* kKeys[] = {"VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
    if (std::find_if(std::begin(kKeys), std::end(kKeys), [&](const char* k) { return key == k; }) == std::end(kKeys))
      throw ParseError(path, lineno, "expected a PCD header keyword (VERSION FIELDS SIZE TYPE COUNT WIDTH HEIGHT VIEWPOINT POINTS DATA), got '" +
                                         key.substr(0, 40) + "'");
    std::vector<std::string>& values = keys[key];
    key_line[key] = lineno;
    while (ls >> word) values.push_back(word);
    if (key == "DATA") break;
  }
  const std::string data = keys["DATA"].empty() ? "" : keys["DATA"][0];
  if (data != "ascii" && data != "binary" && data != "binary_compressed")
    throw ParseError(path, lineno, "expected 'DATA ascii|binary|binary_compressed', got '" + data.substr(0, 40) + "'");
  const std::vector<std::string>& fields = keys["FIELDS"];
  if (fields.empty()) throw ParseError(path, lineno, "expected a FIELDS line before DATA");
  const size_t nf = fields.size();
  std::vector<std::string>& count = keys["COUNT"];
  if (count.empty()) count.assign(nf, "1");
  for (const char* k : {"SIZE", "TYPE", "COUNT"})
    if (keys[k].size() != nf)
      throw ParseError(path, key_line.count(k) ? key_line[k] : lineno,
                       std::string("expected ") + std::to_string(nf) + " entries on the " + k + " line, one per field");
  auto number = [&](const std::string& key, const std::string& text) {
    std::uint64_t v = 0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size() || v > (std::uint64_t(1) << 40))
      throw ParseError(path, key_line.count(key) ? key_line[key] : lineno, "expected a count for " + key + ", got '" + text.substr(0, 40) + "'");
    return v;
  };
  std::uint64_t point_bytes = 0;
  for (size_t i = 0; i < nf; ++i) {
    const std::uint64_t size = number("SIZE", keys["SIZE"][i]), n = number("COUNT", count[i]);
    const std::string& type = keys["TYPE"][i];
    const bool ok_size = size == 1 || size == 2 || size == 4 || size == (type == "F" ? 8u : 4u) || (type != "F" && size == 8);
    if ((type != "F" && type != "U" && type != "I") || !ok_size || n == 0)
      throw ParseError(path, key_line["TYPE"], "expected field '" + fields[i].substr(0, 40) +
                                                    "' to have TYPE F, U or I with SIZE 1, 2, 4 or 8 and COUNT >= 1");
    const std::string& f = fields[i];
    const bool is_float = f == "x" || f == "y" || f == "z" || f == "normal_x" || f == "normal_y" || f == "normal_z";
    if (is_float && (type != "F" || size != 4 || n != 1))
      throw ParseError(path, key_line["TYPE"], "expected field '" + f + "' to be one float (TYPE F, SIZE 4, COUNT 1)");
    if ((f == "rgb" || f == "rgba") && (size != 4 || n != 1))
      throw ParseError(path, key_line["TYPE"], "expected field '" + f + "' to be one packed 4-byte colour");
    point_bytes += size * n;
  }
  const std::uint64_t points = keys["POINTS"].empty()
                                   ? number("WIDTH", keys["WIDTH"].empty() ? "0" : keys["WIDTH"][0]) *
                                         (keys["HEIGHT"].empty() ? 1 : number("HEIGHT", keys["HEIGHT"][0]))
                                   : number("POINTS", keys["POINTS"][0]);
  const std::uint64_t left = bytes.size() - std::min(pos, bytes.size());
  if (data == "binary" && points * point_bytes > left)
    throw ParseError(path, key_line["POINTS"], "expected " + std::to_string(points) + " points of " +
                                                   std::to_string(point_bytes) + " bytes, got only " + std::to_string(left) +
                                                   " bytes of data (truncated file?)");
  if (data == "ascii" && points > left / 2 + 1)
    throw ParseError(path, key_line["POINTS"], "expected " + std::to_string(points) + " lines of points, got only " +
                                                   std::to_string(left) + " bytes of data (truncated file?)");
  if (data == "binary_compressed" && left < 8)
    throw ParseError(path, lineno, "expected the compressed and uncompressed sizes after DATA binary_compressed");
  return points;
}

}  // namespace

void write_pcd(const std::string& path, const PointCloud& cloud) {
  cloud.validate();
  if (cloud.size() == 0) {  // PCL's writer and reader index element 0 of empty clouds (UBSan), so not through PCL
    write_file_atomically(path, [](std::ostream& out) {
      out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
             "COUNT 1 1 1\nWIDTH 0\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA binary\n";
    });
    return;
  }
  write_path_atomically(path, [&](const std::string& tmp) {
    try {
      if (cloud.has_normals() && cloud.has_colors()) save<pcl::PointXYZRGBNormal>(tmp, cloud);
      else if (cloud.has_normals()) save<pcl::PointNormal>(tmp, cloud);
      else if (cloud.has_colors()) save<pcl::PointXYZRGB>(tmp, cloud);
      else save<pcl::PointXYZ>(tmp, cloud);
    } catch (const Error&) {
      throw Error(path + ": PCL could not write the PCD file");
    } catch (const std::exception& e) {  // pcl::IOException and friends
      throw Error(path + ": PCL could not write the PCD file: " + e.what());
    }
  });
}

PointCloud read_pcd(const std::string& path) {
  if (check_header(path) == 0) return PointCloud{};  // see write_pcd: PCL mishandles empty clouds
  pcl::PCLPointCloud2 blob;
  int rc = -1;
  try {
    rc = pcl::io::loadPCDFile(path, blob);
  } catch (const std::exception& e) {
    throw ParseError(path, 0, std::string("expected a PCD file PCL can read: ") + e.what());
  }
  if (rc < 0) throw ParseError(path, 0, "expected a PCD file PCL can read (PCL's reader failed, see its message)");
  if (!has_field(blob, "x") || !has_field(blob, "y") || !has_field(blob, "z"))
    throw ParseError(path, 0, "expected fields x, y and z in the PCD header");
  const bool normals = has_field(blob, "normal_x") && has_field(blob, "normal_y") && has_field(blob, "normal_z");
  const bool colors = has_field(blob, "rgb") || has_field(blob, "rgba");
  PointCloud c;
  if (normals && colors) c = load<pcl::PointXYZRGBNormal>(blob);
  else if (normals) c = load<pcl::PointNormal>(blob);
  else if (colors) c = load<pcl::PointXYZRGB>(blob);
  else c = load<pcl::PointXYZ>(blob);
  return c;
}

}  // namespace hf
