// The 2.5D traversability grid as a GeoTIFF, the raster format of GIS tools (QGIS, gdalinfo,
// rasterio): one Float64 band per layer, written and read back without loss.
//
// Layout (north up, as every GIS raster): pixel (col, row) is grid cell (cx, cy) =
// (col, sizeY() - 1 - row), so row 0 is the northern edge (y max). The geotransform is
// [x_min, cell_size_m, 0, y_max, 0, -cell_size_m]: the map origin and cell size in the map's
// world frame (metres). With an EPSG code (a projected CRS in metres, e.g. EPSG:32633 for
// UTM zone 33N when the run's poses are UTM easting/northing) the file carries that CRS;
// without one it has none (a local frame).
//
// Bands, in order (geoTiffBands(): name = the band's description, unit = its unit type):
// the six a user looks at first (cost, p_nontrav, zeta_min, slope_rad, elevation_m, hits),
// then what a lossless reload needs (logodds_nontrav, zeta_mean, elevation_max_m,
// last_seen_s and the point counts behind the means). A cell never observed (hits 0) is
// nodata (NaN) in every band; a known cell whose layer has no value (e.g. no cost) is NaN in
// that band only. The grid's p_nontrav_threshold and min_hits_known are kept in the dataset
// metadata (UPD_P_NONTRAV_THRESHOLD, UPD_MIN_HITS_KNOWN) so that labels read back the same.
//
// Written atomically (a temporary file beside the target, renamed over it); errors throw a
// one-line std::runtime_error naming the file, GDAL's own message included.
#pragma once

#include "upd/maps/traversability_grid.h"

#include <string>
#include <vector>

namespace upd::gdal {

/// One band of the file: its description (the layer name) and unit.
struct BandSpec {
  const char* name;
  const char* unit;
  const char* meaning;  ///< one line, for docs and `upd map info`
};
/// The bands in file order (band k + 1 is entry k).
const std::vector<BandSpec>& geoTiffBands();

struct GeoTiffOptions {
  /// EPSG code of the map frame's CRS (a projected CRS in metres); 0: no CRS (local frame).
  int epsg = 0;
};

/// Throws std::invalid_argument naming the code when GDAL does not know it or it is not a
/// projected CRS in metres.
void validateEpsg(int epsg);

/// Writes grid to path (the whole window). Throws std::invalid_argument for an EPSG code that
/// GDAL does not know or that is not a projected CRS in metres, std::runtime_error when
/// writing fails.
void writeGeoTiff(const maps::TraversabilityGrid& grid, const std::string& path,
                  const GeoTiffOptions& options = {});

/// What readGeoTiff returns: the grid (a fixed window at the file's position; a non-square
/// raster is padded with unknown cells to the east or north) and the raster's size.
struct GeoTiffMap {
  maps::TraversabilityGrid grid;
  int epsg = 0;          ///< 0: the file has no EPSG CRS
  int width = 0;         ///< raster columns
  int height = 0;        ///< raster rows
};

/// Reads a file written by writeGeoTiff. Throws std::runtime_error naming the file when it
/// cannot be opened, is not north-up, is not aligned to its own cell size or does not hold the
/// bands of geoTiffBands().
GeoTiffMap readGeoTiff(const std::string& path);

}  // namespace upd::gdal
