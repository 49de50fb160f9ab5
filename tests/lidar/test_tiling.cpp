// Tile-parallel runs equal the single run byte for byte on the class raster, for several splits; tile files
// round-trip and reject corruption; a tile whose halo assumptions fail says so.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "lidar/synthetic_settlements.h"
#include "lidar/tiling.h"

namespace hf::lidar {
namespace {

BuiltUpOptions tiling_options_for(const SyntheticSettlements& scene) {
  BuiltUpOptions o;
  o.cell_m = scene.grid.cell_m;
  o.t_s = scene.t_s;
  o.areas = scene.areas;
  return o;
}

std::vector<TileResult> run_all_tiles(const SyntheticSettlements& scene, const TilePlan& plan, const BuiltUpOptions& o,
                                      const TileLimits& limits) {
  std::vector<TileResult> tiles;
  for (int k = 0; k < plan.count(); ++k) {
    const CellRect w = plan.window(k);
    CellRaster raster(plan.grid.window(w.col, w.row, w.width, w.height));
    raster.add(scene.points);
    tiles.push_back(run_tile_on(raster, plan, k, o, limits));
  }
  return tiles;
}

TEST(Tiling, SplitRunsEqualTheSingleRun) {
  const SyntheticSettlements scene = synthetic_settlements({1.0, 21, 300, 0});  // stray points make extra hamlets
  const BuiltUpOptions o = tiling_options_for(scene);
  CellRaster whole(scene.grid);
  whole.add(scene.points);
  const BuiltUpRaster single = built_up_raster(classify_built_up(whole, o), scene.grid);
  const TileLimits limits{10.0, 20.0};
  for (const auto& [nx, ny] : {std::pair{1, 1}, {2, 1}, {3, 2}, {5, 3}}) {
    SCOPED_TRACE(std::to_string(nx) + " x " + std::to_string(ny) + " tiles");
    const TilePlan plan = plan_tiles(scene.grid, nx, ny, o, limits);
    EXPECT_EQ(plan.halo_cells, 51);
    if (nx == 5) {
      EXPECT_LT(plan.window(0).width, scene.grid.width / 2);  // tiles really see only part of the scene
    }
    const BuiltUpRaster merged = merge_tiles(run_all_tiles(scene, plan, o, limits), o.areas);
    EXPECT_EQ(merged.classes.pixels(), single.classes.pixels());
    EXPECT_EQ(merged.s.pixels(), single.s.pixels());
    for (int k = 0; k < kBuiltUpClasses; ++k) {
      EXPECT_EQ(merged.stats[k].cells, single.stats[k].cells);
      EXPECT_EQ(merged.stats[k].components, single.stats[k].components);
      EXPECT_EQ(merged.stats[k].settlements, single.stats[k].settlements);
    }
  }
}

// The streaming merge of tile files (what `hashfusion lidar --merge` runs) gives the single run's raster and
// statistics whatever the band height: one row at a time, bands that cut tile rows unevenly, one band per row of tiles.
TEST(Tiling, StreamingFileMergeEqualsTheSingleRunInAnyBand) {
  const SyntheticSettlements scene = synthetic_settlements({1.0, 21, 300, 0});
  const BuiltUpOptions o = tiling_options_for(scene);
  CellRaster whole(scene.grid);
  whole.add(scene.points);
  const BuiltUpRaster single = built_up_raster(classify_built_up(whole, o), scene.grid);
  const TilePlan plan = plan_tiles(scene.grid, 5, 3, o, {10.0, 20.0});
  const auto dir = std::filesystem::temp_directory_path() / ("hf_lidar_stream_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::vector<std::string> paths;
  for (const TileResult& t : run_all_tiles(scene, plan, o, {10.0, 20.0})) {
    paths.push_back((dir / ("tile_" + std::to_string(t.tile) + ".hflt")).string());
    write_tile(paths.back(), t);
  }
  std::reverse(paths.begin(), paths.end());  // any order
  for (int band_rows : {1, 7, 100000}) {
    SCOPED_TRACE("bands of " + std::to_string(band_rows) + " rows");
    Image<std::uint8_t> classes(scene.grid.width, scene.grid.height, 255);
    Mask s(scene.grid.width, scene.grid.height, 255);
    int next_row = 0, max_rows = 0;
    const MergeSummary m = merge_tile_files(paths, o.areas, [&](int row0, const Image<std::uint8_t>& c, const Mask& band) {
      EXPECT_EQ(row0, next_row);  // consecutive bands, north to south
      next_row += c.height(), max_rows = std::max(max_rows, c.height());
      for (int y = 0; y < c.height(); ++y)
        for (int x = 0; x < c.width(); ++x) classes(x, row0 + y) = c(x, y), s(x, row0 + y) = band(x, y);
    }, band_rows);
    EXPECT_EQ(next_row, scene.grid.height);
    EXPECT_LE(max_rows, band_rows);
    EXPECT_EQ(m.grid, scene.grid);
    EXPECT_EQ(m.tiles, 15);
    EXPECT_EQ(classes.pixels(), single.classes.pixels());
    EXPECT_EQ(s.pixels(), single.s.pixels());
    for (int k = 0; k < kBuiltUpClasses; ++k) {
      EXPECT_EQ(m.stats[k].cells, single.stats[k].cells);
      EXPECT_EQ(m.stats[k].components, single.stats[k].components);
      EXPECT_EQ(m.stats[k].settlements, single.stats[k].settlements);
    }
  }
  const auto ignore = [](int, const Image<std::uint8_t>&, const Mask&) {};
  EXPECT_THROW(merge_tile_files({paths[0], paths[1]}, o.areas, ignore), hf::Error);  // tiles missing
  EXPECT_THROW(merge_tile_files({paths[0], paths[0]}, o.areas, ignore), hf::Error);  // a tile twice
  std::filesystem::remove_all(dir);
}

TEST(Tiling, TileFilesRoundTripAndRejectCorruption) {
  const SyntheticSettlements scene = synthetic_settlements({1.0, 4});
  const BuiltUpOptions o = tiling_options_for(scene);
  const TilePlan plan = plan_tiles(scene.grid, 3, 1, o, {10.0, 20.0});
  const auto tiles = run_all_tiles(scene, plan, o, {10.0, 20.0});
  const auto dir = std::filesystem::temp_directory_path() / ("hf_lidar_tiles_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::vector<TileResult> back;
  for (const TileResult& t : tiles) {
    const std::string path = (dir / ("tile_" + std::to_string(t.tile) + ".hflt")).string();
    write_tile(path, t);
    back.push_back(read_tile(path));
    EXPECT_EQ(back.back().cluster_label.pixels(), t.cluster_label.pixels());
    EXPECT_EQ(back.back().cluster_cells, t.cluster_cells);
  }
  EXPECT_EQ(merge_tiles(back, o.areas).classes.pixels(), merge_tiles(tiles, o.areas).classes.pixels());
  // A missing tile, a repeated tile.
  EXPECT_THROW(merge_tiles({back[0], back[1]}, o.areas), hf::Error);
  EXPECT_THROW(merge_tiles({back[0], back[1], back[1]}, o.areas), hf::Error);

  const std::string path = (dir / "tile_0.hflt").string();
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto error_of = [&](const std::string& b) -> std::string {
    const std::string bad = (dir / "bad.hflt").string();
    std::ofstream(bad, std::ios::binary) << b;
    try {
      read_tile(bad);
    } catch (const hf::Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of(bytes.substr(0, bytes.size() - 3)).find("bad.hflt: byte"), std::string::npos);
  EXPECT_NE(error_of("HFLTILE2" + bytes.substr(8)).find("no HFLTILE1 magic"), std::string::npos);
  std::string b = bytes;
  b[b.size() - 2] = 0x7f;  // a label far out of range
  EXPECT_NE(error_of(b).find("label out of range"), std::string::npos);
  for (size_t cut = 0; cut < 80; cut += 7) EXPECT_NE(error_of(bytes.substr(0, cut)), "");
  std::filesystem::remove_all(dir);
}

TEST(Tiling, UnmetHaloAssumptionsAreReported) {
  const SyntheticSettlements scene = synthetic_settlements({1.0, 4});
  const BuiltUpOptions o = tiling_options_for(scene);
  // Houses are up to 8.25 m tall: a 5 m limit must refuse, not guess.
  const TilePlan plan = plan_tiles(scene.grid, 2, 1, o, {5.0, 20.0});
  try {
    run_all_tiles(scene, plan, o, {5.0, 20.0});
    FAIL() << "no error";
  } catch (const hf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("above --max-height-m"), std::string::npos) << e.what();
  }
  // A 100-cell-wide building across a tile border with a 20 m limit: its tile cannot see it whole.
  Grid grid{1.0, 0, 50, 300, 50};
  std::vector<LasPoint> pts;
  for (int row = 0; row < grid.height; ++row)
    for (int col = 0; col < grid.width; ++col) {
      LasPoint p;
      p.x = col + 0.5, p.y = grid.row0 - 1 - row + 0.5;
      const bool roof = col >= 100 && col < 200 && row >= 20 && row < 30;
      p.z = roof ? 6.0 : 0.0;
      p.classification = roof ? 6 : 2;
      pts.push_back(p);
    }
  const TileLimits narrow{10.0, 20.0};
  const TilePlan three = plan_tiles(grid, 3, 1, o, narrow);
  const CellRect w = three.window(0);
  CellRaster raster(grid.window(w.col, w.row, w.width, w.height));
  raster.add(pts);
  try {
    run_tile_on(raster, three, 0, o, narrow);
    FAIL() << "no error";
  } catch (const hf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("is not seen whole with its ground"), std::string::npos) << e.what();
  }
  EXPECT_THROW(plan_tiles(scene.grid, 0, 1, o), hf::Error);
}

}  // namespace
}  // namespace hf::lidar
