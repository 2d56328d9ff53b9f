// The GeoTIFF export as GIS users open it: gdalinfo -json (bands, units, nodata, geotransform,
// CRS) and gdallocationinfo (a known cell's values at its world position), and our own reader
// (every layer back without loss).
#include "temp_dir.h"
#include "upd/gdal/geotiff.h"
#include "upd/maps/fusion.h"

#include "../apps/run_upd.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace upd {
namespace {

using json = nlohmann::json;

bool haveTool(const char* tool) {
  return std::system((std::string("command -v ") + tool + " >/dev/null 2>&1").c_str()) == 0;
}

// A 4 m window with 0.5 m cells around (10, -3): an obstacle cell and a ground cell known.
maps::TraversabilityGrid sampleGrid(double centre_x = 10.0, double centre_y = -3.0) {
  maps::GridParams p;
  p.cell_size_m = 0.5;
  p.extent_m = 4.0;
  p.follow_robot = false;
  p.center_x_m = centre_x;
  p.center_y_m = centre_y;
  maps::TraversabilityGrid g(p);
  maps::GridCell& rock = *g.cellAt(centre_x + 1.2, centre_y + 0.7);
  rock.logodds_nontrav = 2.55f;
  rock.zeta_min = 0.42f;
  rock.zeta_mean = 0.61f;
  rock.slope_rad = 0.7f;
  rock.cost_mean = 0.9f;
  rock.elevation_m = 0.35f;
  rock.elevation_max_m = 0.5f;
  rock.hits = 37;
  rock.zeta_count = 30;
  rock.slope_count = 29;
  rock.cost_count = 37;
  rock.last_seen_s = 1700000123.25;
  maps::GridCell& ground = g.at(0, 0);
  ground.logodds_nontrav = -1.2f;
  ground.zeta_min = 0.97f;
  ground.hits = 5;
  ground.zeta_count = 5;
  return g;
}

json gdalinfo(const std::string& path) {
  const test::CmdResult r = test::runCommand("gdalinfo -json '" + path + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return json::parse(r.output);
}

TEST(GeoTiff, GdalinfoSeesBandsNodataAndGeotransform) {
  if (!haveTool("gdalinfo")) GTEST_SKIP() << "gdalinfo not found (apt-get install gdal-bin)";
  const test::TempDir dir;
  const maps::TraversabilityGrid g = sampleGrid();
  gdal::writeGeoTiff(g, dir.file("map.tif"));
  EXPECT_EQ(dir.listing(), std::vector<std::string>{"map.tif"});
  const json info = gdalinfo(dir.file("map.tif"));
  EXPECT_EQ(info["driverShortName"], "GTiff");
  EXPECT_EQ(info["size"], json({g.sizeX(), g.sizeY()}));
  const json gt = info["geoTransform"];
  EXPECT_DOUBLE_EQ(gt[0].get<double>(), g.xMin());
  EXPECT_DOUBLE_EQ(gt[1].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(gt[3].get<double>(), g.yMax());  // north up: row 0 is y max
  EXPECT_DOUBLE_EQ(gt[5].get<double>(), -0.5);
  EXPECT_TRUE(!info.contains("coordinateSystem") ||
              info["coordinateSystem"]["wkt"].get<std::string>().empty());
  const auto& specs = gdal::geoTiffBands();
  ASSERT_EQ(info["bands"].size(), specs.size());
  const char* first[] = {"cost", "p_nontrav", "zeta_min", "slope_rad", "elevation_m", "hits"};
  for (std::size_t b = 0; b < specs.size(); ++b) {
    const json& band = info["bands"][b];
    SCOPED_TRACE(band.dump());
    if (b < 6) {
      EXPECT_EQ(band["description"], first[b]);
    }
    EXPECT_EQ(band["description"], specs[b].name);
    EXPECT_EQ(band["unit"], specs[b].unit);
    EXPECT_EQ(band["type"], "Float64");
    EXPECT_EQ(band["noDataValue"], "NaN");
  }
}

// The rock cell's values where a GIS user clicks: its world position.
TEST(GeoTiff, AKnownCellReadsAtItsWorldPosition) {
  if (!haveTool("gdallocationinfo")) GTEST_SKIP() << "gdallocationinfo not found (gdal-bin)";
  const test::TempDir dir;
  gdal::writeGeoTiff(sampleGrid(), dir.file("map.tif"));
  auto values = [&](double x, double y) {
    std::ostringstream cmd;
    cmd << "gdallocationinfo -valonly -geoloc '" << dir.file("map.tif") << "' " << x << " " << y;
    const test::CmdResult r = test::runCommand(cmd.str());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::istringstream in(r.output);
    std::vector<std::string> v;
    for (std::string s; in >> s;) v.push_back(s);
    return v;
  };
  const auto rock = values(11.2, -2.3);
  ASSERT_EQ(rock.size(), gdal::geoTiffBands().size());
  EXPECT_NEAR(std::stod(rock[0]), 0.9, 1e-6);                                         // cost
  EXPECT_NEAR(std::stod(rock[1]), maps::probabilityFromLogOdds(2.55f), 1e-6);         // p
  EXPECT_NEAR(std::stod(rock[2]), 0.42, 1e-6);                                        // zeta_min
  EXPECT_NEAR(std::stod(rock[3]), 0.7, 1e-6);                                         // slope
  EXPECT_NEAR(std::stod(rock[4]), 0.35, 1e-6);                                        // z
  EXPECT_EQ(rock[5], "37");                                                           // hits
  const auto unknown = values(9.1, -1.2);
  ASSERT_FALSE(unknown.empty());
  EXPECT_EQ(unknown[0], "nan");
}

TEST(GeoTiff, EpsgCodeBecomesTheCrs) {
  if (!haveTool("gdalinfo")) GTEST_SKIP() << "gdalinfo not found (apt-get install gdal-bin)";
  const test::TempDir dir;
  // UTM zone 33N poses: easting ~ 500 km, northing ~ 5000 km.
  gdal::writeGeoTiff(sampleGrid(500010.0, 5000020.0), dir.file("utm.tif"), {32633});
  const json info = gdalinfo(dir.file("utm.tif"));
  const std::string wkt = info["coordinateSystem"]["wkt"];
  EXPECT_NE(wkt.find("UTM zone 33N"), std::string::npos) << wkt;
  EXPECT_NE(wkt.find("ID[\"EPSG\",32633]"), std::string::npos) << wkt;
  EXPECT_NEAR(info["cornerCoordinates"]["upperLeft"][0].get<double>(), 500008.0, 1e-6);
  EXPECT_EQ(gdal::readGeoTiff(dir.file("utm.tif")).epsg, 32633);
  // A geographic CRS (degrees) or an unknown code is refused before anything is written.
  EXPECT_THROW(gdal::writeGeoTiff(sampleGrid(), dir.file("deg.tif"), {4326}), std::invalid_argument);
  EXPECT_THROW(gdal::writeGeoTiff(sampleGrid(), dir.file("bad.tif"), {999999}), std::invalid_argument);
  EXPECT_EQ(dir.listing(), std::vector<std::string>{"utm.tif"});
}

void expectSameCell(const maps::GridCell& a, const maps::GridCell& b) {
  auto same = [](double x, double y) { return (std::isnan(x) && std::isnan(y)) || x == y; };
  EXPECT_TRUE(same(a.logodds_nontrav, b.logodds_nontrav));
  EXPECT_TRUE(same(a.zeta_min, b.zeta_min));
  EXPECT_TRUE(same(a.zeta_mean, b.zeta_mean));
  EXPECT_TRUE(same(a.slope_rad, b.slope_rad));
  EXPECT_TRUE(same(a.cost_mean, b.cost_mean));
  EXPECT_TRUE(same(a.elevation_m, b.elevation_m));
  EXPECT_TRUE(same(a.elevation_max_m, b.elevation_max_m));
  EXPECT_TRUE(same(a.last_seen_s, b.last_seen_s));
  EXPECT_EQ(a.hits, b.hits);
  EXPECT_EQ(a.zeta_count, b.zeta_count);
  EXPECT_EQ(a.slope_count, b.slope_count);
  EXPECT_EQ(a.cost_count, b.cost_count);
}

TEST(GeoTiff, ReadsBackEveryLayerWithoutLoss) {
  const test::TempDir dir;
  maps::TraversabilityGrid g = sampleGrid(-7.3, 4.9);
  maps::GridParams p = g.params();
  gdal::writeGeoTiff(g, dir.file("map.tif"));
  const gdal::GeoTiffMap back = gdal::readGeoTiff(dir.file("map.tif"));
  EXPECT_EQ(back.epsg, 0);
  ASSERT_EQ(back.grid.sizeX(), g.sizeX());
  ASSERT_EQ(back.grid.sizeY(), g.sizeY());
  EXPECT_EQ(back.grid.originI(), g.originI());
  EXPECT_EQ(back.grid.originJ(), g.originJ());
  EXPECT_DOUBLE_EQ(back.grid.cellSize(), p.cell_size_m);
  EXPECT_DOUBLE_EQ(back.grid.params().p_nontrav_threshold, p.p_nontrav_threshold);
  for (int cy = 0; cy < g.sizeY(); ++cy) {
    for (int cx = 0; cx < g.sizeX(); ++cx) {
      SCOPED_TRACE(std::to_string(cx) + "," + std::to_string(cy));
      expectSameCell(back.grid.at(cx, cy), g.at(cx, cy));
    }
  }
}

TEST(GeoTiff, ReadingAnotherFileFailsNamingIt) {
  const test::TempDir dir;
  std::ofstream(dir.file("not.tif")) << "text";
  try {
    gdal::readGeoTiff(dir.file("not.tif"));
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not.tif"), std::string::npos) << e.what();
  }
  EXPECT_THROW(gdal::writeGeoTiff(sampleGrid(), dir.file("missing/map.tif")), std::runtime_error);
}

// A map file damaged after it was written (a count band edited to a value no count has, the
// origin moved beyond any grid, a threshold that is not a number) is refused naming the file and
// what is wrong; nothing is converted that would not fit.
TEST(GeoTiff, DamagedFileIsRefusedNamingWhatIsWrong) {
  const test::TempDir dir;
  const std::string good = dir.file("good.tif");
  gdal::writeGeoTiff(sampleGrid(), good);
  GDALAllRegister();
  struct Damage {
    const char* name;
    std::function<void(GDALDataset&)> apply;
    const char* expected;
  };
  const auto setPixel = [](int band, double v) {
    return [band, v](GDALDataset& ds) {
      double value = v;
      ASSERT_EQ(ds.GetRasterBand(band)->RasterIO(GF_Write, 2, 3, 1, 1, &value, 1, 1,
                                                  GDT_Float64, 0, 0, nullptr),
                CE_None);
    };
  };
  const auto moveOrigin = [](double x) {
    return [x](GDALDataset& ds) {
      double gt[6];
      ASSERT_EQ(ds.GetGeoTransform(gt), CE_None);
      gt[0] = x;
      ASSERT_EQ(ds.SetGeoTransform(gt), CE_None);
    };
  };
  const std::vector<Damage> damages = {
      {"negative_hits", setPixel(6, -1.0), "band 6 'hits' holds -1 at pixel (2, 3), not a count"},
      {"huge_count", setPixel(11, 1e20), "band 11 'zeta_count' holds 1e+20"},
      {"fraction", setPixel(13, 2.5), "band 13 'cost_count' holds 2.5"},
      {"far_origin", moveOrigin(1e300), "GridParams.center_x_m = "},
      {"threshold",
       [](GDALDataset& ds) { ds.SetMetadataItem("UPD_P_NONTRAV_THRESHOLD", "abc"); },
       "GridParams.p_nontrav_threshold = 0"},
  };
  for (const Damage& d : damages) {
    const std::string path = dir.file(std::string(d.name) + ".tif");
    std::filesystem::copy_file(good, path);
    {
      std::unique_ptr<GDALDataset> ds(
          static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE,
                                               nullptr, nullptr, nullptr)));
      ASSERT_TRUE(ds) << path;
      d.apply(*ds);
    }  // closed: written
    try {
      gdal::readGeoTiff(path);
      ADD_FAILURE() << d.name << ": read";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(d.expected), std::string::npos) << what;
    }
  }
  EXPECT_NO_THROW(gdal::readGeoTiff(good));
}

}  // namespace
}  // namespace upd
