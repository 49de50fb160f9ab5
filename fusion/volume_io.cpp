#include "fusion/volume_io.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <ostream>
#include <sstream>
#include <unordered_set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/regular_path.h"

namespace hf::fusion {

static_assert(std::endian::native == std::endian::little, "the volume format is little-endian");
static_assert(sizeof(VoxelBlock) == HF_VOXELS_PER_BLOCK * 8, "blocks are stored as their raw bytes");

namespace {

constexpr char kMagic[8] = {'H', 'F', 'V', 'O', 'L', 'U', 'M', 'E'};
constexpr size_t kParamsBytes = 8 + 8 + 4 + 4 + 8 + 8;
constexpr size_t kRecordBytes = 16 + sizeof(VoxelBlock);
constexpr std::uint32_t kFlagStreamed = 1;

template <class T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
T get(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

}  // namespace

std::uint64_t fnv1a64(const void* data, size_t size) {
  std::uint64_t h = 14695981039346656037ull;
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

std::string serialize_volume(const VoxelBlockGrid& grid, const BlockStore* store) {
  const auto resident = grid.blocks();
  std::vector<std::pair<BlockCoord, const VoxelBlock*>> streamed;
  if (store)
    for (const auto& c : store->block_coords()) streamed.emplace_back(c, store->find(c));
  const VolumeParams& p = grid.params();
  std::string out;
  out.reserve(sizeof(kMagic) + 4 + kParamsBytes + (resident.size() + streamed.size()) * kRecordBytes + 8);
  out.append(kMagic, sizeof(kMagic));
  put<std::uint32_t>(out, kVolumeFormatVersion);
  const size_t payload_begin = out.size();
  put<double>(out, p.voxel_m);
  put<double>(out, p.truncation_vox);
  put<float>(out, p.max_weight);
  put<std::uint32_t>(out, 0);
  put<std::uint64_t>(out, p.capacity_blocks);
  put<std::uint64_t>(out, resident.size() + streamed.size());
  auto put_block = [&](const BlockCoord& c, const VoxelBlock& b, std::uint32_t flags) {
    put<std::int32_t>(out, c.x);
    put<std::int32_t>(out, c.y);
    put<std::int32_t>(out, c.z);
    put<std::uint32_t>(out, flags);
    out.append(reinterpret_cast<const char*>(b.voxels.data()), sizeof(VoxelBlock));
  };
  for (const auto& [c, b] : resident) put_block(c, *b, 0);
  for (const auto& [c, b] : streamed) put_block(c, *b, kFlagStreamed);
  put<std::uint64_t>(out, fnv1a64(out.data() + payload_begin, out.size() - payload_begin));
  return out;
}

void save_volume(const std::string& path, const VoxelBlockGrid& grid, const BlockStore* store) {
  const std::string bytes = serialize_volume(grid, store);
  write_file_atomically(path, [&](std::ostream& os) { os.write(bytes.data(), std::streamsize(bytes.size())); }, true);
}

Volume parse_volume(std::string_view bytes, const std::string& name) {
  auto fail = [&](const std::string& what) -> void { throw ParseError(name, 0, what); };
  const size_t header = sizeof(kMagic) + 4;
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
    fail("expected a hashfusion volume starting with \"HFVOLUME\" (" + std::to_string(bytes.size()) +
         " bytes, wrong magic)");
  if (bytes.size() < header + kParamsBytes + 8)
    fail("expected at least " + std::to_string(header + kParamsBytes + 8) + " bytes of header, got " +
         std::to_string(bytes.size()) + " (truncated file)");
  const std::uint32_t version = get<std::uint32_t>(bytes.data() + 8);
  if (version != kVolumeFormatVersion)
    fail("expected volume format version " + std::to_string(kVolumeFormatVersion) + ", got " +
         std::to_string(version));
  const char* p = bytes.data() + header;
  VolumeParams params;
  params.voxel_m = get<double>(p);
  params.truncation_vox = get<double>(p + 8);
  params.max_weight = get<float>(p + 16);
  const std::uint64_t capacity = get<std::uint64_t>(p + 24);
  const std::uint64_t count = get<std::uint64_t>(p + 32);
  const size_t available = bytes.size() - header - kParamsBytes - 8;
  if (count > available / kRecordBytes || count * kRecordBytes != available) {
    std::ostringstream msg;
    msg << "expected " << count << " blocks (" << count << " x " << kRecordBytes << " bytes) after the header, got "
        << available << " bytes (" << (count * kRecordBytes > available || count > available / kRecordBytes
                                            ? "truncated file" : "trailing bytes") << ")";
    fail(msg.str());
  }
  const size_t payload_size = kParamsBytes + count * kRecordBytes;
  const std::uint64_t stored_sum = get<std::uint64_t>(bytes.data() + header + payload_size);
  const std::uint64_t sum = fnv1a64(bytes.data() + header, payload_size);
  if (sum != stored_sum) {
    std::ostringstream msg;
    msg << "expected FNV-1a 64 checksum " << std::hex << stored_sum << " over the payload, computed " << sum
        << " (corrupted file)";
    fail(msg.str());
  }
  params.capacity_blocks = size_t(capacity);
  if (capacity != params.capacity_blocks) fail("expected capacity_blocks that fits in size_t");
  try {
    params.validate();
  } catch (const ParseError&) {
    throw;
  } catch (const Error& e) {
    fail(std::string("expected valid volume parameters: ") + e.what());
  }
  size_t resident = 0;
  for (std::uint64_t i = 0; i < count; ++i)
    if (!(get<std::uint32_t>(p + kParamsBytes + i * kRecordBytes + 12) & kFlagStreamed)) ++resident;
  if (resident > params.capacity_blocks)
    fail("expected at most capacity_blocks = " + std::to_string(params.capacity_blocks) + " resident blocks, got " +
         std::to_string(resident));

  Volume volume{VoxelBlockGrid(params), BlockStore()};
  for (std::uint64_t i = 0; i < count; ++i) {
    const char* r = p + kParamsBytes + i * kRecordBytes;
    const BlockCoord c{get<std::int32_t>(r), get<std::int32_t>(r + 4), get<std::int32_t>(r + 8)};
    const std::uint32_t flags = get<std::uint32_t>(r + 12);
    if (flags & ~kFlagStreamed) fail("expected block flags 0 or 1 in block " + std::to_string(i));
    if (volume.grid.find(c) || volume.store.contains(c))
      fail("expected each block once, block (" + std::to_string(c.x) + ", " + std::to_string(c.y) + ", " +
           std::to_string(c.z) + ") appears twice");
    VoxelBlock scratch;
    std::uint8_t* surface_free = nullptr;
    VoxelBlock* block = (flags & kFlagStreamed) ? &scratch : volume.grid.allocate(c, nullptr, &surface_free);
    std::memcpy(block->voxels.data(), r + 16, sizeof(VoxelBlock));
    if (flags & kFlagStreamed)
      volume.store.put(c, scratch);
    else
      *surface_free = block_is_surface_free(*block) ? 1 : 0;  // derived, so not stored in the file
  }
  return volume;
}

Volume load_volume(const std::string& path) {
  // An ifstream on a FIFO or device blocks or reads endlessly; the refusal keeps load_volume's ParseError contract.
  try {
    require_regular_path(path, "volume file");
  } catch (const Error& e) {
    const std::string why = e.what();
    throw ParseError(path, 0, "expected a readable hashfusion volume file (" +
                                  (why.rfind(path + ": ", 0) == 0 ? why.substr(path.size() + 2) : why) + ")");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ParseError(path, 0, "expected a readable hashfusion volume file (cannot open it)");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw ParseError(path, 0, "expected a readable hashfusion volume file (read error)");
  return parse_volume(bytes, path);
}

}  // namespace hf::fusion
