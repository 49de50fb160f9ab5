#include "lidar/tiling.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/regular_path.h"
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
  // Points beyond the window belong to other tiles; points beyond the plan's whole grid prove a header's box
  // wrong, and would be lost by every tile without a word (the single run refuses such a file the same way).
  const CellRaster raster = rasterise_files(files, plan.grid.window(win.col, win.row, win.width, win.height),
                                            options.classes, progress, OutsideGrid::refuse, &plan.grid);
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

namespace {

constexpr size_t kHeaderBytes = 80;  // magic .. the two label counts

// The fixed header (through the label counts); `clusters` gets the cluster count.
TileResult parse_header(Reader& r, std::int32_t& clusters) {
  if (r.bytes.size() < 8 || std::memcmp(r.bytes.data(), kMagic, 8) != 0) r.fail(0, "not a hashfusion lidar tile (no HFLTILE1 magic)");
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
  clusters = r.get<std::int32_t>("label counts");
  const std::uint64_t cells = std::uint64_t(t.core.width) * t.core.height;
  if (t.buildings < 0 || clusters < 0 || std::uint64_t(t.buildings) > cells || std::uint64_t(clusters) > cells)
    r.fail(r.at - 8, "label counts are not valid");
  return t;
}

}  // namespace

TileResult read_tile_header(const std::string& path) {
  require_regular_path(path, "tile file");  // the merge lists *.hflt names: a FIFO among them would block the open
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open tile file");
  std::string bytes(kHeaderBytes, '\0');
  in.read(bytes.data(), std::streamsize(kHeaderBytes));
  bytes.resize(static_cast<size_t>(in.gcount()));
  Reader r{path, bytes};
  std::int32_t clusters = 0;
  TileResult t = parse_header(r, clusters);
  t.cluster_cells.assign(static_cast<size_t>(clusters), 0);
  return t;
}

TileResult read_tile(const std::string& path) {
  require_regular_path(path, "tile file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open tile file");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  Reader r{path, bytes};
  std::int32_t clusters = 0;
  TileResult t = parse_header(r, clusters);
  const std::uint64_t cells = std::uint64_t(t.core.width) * t.core.height;
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

namespace {

// What the merge reads of its tiles, so files and in-memory tiles share one merge: the headers (no labels; the
// cluster count in cluster_cells.size() is enough), the whole tile for the first pass, rows of labels for the second.
struct TileSource {
  std::vector<TileResult> headers;
  std::vector<std::int32_t> clusters;
  std::vector<std::string> names;
  std::function<TileResult(size_t)> load;
  std::function<void(size_t, int y0, int rows, std::int32_t* building, std::int32_t* cluster)> rows;
};

// The tiles as rows of tiles (north to south; each west to east). A plan's cores share their rows within a row of
// tiles and cover the grid exactly once; anything else is an overlap or a missing tile.
std::vector<std::vector<size_t>> tile_layout(const TileSource& src) {
  const Grid& grid = src.headers[0].grid;
  std::vector<size_t> order(src.headers.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const CellRect &x = src.headers[a].core, &y = src.headers[b].core;
    return std::pair(x.row, x.col) < std::pair(y.row, y.col);
  });
  std::vector<std::vector<size_t>> rows;
  int next_row = 0, next_col = 0, row_height = 0;
  for (size_t k : order) {
    const CellRect& c = src.headers[k].core;
    if (next_col == grid.width) next_row += row_height, next_col = 0;
    if (next_col == 0) rows.emplace_back(), row_height = c.height;
    if (c.row != next_row || c.col != next_col || c.height != row_height)
      throw Error("merge: " + src.names[k] + ": tiles overlap or a tile is missing (core at cell (" + std::to_string(c.col) + ", " +
                  std::to_string(c.row) + "), expected (" + std::to_string(next_col) + ", " + std::to_string(next_row) + "))");
    rows.back().push_back(k);
    next_col += c.width;
  }
  if (next_col != grid.width || next_row + row_height != grid.height)
    throw Error("merge: the tiles do not cover the whole grid (a tile is missing)");
  return rows;
}

MergeSummary merge(const TileSource& src, const AreaThresholds& areas, const MergeBand& band, int band_rows) {
  validate(areas);
  if (src.headers.empty()) throw Error("merge: no tiles");
  if (band_rows < 1) throw Error("merge: band_rows must be positive");
  const size_t n = src.headers.size();
  const Grid grid = src.headers[0].grid;
  const int w = grid.width;
  // Global ids: each tile's labels shifted past the previous tiles'.
  std::vector<std::int64_t> building_base(n), cluster_base(n);
  std::int64_t buildings = 0, clusters = 0;
  for (size_t k = 0; k < n; ++k) {
    const TileResult& t = src.headers[k];
    if (t.grid != grid || t.t_s != src.headers[0].t_s)
      throw Error("merge: " + src.names[k] + " was run on another grid or t^S than " + src.names[0]);
    building_base[k] = buildings, cluster_base[k] = clusters;
    buildings += t.buildings, clusters += src.clusters[k];
  }
  const std::vector<std::vector<size_t>> layout = tile_layout(src);

  // Pass 1: components that continue across a core border (8-neighbours in S, resp. psi(S), in two tiles). Only
  // the grid-wide row above the current row of tiles and the column left of the current tile are kept.
  UnionFind bu(buildings), cu(clusters);
  std::vector<std::int64_t> cells_of(static_cast<size_t>(clusters), 0);
  std::vector<std::int64_t> above_b(w, -1), above_c(w, -1), below_b(w, -1), below_c(w, -1), left_b, left_c;
  for (const auto& row : layout) {
    left_b.clear(), left_c.clear();
    for (size_t k : row) {
      const TileResult t = src.load(k);
      const CellRect& core = src.headers[k].core;
      if (t.core != core || t.buildings != src.headers[k].buildings || std::int64_t(t.cluster_cells.size()) != src.clusters[k])
        throw Error("merge: " + src.names[k] + " changed while it was merged");
      std::copy(t.cluster_cells.begin(), t.cluster_cells.end(), cells_of.begin() + cluster_base[k]);
      const auto gb = [&](int x, int y) { const int l = t.building_label(x, y); return l < 0 ? -1 : building_base[k] + l; };
      const auto gc = [&](int x, int y) { const int l = t.cluster_label(x, y); return l < 0 ? -1 : cluster_base[k] + l; };
      const auto join = [](UnionFind& u, std::int64_t a, std::int64_t b) {
        if (a >= 0 && b >= 0) u.unite(a, b);
      };
      if (core.row > 0)
        for (int x = 0; x < core.width; ++x)
          for (int dx = -1; dx <= 1; ++dx)
            if (const int gx = core.col + x + dx; gx >= 0 && gx < w) join(bu, gb(x, 0), above_b[gx]), join(cu, gc(x, 0), above_c[gx]);
      if (!left_b.empty())
        for (int y = 0; y < core.height; ++y)
          for (int dy = -1; dy <= 1; ++dy)
            if (const int yy = y + dy; yy >= 0 && yy < core.height) join(bu, gb(0, y), left_b[yy]), join(cu, gc(0, y), left_c[yy]);
      left_b.resize(core.height), left_c.resize(core.height);
      for (int y = 0; y < core.height; ++y) left_b[y] = gb(core.width - 1, y), left_c[y] = gc(core.width - 1, y);
      for (int x = 0; x < core.width; ++x) below_b[core.col + x] = gb(x, core.height - 1), below_c[core.col + x] = gc(x, core.height - 1);
    }
    std::swap(above_b, below_b), std::swap(above_c, below_c);
  }
  std::vector<std::int64_t> root_cells(static_cast<size_t>(clusters), 0);
  for (std::int64_t c = 0; c < clusters; ++c) root_cells[cu.find(c)] += cells_of[c];
  std::vector<std::int64_t>().swap(cells_of);

  // Pass 2: the classes, band by band, from the labels' rows.
  MergeSummary out;
  out.grid = grid, out.t_s = src.headers[0].t_s, out.tiles = static_cast<int>(n);
  std::vector<char> building_seen(static_cast<size_t>(buildings), 0), cluster_seen(static_cast<size_t>(clusters), 0);
  std::vector<std::int32_t> b_rows, c_rows;
  for (const auto& row : layout) {
    const CellRect& first = src.headers[row.front()].core;
    for (int y0 = 0; y0 < first.height; y0 += band_rows) {
      const int rows = std::min(band_rows, first.height - y0);
      Image<std::uint8_t> classes(w, rows, 0);
      Mask s(w, rows, 0);
      for (size_t k : row) {
        const CellRect& core = src.headers[k].core;
        b_rows.resize(size_t(core.width) * rows), c_rows.resize(b_rows.size());
        src.rows(k, y0, rows, b_rows.data(), c_rows.data());
        for (int y = 0; y < rows; ++y)
          for (int x = 0; x < core.width; ++x) {
            const std::int32_t b = b_rows[size_t(y) * core.width + x], c = c_rows[size_t(y) * core.width + x];
            if (b < 0) continue;
            if (b >= src.headers[k].buildings || c < 0 || c >= src.clusters[k])
              throw Error("merge: " + src.names[k] + " changed while it was merged (label out of range)");
            const std::int64_t root = cu.find(cluster_base[k] + c);
            const BuiltUpClass cls = class_of_area(double(root_cells[root]) * grid.cell_area_m2(), areas);
            s(core.col + x, y) = 1;
            classes(core.col + x, y) = static_cast<std::uint8_t>(cls);
            ClassStatistics& st = out.stats[static_cast<int>(cls) - 1];
            ++st.cells;
            if (char& seen = building_seen[bu.find(building_base[k] + b)]; !seen) seen = 1, ++st.components;
            if (char& seen = cluster_seen[root]; !seen) seen = 1, ++st.settlements;
          }
      }
      band(first.row + y0, classes, s);
    }
  }
  return out;
}

}  // namespace

BuiltUpRaster merge_tiles(const std::vector<TileResult>& tiles, const AreaThresholds& areas) {
  TileSource src;
  for (const TileResult& t : tiles) {
    src.headers.push_back(t);
    src.headers.back().building_label = {}, src.headers.back().cluster_label = {};
    src.clusters.push_back(static_cast<std::int32_t>(t.cluster_cells.size()));
    src.names.push_back("tile " + std::to_string(t.tile));
  }
  src.load = [&](size_t k) { return tiles[k]; };
  src.rows = [&](size_t k, int y0, int rows, std::int32_t* b, std::int32_t* c) {
    const size_t at = size_t(y0) * tiles[k].core.width, count = size_t(rows) * tiles[k].core.width;
    std::copy_n(tiles[k].building_label.data() + at, count, b);
    std::copy_n(tiles[k].cluster_label.data() + at, count, c);
  };
  BuiltUpRaster out;
  if (!tiles.empty()) out.s = Mask(tiles[0].grid.width, tiles[0].grid.height, 0), out.classes = Image<std::uint8_t>(out.s.width(), out.s.height(), 0);
  const MergeSummary m = merge(src, areas, [&](int row0, const Image<std::uint8_t>& classes, const Mask& s) {
    std::copy_n(classes.data(), classes.size(), out.classes.data() + size_t(row0) * out.classes.width());
    std::copy_n(s.data(), s.size(), out.s.data() + size_t(row0) * out.s.width());
  }, 64);
  out.grid = m.grid, out.stats = m.stats;
  return out;
}

MergeSummary merge_tile_files(const std::vector<std::string>& paths, const AreaThresholds& areas, const MergeBand& band, int band_rows) {
  TileSource src;
  for (const std::string& path : paths) {
    src.headers.push_back(read_tile_header(path));
    src.clusters.push_back(static_cast<std::int32_t>(src.headers.back().cluster_cells.size()));
    src.headers.back().cluster_cells = {};
    src.names.push_back(path);
  }
  src.load = [&](size_t k) { return read_tile(paths[k]); };
  src.rows = [&](size_t k, int y0, int rows, std::int32_t* b, std::int32_t* c) {
    const CellRect& core = src.headers[k].core;
    const std::uint64_t cells = std::uint64_t(core.width) * core.height, labels_at = kHeaderBytes + std::uint64_t(src.clusters[k]) * 8;
    const std::uint64_t at = std::uint64_t(y0) * core.width * 4, bytes = std::uint64_t(rows) * core.width * 4;
    std::ifstream in(paths[k], std::ios::binary);
    in.seekg(std::streamoff(labels_at + at));
    in.read(reinterpret_cast<char*>(b), std::streamsize(bytes));
    in.seekg(std::streamoff(labels_at + cells * 4 + at));
    in.read(reinterpret_cast<char*>(c), std::streamsize(bytes));
    if (!in) throw Error(paths[k] + ": byte " + std::to_string(labels_at + at) + ": truncated tile file (it changed while it was merged)");
  };
  return merge(src, areas, band, band_rows);
}

}  // namespace hf::lidar
