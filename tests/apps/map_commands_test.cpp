// `upd playback` with several rawlogs and `upd map info|merge|crop` as a user runs them, on a
// short simulated run: merging the maps of two halves gives the map of the whole run, two
// rawlogs played together give the merge of their maps, a map of another cell size is refused
// in one line, a crop keeps exactly the region; every folder written opens in gdalinfo,
// convert_octree and ros-map-yaml2mrpt.
#include "run_upd.h"
#include "temp_dir.h"
#include "upd/gdal/geotiff.h"
#include "upd/maps/traversability_octree.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace upd {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using test::CmdResult;
using test::runUpd;

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect-realtime.ini";

// Two short simulated runs of one world frame, played once for every test.
class MapCommands : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new test::TempDir("maps");
    for (const auto& [world, frames] : {std::pair{"mixed", 8}, std::pair{"ramp", 4}}) {
      const CmdResult r = runUpd(std::string("simulate --world ") + world + " --frames " +
                                 std::to_string(frames) + " --output " + file(world, ".rawlog"));
      ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    play("whole", {"mixed"});
  }
  static void TearDownTestSuite() { delete tmp_; }

  static std::string file(const std::string& stem, const std::string& ext) {
    return tmp_->file(stem + ext);
  }
  static fs::path dir(const std::string& name) { return tmp_->path() / name; }
  // upd playback of the runs (each with its ground-truth poses) into dir(out).
  static void play(const std::string& out, const std::vector<std::string>& runs,
                   const std::string& extra = "") {
    std::string rawlogs, poses;
    for (const auto& r : runs) {
      rawlogs += file(r, ".rawlog") + " ";
      poses += (poses.empty() ? "" : ",") + file(r, ".gt.tum");
    }
    const CmdResult r = runUpd("playback " + rawlogs + "--config " + kConfig + " --poses " +
                               poses + " --quiet --output " + dir(out).string() + " " + extra);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static CmdResult map(const std::string& args) { return runUpd("map " + args); }

  static test::TempDir* tmp_;

  // The properties, each checked on the maps of the one simulated run (SetUpTestSuite).
  void mergingTwoHalvesGivesTheWholeRun();
  void twoRawlogsPlayedTogetherAreTheMergeOfTheirMaps();
  void aMapOfAnotherFrameIsRefusedInOneLine();
  void cropKeepsExactlyTheRegion();
  void infoPrintsWhatTheFolderHolds();
};
test::TempDir* MapCommands::tmp_ = nullptr;

json gdalinfo(const fs::path& tif) {
  const CmdResult r = test::runCommand("gdalinfo -json '" + tif.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.exit_code == 0 ? json::parse(r.output) : json();
}

// The folder's files open in the tools users open them with.
void expectToolsOpen(const fs::path& d) {
  for (const char* tool : {"gdalinfo", "convert_octree", "ros-map-yaml2mrpt"}) {
    if (std::system((std::string("command -v ") + tool + " >/dev/null 2>&1").c_str()) != 0) {
      std::printf("[ SKIPPED  ] %s not found (scripts/setup.sh installs it)\n", tool);
      return;
    }
  }
  EXPECT_EQ(gdalinfo(d / "map.tif")["bands"].size(), gdal::geoTiffBands().size());
  const CmdResult ot = test::runCommand("convert_octree '" + (d / "map.ot").string() + "' '" +
                                        (d / "converted.bt").string() + "'");
  EXPECT_EQ(ot.exit_code, 0) << ot.output;
  for (const char* yaml : {"map.yaml", "map_cost.yaml"}) {
    const CmdResult r = test::runCommand("ros-map-yaml2mrpt -q -w -i '" + (d / yaml).string() +
                                         "' -d '" + d.string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
  fs::remove(d / "converted.bt");
}

// merged (a merge) against single (one fusion of the same frames), cell by world cell. Exact:
// the known cells, hits and counts, zeta_min and elevation_max; means to float rounding; the
// log-odds may differ where one run saturated a cell (map_merge.h), so labels must agree on
// at least 98 % of the known cells.
void expectSameGrid(const maps::TraversabilityGrid& merged, const maps::TraversabilityGrid& single) {
  std::size_t known = 0, agree = 0;
  for (int cy = 0; cy < single.sizeY(); ++cy) {
    for (int cx = 0; cx < single.sizeX(); ++cx) {
      const maps::GridCell& s = single.at(cx, cy);
      const Eigen::Vector2d xy = single.cellCenter(cx, cy);
      const maps::GridCell* m = merged.cellAt(xy.x(), xy.y());
      if (!s.observed()) {
        EXPECT_TRUE(m == nullptr || !m->observed()) << xy.transpose();
        continue;
      }
      ASSERT_NE(m, nullptr) << xy.transpose();
      SCOPED_TRACE(::testing::Message() << "cell at " << xy.transpose());
      ++known;
      agree += maps::labelOf(*m, merged.params()) == maps::labelOf(s, single.params());
      EXPECT_EQ(m->hits, s.hits);
      EXPECT_EQ(m->zeta_count, s.zeta_count);
      EXPECT_EQ(m->cost_count, s.cost_count);
      EXPECT_TRUE(m->zeta_min == s.zeta_min || (std::isnan(m->zeta_min) && std::isnan(s.zeta_min)));
      EXPECT_EQ(m->elevation_max_m, s.elevation_max_m);
      EXPECT_NEAR(m->elevation_m, s.elevation_m, 1e-4);
      if (s.cost_count > 0) {
        EXPECT_NEAR(m->cost_mean, s.cost_mean, 1e-4);
      }
      if (s.zeta_count > 0) {
        EXPECT_NEAR(m->zeta_mean, s.zeta_mean, 1e-4);
      }
    }
  }
  EXPECT_GT(known, 500u);
  EXPECT_GE(static_cast<double>(agree), 0.98 * known) << agree << " of " << known;
  std::printf("merge vs one fusion: %zu known cells, labels agree on %zu\n", known, agree);
}

void MapCommands::mergingTwoHalvesGivesTheWholeRun() {
  play("first", {"mixed"}, "--to 3");
  play("second", {"mixed"}, "--from 4");
  const CmdResult r = map("merge " + dir("first").string() + " " + dir("second").string() +
                          " --output " + dir("halves").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectSameGrid(gdal::readGeoTiff((dir("halves") / "map.tif").string()).grid,
                 gdal::readGeoTiff((dir("whole") / "map.tif").string()).grid);
  const auto merged = maps::readTraversabilityOt((dir("halves") / "map_traversability.ot").string());
  const auto whole = maps::readTraversabilityOt((dir("whole") / "map_traversability.ot").string());
  EXPECT_EQ(maps::computeStats(*merged).traversability_leaves,
            maps::computeStats(*whole).traversability_leaves);
  const json s = json::parse(std::ifstream(dir("halves") / "summary.json"));
  EXPECT_EQ(s["merged_from"].size(), 2u);
  EXPECT_EQ(s["rawlogs"], json::array({file("mixed", ".rawlog")}));
  expectToolsOpen(dir("halves"));
}

void MapCommands::twoRawlogsPlayedTogetherAreTheMergeOfTheirMaps() {
  play("both", {"mixed", "ramp"});
  play("ramp", {"ramp"});
  const CmdResult r = map("merge " + dir("whole").string() + " " + dir("ramp").string() +
                          " --output " + dir("merged").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectSameGrid(gdal::readGeoTiff((dir("merged") / "map.tif").string()).grid,
                 gdal::readGeoTiff((dir("both") / "map.tif").string()).grid);
  const json s = json::parse(std::ifstream(dir("both") / "summary.json"));
  EXPECT_EQ(s["rawlogs"].size(), 2u);
  // One --poses file per rawlog.
  const CmdResult bad = runUpd("playback " + file("mixed", ".rawlog") + " " +
                               file("ramp", ".rawlog") + " --config " + kConfig + " --poses " +
                               file("mixed", ".gt.tum") + " --output " + dir("bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("1 file(s) for 2 rawlog(s)"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir("bad")));
}

void MapCommands::aMapOfAnotherFrameIsRefusedInOneLine() {
  // The whole run's map at 0.2 m cells (its tree copied): another frame for the grid.
  fs::create_directories(dir("coarse"));
  maps::GridParams p;
  p.cell_size_m = 0.2;
  gdal::writeGeoTiff(maps::TraversabilityGrid(p), (dir("coarse") / "map.tif").string());
  fs::copy_file(dir("whole") / "map_traversability.ot", dir("coarse") / "map_traversability.ot",
                fs::copy_options::overwrite_existing);
  // A run played with --epsg: poses in UTM zone 33N, so map.tif carries that CRS.
  play("utm", {"mixed"}, "--to 1 --epsg 32633");
  const json utm = gdalinfo(dir("utm") / "map.tif");
  EXPECT_NE(utm["coordinateSystem"]["wkt"].get<std::string>().find("ID[\"EPSG\",32633]"),
            std::string::npos);
  for (const auto& [other, expected] : {std::pair{"coarse", "cell size 0.2"},
                                        std::pair{"utm", "CRS EPSG:32633"}}) {
    const CmdResult r = map("merge " + dir("whole").string() + " " + dir(other).string() +
                            " --output " + dir("refused").string());
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("different frames"), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(dir("refused")));
  }
}

void MapCommands::cropKeepsExactlyTheRegion() {
  const CmdResult r = map("crop " + dir("whole").string() + " --region 2,-1.5,5,1.5 --output " +
                          dir("crop").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json info = gdalinfo(dir("crop") / "map.tif");
  EXPECT_NEAR(info["geoTransform"][0].get<double>(), 2.0, 1e-9);
  EXPECT_NEAR(info["geoTransform"][3].get<double>(), 1.5, 1e-9);  // y max: a square window
  EXPECT_EQ(info["size"], json({30, 30}));
  const auto whole = gdal::readGeoTiff((dir("whole") / "map.tif").string()).grid;
  const auto crop = gdal::readGeoTiff((dir("crop") / "map.tif").string()).grid;
  std::size_t inside = 0;
  maps::forEachKnownCell(whole, [&](int cx, int cy, const maps::GridCell& c) {
    const Eigen::Vector2d xy = whole.cellCenter(cx, cy);
    const bool in = xy.x() > 2 && xy.x() < 5 && xy.y() > -1.5 && xy.y() < 1.5;
    const maps::GridCell* k = crop.cellAt(xy.x(), xy.y());
    EXPECT_EQ(k != nullptr && k->observed(), in) << xy.transpose();
    if (in && k != nullptr) {
      EXPECT_EQ(k->hits, c.hits);
    }
    inside += in;
  });
  EXPECT_GT(inside, 100u);
  EXPECT_EQ(maps::computeStats(crop).known, inside);
  const auto tree = maps::readTraversabilityOt((dir("crop") / "map_traversability.ot").string());
  for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it) {
    ASSERT_GE(it.getX(), 2.0 - 0.1) << it.getCoordinate();
    ASSERT_LE(it.getX(), 5.0 + 0.1) << it.getCoordinate();
  }
  expectToolsOpen(dir("crop"));
  const CmdResult outside = map("crop " + dir("whole").string() +
                                " --region 500,500,501,501 --output " + dir("nothing").string());
  EXPECT_EQ(outside.exit_code, 1) << outside.output;
  EXPECT_NE(outside.output.find("outside the map"), std::string::npos) << outside.output;
}

void MapCommands::infoPrintsWhatTheFolderHolds() {
  const CmdResult r = map("info " + dir("whole").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = json::parse(std::ifstream(dir("whole") / "summary.json"));
  for (const std::string& expected :
       {"rawlog: " + file("mixed", ".rawlog"), "cells known: " + s["grid"]["known"].dump() + " of",
        std::string(" non-traversable"), std::string("1 cost [1]; 2 p_nontrav [1]"),
        std::string("memory: grid"), std::string("CRS: none"), std::string("map_cost.pgm ("),
        "frames: " + s["frames_processed"].dump() + " processed"}) {
    EXPECT_NE(r.output.find(expected), std::string::npos) << expected << " in\n" << r.output;
  }
  const CmdResult missing = map("info " + tmp_->file("nowhere"));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("nowhere"), std::string::npos) << missing.output;
}

// One test, so that the run is simulated and played once (ctest runs each test in its own
// process).
TEST_F(MapCommands, MergeCropAndInfoOfSimulatedRuns) {
  {
    SCOPED_TRACE("MergingTwoHalvesGivesTheWholeRun");
    mergingTwoHalvesGivesTheWholeRun();
  }
  {
    SCOPED_TRACE("TwoRawlogsPlayedTogetherAreTheMergeOfTheirMaps");
    twoRawlogsPlayedTogetherAreTheMergeOfTheirMaps();
  }
  {
    SCOPED_TRACE("AMapOfAnotherFrameIsRefusedInOneLine");
    aMapOfAnotherFrameIsRefusedInOneLine();
  }
  {
    SCOPED_TRACE("CropKeepsExactlyTheRegion");
    cropKeepsExactlyTheRegion();
  }
  {
    SCOPED_TRACE("InfoPrintsWhatTheFolderHolds");
    infoPrintsWhatTheFolderHolds();
  }
}

}  // namespace
}  // namespace upd
