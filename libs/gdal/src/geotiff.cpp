#include "upd/gdal/geotiff.h"

#include "upd/io/atomic_file.h"
#include "upd/maps/fusion.h"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace upd::gdal {

namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Band order; bandValue and setBandValue follow it.
enum Band : int {
  kCost, kPNonTrav, kZetaMin, kSlope, kElevation, kHits, kLogOdds, kZetaMean, kElevationMax,
  kLastSeen, kZetaCount, kSlopeCount, kCostCount, kBandCount
};

double bandValue(const maps::GridCell& c, int band) {
  switch (band) {
    case kCost: return c.cost_mean;
    case kPNonTrav: return maps::probabilityFromLogOdds(c.logodds_nontrav);
    case kZetaMin: return c.zeta_min;
    case kSlope: return c.slope_rad;
    case kElevation: return c.elevation_m;
    case kHits: return c.hits;
    case kLogOdds: return c.logodds_nontrav;
    case kZetaMean: return c.zeta_mean;
    case kElevationMax: return c.elevation_max_m;
    case kLastSeen: return c.last_seen_s;
    case kZetaCount: return c.zeta_count;
    case kSlopeCount: return c.slope_count;
    case kCostCount: return c.cost_count;
    default: return kNaN;
  }
}

bool isCountBand(int band) {
  return band == kHits || band == kZetaCount || band == kSlopeCount || band == kCostCount;
}

// A count band's value converts to a cell's 32-bit count only when it is one.
bool isCount(double v) { return v >= 0 && v <= 4294967295.0 && v == std::floor(v); }

std::uint32_t count(double v) { return static_cast<std::uint32_t>(v); }

void setBandValue(maps::GridCell& c, int band, double v) {
  switch (band) {
    case kCost: c.cost_mean = static_cast<float>(v); break;
    case kZetaMin: c.zeta_min = static_cast<float>(v); break;
    case kSlope: c.slope_rad = static_cast<float>(v); break;
    case kElevation: c.elevation_m = static_cast<float>(v); break;
    case kHits: c.hits = count(v); break;
    case kLogOdds: c.logodds_nontrav = static_cast<float>(v); break;
    case kZetaMean: c.zeta_mean = static_cast<float>(v); break;
    case kElevationMax: c.elevation_max_m = static_cast<float>(v); break;
    case kLastSeen: c.last_seen_s = v; break;
    case kZetaCount: c.zeta_count = count(v); break;
    case kSlopeCount: c.slope_count = count(v); break;
    case kCostCount: c.cost_count = count(v); break;
    default: break;  // p_nontrav is derived from the log-odds
  }
}

// GDAL registered once; its messages go into the exceptions, not to stderr.
void initGdal() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

struct QuietErrors {
  QuietErrors() {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietErrors() { CPLPopErrorHandler(); }
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;
};

std::string gdalMessage() {
  const char* m = CPLGetLastErrorMsg();
  return (m != nullptr && *m != '\0') ? std::string(": ") + m : std::string();
}

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

OGRSpatialReference spatialReference(int epsg) {
  OGRSpatialReference srs;
  if (srs.importFromEPSG(epsg) != OGRERR_NONE) {
    throw std::invalid_argument("EPSG:" + std::to_string(epsg) + ": unknown to GDAL/PROJ");
  }
  if (!srs.IsProjected() || std::abs(srs.GetLinearUnits() - 1.0) > 1e-12) {
    throw std::invalid_argument("EPSG:" + std::to_string(epsg) +
                                ": not a projected CRS in metres (the map's x and y are metres)");
  }
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

void describeBands(GDALDataset& ds) {
  const auto& specs = geoTiffBands();
  for (int b = 0; b < kBandCount; ++b) {
    GDALRasterBand* band = ds.GetRasterBand(b + 1);
    band->SetDescription(specs[b].name);
    band->SetUnitType(specs[b].unit);
    band->SetNoDataValue(kNaN);
  }
}

void writeBands(const maps::TraversabilityGrid& grid, GDALDataset& ds, const std::string& path) {
  const int w = grid.sizeX(), h = grid.sizeY();
  std::vector<double> buf(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (int b = 0; b < kBandCount; ++b) {
    for (int row = 0; row < h; ++row) {
      const int cy = h - 1 - row;  // north up
      for (int cx = 0; cx < w; ++cx) {
        const maps::GridCell& c = grid.at(cx, cy);
        buf[static_cast<std::size_t>(row) * w + cx] = c.observed() ? bandValue(c, b) : kNaN;
      }
    }
    if (ds.GetRasterBand(b + 1)->RasterIO(GF_Write, 0, 0, w, h, buf.data(), w, h, GDT_Float64,
                                          0, 0, nullptr) != CE_None) {
      throw std::runtime_error("cannot write " + path + gdalMessage());
    }
  }
}

void writeDataset(const maps::TraversabilityGrid& grid, const std::string& tmp,
                  const std::string& path, const GeoTiffOptions& options) {
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (driver == nullptr) throw std::runtime_error("cannot write " + path + ": no GTiff driver");
  const char* create_options[] = {"COMPRESS=DEFLATE", "PREDICTOR=3", "TILED=YES",
                                  "INTERLEAVE=BAND", nullptr};
  DatasetPtr ds(driver->Create(tmp.c_str(), grid.sizeX(), grid.sizeY(), kBandCount, GDT_Float64,
                               const_cast<char**>(create_options)));
  if (!ds) throw std::runtime_error("cannot write " + path + gdalMessage());
  double gt[6] = {grid.xMin(), grid.cellSize(), 0.0, grid.yMax(), 0.0, -grid.cellSize()};
  ds->SetGeoTransform(gt);
  if (options.epsg != 0) {
    const OGRSpatialReference srs = spatialReference(options.epsg);
    ds->SetSpatialRef(&srs);
  }
  ds->SetMetadataItem("UPD_P_NONTRAV_THRESHOLD",
                      std::to_string(grid.params().p_nontrav_threshold).c_str());
  ds->SetMetadataItem("UPD_MIN_HITS_KNOWN", std::to_string(grid.params().min_hits_known).c_str());
  describeBands(*ds);
  writeBands(grid, *ds, path);
  ds->FlushCache();
  if (CPLGetLastErrorType() >= CE_Failure) {
    throw std::runtime_error("cannot write " + path + gdalMessage());
  }
}

}  // namespace

void validateEpsg(int epsg) { spatialReference(epsg); }

const std::vector<BandSpec>& geoTiffBands() {
  static const std::vector<BandSpec> bands{
      {"cost", "1", "mean traversal cost of the cell's points, 0 (easy) .. 1"},
      {"p_nontrav", "1", "probability that the cell is non-traversable"},
      {"zeta_min", "1", "smallest UPD zeta of any point seen in the cell"},
      {"slope_rad", "rad", "mean slope of the points' UPD direction r"},
      {"elevation_m", "m", "mean z of the cell's labelled points"},
      {"hits", "count", "labelled points integrated in the cell"},
      {"logodds_nontrav", "1", "fused log-odds of non-traversable (the fusion rule's state)"},
      {"zeta_mean", "1", "mean UPD zeta"},
      {"elevation_max_m", "m", "highest z of the cell's labelled points"},
      {"last_seen_s", "s", "time of the last frame that updated the cell"},
      {"zeta_count", "count", "points behind zeta_mean"},
      {"slope_count", "count", "points behind slope_rad"},
      {"cost_count", "count", "points behind cost"},
  };
  return bands;
}

void writeGeoTiff(const maps::TraversabilityGrid& grid, const std::string& path,
                  const GeoTiffOptions& options) {
  if (options.epsg != 0) validateEpsg(options.epsg);  // fail before creating anything
  initGdal();
  const QuietErrors quiet;
  io::writeFileAtomicallyVia(
      path,
      [&](const std::string& tmp) {
        try {
          writeDataset(grid, tmp, path, options);  // closed (flushed to disk) on return
        } catch (...) {
          std::error_code ec;
          fs::remove(tmp + ".aux.xml", ec);
          throw;
        }
      },
      ".tif");
}

namespace {

// The grid window the file covers: a fixed square window whose first cell is world cell
// (i0, j0), sized to hold width x height cells.
maps::GridParams windowParams(const std::string& path, const double gt[6], int width, int height,
                              GDALDataset& ds) {
  const double cell = gt[1];
  if (!(cell > 0) || gt[2] != 0.0 || gt[4] != 0.0 || std::abs(gt[5] + cell) > 1e-9 * cell) {
    throw std::runtime_error("GeoTIFF " + path + ": not a north-up raster with square cells");
  }
  if (!std::isfinite(gt[0]) || !std::isfinite(gt[3])) {
    throw std::runtime_error("GeoTIFF " + path + ": its origin is not finite");
  }
  const double fi = gt[0] / cell, fj = gt[3] / cell - height;
  if (std::abs(fi - std::round(fi)) > 1e-6 || std::abs(fj - std::round(fj)) > 1e-6) {
    throw std::runtime_error("GeoTIFF " + path + ": origin not aligned to its cell size");
  }
  const int n = std::max(width, height);
  maps::GridParams p;
  p.cell_size_m = cell;
  p.extent_m = n * cell;
  p.follow_robot = false;
  // floor(center / cell) - n / 2 must give the file's first cell (traversability_grid.cpp).
  p.center_x_m = (std::round(fi) + n / 2 + 0.5) * cell;
  p.center_y_m = (std::round(fj) + n / 2 + 0.5) * cell;
  if (const char* t = ds.GetMetadataItem("UPD_P_NONTRAV_THRESHOLD")) p.p_nontrav_threshold = std::atof(t);
  if (const char* k = ds.GetMetadataItem("UPD_MIN_HITS_KNOWN")) p.min_hits_known = std::atoi(k);
  try {
    p.validate();  // a window beyond the grid's reach, a damaged threshold
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("GeoTIFF " + path + ": " + e.what());
  }
  return p;
}

void checkBands(const std::string& path, GDALDataset& ds) {
  const auto& specs = geoTiffBands();
  if (ds.GetRasterCount() != kBandCount) {
    throw std::runtime_error("GeoTIFF " + path + ": " + std::to_string(ds.GetRasterCount()) +
                             " bands, not the " + std::to_string(kBandCount) +
                             " of a traversability map");
  }
  for (int b = 0; b < kBandCount; ++b) {
    const std::string d = ds.GetRasterBand(b + 1)->GetDescription();
    if (d != specs[b].name) {
      throw std::runtime_error("GeoTIFF " + path + ": band " + std::to_string(b + 1) + " is '" +
                               d + "', expected '" + specs[b].name + "'");
    }
  }
}

int epsgOf(GDALDataset& ds) {
  const OGRSpatialReference* srs = ds.GetSpatialRef();
  if (srs == nullptr) return 0;
  const char* code = srs->GetAuthorityCode(nullptr);
  return code != nullptr ? std::atoi(code) : 0;
}

}  // namespace

GeoTiffMap readGeoTiff(const std::string& path) {
  initGdal();
  const QuietErrors quiet;
  DatasetPtr ds(static_cast<GDALDataset*>(
      GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  if (!ds) throw std::runtime_error("GeoTIFF " + path + ": cannot be opened" + gdalMessage());
  checkBands(path, *ds);
  double gt[6];
  if (ds->GetGeoTransform(gt) != CE_None) {
    throw std::runtime_error("GeoTIFF " + path + ": no geotransform");
  }
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  GeoTiffMap out{maps::TraversabilityGrid(windowParams(path, gt, w, h, *ds)), epsgOf(*ds), w, h};
  std::vector<double> buf(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (int b = 0; b < kBandCount; ++b) {
    if (ds->GetRasterBand(b + 1)->RasterIO(GF_Read, 0, 0, w, h, buf.data(), w, h, GDT_Float64, 0,
                                           0, nullptr) != CE_None) {
      throw std::runtime_error("GeoTIFF " + path + ": cannot read band " + std::to_string(b + 1) +
                               gdalMessage());
    }
    for (int row = 0; row < h; ++row) {
      for (int cx = 0; cx < w; ++cx) {
        const double v = buf[static_cast<std::size_t>(row) * w + cx];
        if (std::isnan(v)) continue;  // nodata
        if (isCountBand(b) && !isCount(v)) {
          std::ostringstream os;
          os << "GeoTIFF " << path << ": band " << b + 1 << " '" << geoTiffBands()[b].name
             << "' holds " << v << " at pixel (" << cx << ", " << row << "), not a count";
          throw std::runtime_error(os.str());
        }
        setBandValue(out.grid.at(cx, h - 1 - row), b, v);
      }
    }
  }
  return out;
}

}  // namespace upd::gdal
