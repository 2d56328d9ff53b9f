#include "upd/maps/grid_state.h"

#include "grid_tiles.h"
#include "upd/io/atomic_file.h"

#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

namespace upd::maps {

namespace {

constexpr const char* kMagic = "UPD grid state 1";

// Writes each [GridParams] key as "key value".
struct ParamWriter {
  std::ostream& out;
  template <class T>
  void operator()(const char* key, T& value, const char* /*doc*/) {
    out << key << ' ' << value << '\n';
  }
};

// Sets each [GridParams] key from the lines read; a missing or malformed one is an error.
struct ParamReader {
  const std::map<std::string, std::string>& lines;
  const std::string& path;
  template <class T>
  void operator()(const char* key, T& value, const char* /*doc*/) {
    const auto it = lines.find(key);
    std::istringstream in(it == lines.end() ? std::string() : it->second);
    if (!(in >> value)) {
      throw std::runtime_error("cannot read grid state '" + path + "': no valid '" + key + "'");
    }
  }
};

std::runtime_error corrupt(const std::string& path, const std::string& why) {
  return std::runtime_error("cannot read grid state '" + path + "': " + why);
}

}  // namespace

void writeGridState(const TraversabilityGrid& grid, const std::string& path) {
  const detail::GridTileStore tiles = GridStateAccess::allCells(grid);
  io::writeFileAtomically(path, [&](std::ostream& out) {
    out << kMagic << '\n' << std::setprecision(17);
    GridParams params = grid.params();
    ParamWriter writer{out};
    params.visit(writer);
    out << "window " << grid.originI() << ' ' << grid.originJ() << '\n';
    out << "tiles " << tiles.tiles() << '\n';
    tiles.forEachKey([&](const detail::TileKey& key) {
      const std::vector<std::uint8_t>& bytes = *tiles.packed(key);
      out << key.first << ' ' << key.second << ' ' << bytes.size() << '\n';
      out.write(reinterpret_cast<const char*>(bytes.data()),
                static_cast<std::streamsize>(bytes.size()));
    });
  });
}

TraversabilityGrid readGridState(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw corrupt(path, "cannot open the file");
  std::string line;
  if (!std::getline(in, line) || line != kMagic) {
    throw corrupt(path, "not a grid state file (first line '" + line.substr(0, 40) + "')");
  }
  std::map<std::string, std::string> lines;
  std::string key;
  while (in >> key && key != "window") std::getline(in >> std::ws, lines[key]);
  std::int64_t i0 = 0, j0 = 0;
  std::size_t n = 0;
  std::string tiles_word;
  if (!(in >> i0 >> j0 >> tiles_word >> n) || tiles_word != "tiles") {
    throw corrupt(path, "no 'window' and 'tiles' lines");
  }
  GridParams params;
  ParamReader reader{lines, path};
  params.visit(reader);
  TraversabilityGrid grid(params);  // validates them
  detail::GridTileStore tiles(params.tile_cells);
  for (std::size_t k = 0; k < n; ++k) {
    std::int64_t tx = 0, ty = 0;
    std::size_t size = 0;
    if (!(in >> tx >> ty >> size) || in.get() != '\n' || size > (std::size_t{1} << 30)) {
      throw corrupt(path, "tile " + std::to_string(k) + " of " + std::to_string(n) + " is truncated");
    }
    std::vector<std::uint8_t> bytes(size);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
      throw corrupt(path, "tile " + std::to_string(k) + " of " + std::to_string(n) + " is truncated");
    }
    tiles.putPacked({tx, ty}, std::move(bytes));
  }
  try {
    GridStateAccess::restore(grid, i0, j0, std::move(tiles));
  } catch (const std::logic_error& e) {
    throw corrupt(path, e.what());  // a tile that does not decompress
  }
  return grid;
}

}  // namespace upd::maps
