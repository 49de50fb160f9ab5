#include "lidar/tiling.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/las.h"

namespace hf::lidar {
namespace {

constexpr char kMagic[8] = {'H', 'F', 'L', 'T', 'I', 'L', 'E', '1'};
constexpr std::uint32_t kByteOrder = 0x01020304u;

int ceil_cells(double metres, double cell_m) { return static_cast<int>(std::ceil(metres / cell_m)); }

// Union-find with path halving; roots are the smallest id of their set, so results do not depend on order.
struct UnionFind {
  std::vector<std::int64_t> parent;
  explicit UnionFind(std::int64_t n) : parent(static_cast<size_t>(n)) { std::iota(parent.begin(), parent.end(), 0); }
  std::int64_t find(std::int64_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void unite(std::int64_t a, std::int64_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

template <class T>
void put(std::ostream& os, T v) {
  os.write(reinterpret_cast<const char*>(&v), sizeof v);
}

struct Reader {
  const std::string& name;
  const std::string& bytes;
  size_t at = 0;
  template <class T>
  T get(const char* what) {
    if (bytes.size() - at < sizeof(T)) throw Error(name + ": byte " + std::to_string(at) + ": truncated tile file (" + what + ")");
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof v);
    at += sizeof v;
    return v;
  }
  [[noreturn]] void fail(size_t byte, const std::string& what) const { throw Error(name + ": byte " + std::to_string(byte) + ": " + what); }
};

}  // namespace

CellRect TilePlan::core(int tile) const {
  const int tx = tile % tiles_x, ty = tile / tiles_x;
  const auto split = [](int n, int parts, int i) { return static_cast<int>(std::int64_t(n) * i / parts); };
  const int c0 = split(grid.width, tiles_x, tx), c1 = split(grid.width, tiles_x, tx + 1);
  const int r0 = split(grid.height, tiles_y, ty), r1 = split(grid.height, tiles_y, ty + 1);
  return {c0, r0, c1 - c0, r1 - r0};
}

CellRect TilePlan::window(int tile) const {
  const CellRect c = core(tile);
  const int c0 = std::max(0, c.col - halo_cells), r0 = std::max(0, c.row - halo_cells);
  const int c1 = std::min(grid.width, c.col + c.width + halo_cells), r1 = std::min(grid.height, c.row + c.height + halo_cells);
  return {c0, r0, c1 - c0, r1 - r0};
}

TilePlan plan_tiles(const Grid& grid, int tiles_x, int tiles_y, const BuiltUpOptions& options, const TileLimits& limits) {
  validate(options);
  if (tiles_x < 1 || tiles_y < 1 || tiles_x > grid.width || tiles_y > grid.height)
    throw Error("tiles: " + std::to_string(tiles_x) + " x " + std::to_string(tiles_y) + " tiles do not fit a " +
                std::to_string(grid.width) + " x " + std::to_string(grid.height) + " cell grid");
  if (!(limits.max_height_m > 0 && limits.max_building_m > 0 && std::isfinite(limits.max_height_m) && std::isfinite(limits.max_building_m)))
    throw Error("tiles: --max-height-m and --max-building-m must be positive");
  TilePlan p;
  p.grid = grid;
  p.tiles_x = tiles_x, p.tiles_y = tiles_y;
  p.halo_cells = ceil_cells(options.t_s * limits.max_height_m + limits.max_building_m + options.heights.ground_margin_m, grid.cell_m) + 1;
  return p;
}

TileResult run_tile_on(const CellRaster& raster, const TilePlan& plan, int tile, const BuiltUpOptions& options, const TileLimits& limits) {
  if (tile < 0 || tile >= plan.count()) throw Error("tile " + std::to_string(tile) + " is not in the plan's 0.." + std::to_string(plan.count() - 1));
  const CellRect win = plan.window(tile), core = plan.core(tile);
  if (raster.grid != plan.grid.window(win.col, win.row, win.width, win.height)) throw Error("tile raster does not cover the tile's window");
  BuiltUpOptions o = options;
  o.cell_m = plan.grid.cell_m;
  const BuiltUp b = classify_built_up(raster, o);

  // The halo's assumptions, for every building whose disc could reach the core.
  const int r_max = ceil_cells(o.t_s * limits.max_height_m, o.cell_m) + 1;
  // At least one cell, so that a building cut by the window's edge is caught even without a ground margin.
  const int margin = std::max(1, ceil_cells(o.heights.ground_margin_m, o.cell_m));
  const int cx0 = core.col - win.col, cy0 = core.row - win.row, cx1 = cx0 + core.width - 1, cy1 = cy0 + core.height - 1;
  for (int id = 0; id < b.buildings.count; ++id) {
    const int x0 = b.buildings.min_col[id], x1 = b.buildings.max_col[id], y0 = b.buildings.min_row[id], y1 = b.buildings.max_row[id];
    const int gap = std::max({cx0 - x1, x0 - cx1, cy0 - y1, y0 - cy1, 0});
    if (gap > r_max) continue;
    const auto where = [&] {
      const double x = plan.grid.west() + (win.col + x0 + 0.5) * o.cell_m, y = plan.grid.north() - (win.row + y0 + 0.5) * o.cell_m;
      return "building near (" + std::to_string(x) + ", " + std::to_string(y) + ")";
    };
    if (b.heights_m[id] > limits.max_height_m)
      throw Error(where() + " is " + std::to_string(b.heights_m[id]) + " m tall, above --max-height-m " + std::to_string(limits.max_height_m));
    // Its ground box, clipped to the whole grid, must lie in the window (which is clipped the same way).
    const int gx0 = std::max(0, win.col + x0 - margin), gx1 = std::min(plan.grid.width - 1, win.col + x1 + margin);
    const int gy0 = std::max(0, win.row + y0 - margin), gy1 = std::min(plan.grid.height - 1, win.row + y1 + margin);
    if (gx0 < win.col || gy0 < win.row || gx1 >= win.col + win.width || gy1 >= win.row + win.height)
      throw Error(where() + " is not seen whole with its ground by its tile: wider than --max-building-m " +
                  std::to_string(limits.max_building_m) + "?");
  }

  TileResult t;
  t.grid = plan.grid, t.tile = tile, t.core = core, t.t_s = o.t_s, t.cell_m = o.cell_m;
  Mask s(core.width, core.height, 0), psi(core.width, core.height, 0);
  for (int y = 0; y < core.height; ++y)
    for (int x = 0; x < core.width; ++x) s(x, y) = b.s(cx0 + x, cy0 + y), psi(x, y) = b.psi_s(cx0 + x, cy0 + y);
  Components sc = connected_components(s), pc = connected_components(psi);
  t.building_label = std::move(sc.label);
  t.buildings = sc.count;
  t.cluster_label = std::move(pc.label);
  t.cluster_cells = std::move(pc.cells);
  return t;
}

TileResult run_tile(const std::vector<std::string>& files, const TilePlan& plan, int tile, const BuiltUpOptions& options,
                    const TileLimits& limits, bool progress) {
  if (tile < 0 || tile >= plan.count()) throw Error("tile " + std::to_string(tile) + " is not in the plan's 0.." + std::to_string(plan.count() - 1));
  const CellRect win = plan.window(tile);
  const CellRaster raster = rasterise_files(files, plan.grid.window(win.col, win.row, win.width, win.height), options.classes, progress);
  return run_tile_on(raster, plan, tile, options, limits);
}

void write_tile(const std::string& path, const TileResult& t) {
  write_file_atomically(
      path,
      [&](std::ostream& os) {
        os.write(kMagic, 8);
        put(os, kByteOrder);
        put(os, t.grid.cell_m), put(os, t.grid.col0), put(os, t.grid.row0), put(os, t.grid.width), put(os, t.grid.height);
        put(os, t.tile), put(os, t.core.col), put(os, t.core.row), put(os, t.core.width), put(os, t.core.height);
        put(os, t.t_s);
        put(os, t.buildings), put(os, static_cast<std::int32_t>(t.cluster_cells.size()));
        for (std::int64_t c : t.cluster_cells) put(os, c);
        os.write(reinterpret_cast<const char*>(t.building_label.data()), static_cast<std::streamsize>(t.building_label.size() * 4));
        os.write(reinterpret_cast<const char*>(t.cluster_label.data()), static_cast<std::streamsize>(t.cluster_label.size() * 4));
      },
      true);
}

TileResult read_tile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open tile file");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  Reader r{path, bytes};
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0) r.fail(0, "not a hashfusion lidar tile (no HFLTILE1 magic)");
  r.at = 8;
  if (r.get<std::uint32_t>("byte-order mark") != kByteOrder) r.fail(8, "written on a machine of the other byte order");
  TileResult t;
  t.grid.cell_m = r.get<double>("grid"), t.grid.col0 = r.get<std::int64_t>("grid"), t.grid.row0 = r.get<std::int64_t>("grid");
  t.grid.width = r.get<std::int32_t>("grid"), t.grid.height = r.get<std::int32_t>("grid");
  t.tile = r.get<std::int32_t>("tile");
  t.core.col = r.get<std::int32_t>("core"), t.core.row = r.get<std::int32_t>("core");
  t.core.width = r.get<std::int32_t>("core"), t.core.height = r.get<std::int32_t>("core");
  t.cell_m = t.grid.cell_m;
  t.t_s = r.get<double>("t^S");
  if (!(t.grid.cell_m > 0 && std::isfinite(t.grid.cell_m)) || t.grid.width <= 0 || t.grid.height <= 0 || t.core.col < 0 ||
      t.core.row < 0 || t.core.width <= 0 || t.core.height <= 0 || t.core.col + std::int64_t(t.core.width) > t.grid.width ||
      t.core.row + std::int64_t(t.core.height) > t.grid.height || !std::isfinite(t.t_s))
    r.fail(12, "grid or core rectangle is not valid");
  t.buildings = r.get<std::int32_t>("label counts");
  const std::int32_t clusters = r.get<std::int32_t>("label counts");
  const std::uint64_t cells = std::uint64_t(t.core.width) * t.core.height;
  if (t.buildings < 0 || clusters < 0 || std::uint64_t(t.buildings) > cells || std::uint64_t(clusters) > cells)
    r.fail(r.at - 8, "label counts are not valid");
  if (bytes.size() - r.at != std::uint64_t(clusters) * 8 + cells * 8)
    r.fail(r.at, "file size " + std::to_string(bytes.size()) + " does not match its " + std::to_string(cells) + " cells");
  for (int i = 0; i < clusters; ++i) t.cluster_cells.push_back(r.get<std::int64_t>("cluster sizes"));
  t.building_label = Image<std::int32_t>(t.core.width, t.core.height);
  t.cluster_label = Image<std::int32_t>(t.core.width, t.core.height);
  const size_t labels_at = r.at;
  std::memcpy(t.building_label.data(), bytes.data() + r.at, cells * 4);
  std::memcpy(t.cluster_label.data(), bytes.data() + r.at + cells * 4, cells * 4);
  std::vector<std::int64_t> counted(static_cast<size_t>(clusters), 0);
  for (size_t i = 0; i < cells; ++i) {
    const std::int32_t b = t.building_label.pixels()[i], c = t.cluster_label.pixels()[i];
    if (b < -1 || b >= t.buildings || c < -1 || c >= clusters || (b >= 0 && c < 0))
      r.fail(labels_at + i * 4, "cell label out of range (or a building cell outside every cluster)");
    if (c >= 0) ++counted[c];
  }
  if (counted != t.cluster_cells) r.fail(labels_at, "cluster sizes disagree with the cells' labels");
  return t;
}

BuiltUpRaster built_up_raster(const BuiltUp& b, const Grid& grid) {
  return {grid, b.s, b.profile.classes, b.profile.stats};
}

BuiltUpRaster merge_tiles(const std::vector<TileResult>& tiles, const AreaThresholds& areas) {
  validate(areas);
  if (tiles.empty()) throw Error("merge: no tiles");
  const Grid grid = tiles[0].grid;
  const int w = grid.width, h = grid.height;
  // Global ids: each tile's labels shifted past the previous tiles'.
  std::vector<std::int64_t> building_base, cluster_base;
  std::int64_t buildings = 0, clusters = 0;
  for (const TileResult& t : tiles) {
    if (t.grid != grid || t.t_s != tiles[0].t_s)
      throw Error("merge: tile " + std::to_string(t.tile) + " was run on another grid or t^S than tile " + std::to_string(tiles[0].tile));
    building_base.push_back(buildings), cluster_base.push_back(clusters);
    buildings += t.buildings, clusters += std::int64_t(t.cluster_cells.size());
  }
  Image<std::int64_t> building_id(w, h, -1), cluster_id(w, h, -1);
  Image<std::uint8_t> covered(w, h, 0);
  for (size_t k = 0; k < tiles.size(); ++k) {
    const TileResult& t = tiles[k];
    for (int y = 0; y < t.core.height; ++y)
      for (int x = 0; x < t.core.width; ++x) {
        const int gx = t.core.col + x, gy = t.core.row + y;
        if (covered(gx, gy)++) throw Error("merge: tiles overlap at cell (" + std::to_string(gx) + ", " + std::to_string(gy) + ")");
        if (const int b = t.building_label(x, y); b >= 0) building_id(gx, gy) = building_base[k] + b;
        if (const int c = t.cluster_label(x, y); c >= 0) cluster_id(gx, gy) = cluster_base[k] + c;
      }
  }
  for (auto c : covered.pixels())
    if (!c) throw Error("merge: the tiles do not cover the whole grid (a tile is missing)");

  // Components that continue across a core border: 8-neighbours in S (resp. psi(S)) with different labels.
  UnionFind bu(buildings), cu(clusters);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 1}, {0, 1}, {1, 1}}) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || nx >= w || ny >= h) continue;
        if (building_id(x, y) >= 0 && building_id(nx, ny) >= 0) bu.unite(building_id(x, y), building_id(nx, ny));
        if (cluster_id(x, y) >= 0 && cluster_id(nx, ny) >= 0) cu.unite(cluster_id(x, y), cluster_id(nx, ny));
      }
  std::vector<std::int64_t> root_cells(static_cast<size_t>(clusters), 0);
  for (size_t k = 0; k < tiles.size(); ++k)
    for (size_t c = 0; c < tiles[k].cluster_cells.size(); ++c) root_cells[cu.find(cluster_base[k] + std::int64_t(c))] += tiles[k].cluster_cells[c];

  BuiltUpRaster out;
  out.grid = grid;
  out.s = Mask(w, h, 0);
  out.classes = Image<std::uint8_t>(w, h, 0);
  std::vector<char> building_seen(static_cast<size_t>(buildings), 0), cluster_seen(static_cast<size_t>(clusters), 0);
  for (size_t i = 0; i < out.s.size(); ++i) {
    const std::int64_t b = building_id.pixels()[i];
    if (b < 0) continue;
    const std::int64_t root = cu.find(cluster_id.pixels()[i]);
    const BuiltUpClass c = class_of_area(double(root_cells[root]) * grid.cell_area_m2(), areas);
    out.s.pixels()[i] = 1;
    out.classes.pixels()[i] = static_cast<std::uint8_t>(c);
    ClassStatistics& st = out.stats[static_cast<int>(c) - 1];
    ++st.cells;
    if (char& seen = building_seen[bu.find(b)]; !seen) seen = 1, ++st.components;
    if (char& seen = cluster_seen[root]; !seen) seen = 1, ++st.settlements;
  }
  return out;
}

}  // namespace hf::lidar
