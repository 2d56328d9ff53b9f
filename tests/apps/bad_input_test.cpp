// The catalogue of bad inputs (docs/RELIABILITY.md): each case is run through the real `upd`
// as a user would, with its exact expectation. A job that cannot be done exits non-zero with
// one line naming the file (and the line, field or value), and leaves no output file, whole or
// half, and no temporary file. Inputs that are odd but valid (NaN-only clouds, empty XYZ) are
// scored and counted. Damaged rawlogs are in playback_damage_test.cpp; the reader-level cases
// in tests/io.
#include "io/cloud_samples.h"
#include "run_upd.h"
#include "temp_dir.h"

#include "upd/io/cloud_io.h"
#include "upd/mrpt_bridge/observation_cloud.h"

#include <gtest/gtest.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <nlohmann/json.hpp>
#include <sys/mount.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace upd {
namespace {

namespace fs = std::filesystem;
namespace samples = test::samples;
using json = nlohmann::json;
using test::CmdResult;
using test::runUpd;

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect.ini";

void writeBytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::size_t lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

// One input file, the text the error must contain (empty: the run must succeed).
struct Case {
  std::string name;   ///< the file name (its extension picks the reader)
  std::string bytes;  ///< its content
  std::string says;   ///< expected in the one error line; "" = exit 0
};

class BadInput : public ::testing::Test {
 protected:
  test::TempDir dir_{"catalogue"};

  fs::path in(const std::string& name) const { return dir_.path() / "in" / name; }
  fs::path out() const { return dir_.path() / "out"; }

  void SetUp() override {
    fs::create_directories(dir_.path() / "in");
    fs::create_directories(out());
  }

  // `upd analyze` on the case: an error is one line naming the file and c.says, exit 1, and
  // nothing in the output folder.
  CmdResult analyze(const Case& c, const std::string& extra = "") {
    writeBytes(in(c.name), c.bytes);
    fs::remove_all(out());
    fs::create_directories(out());
    const CmdResult r = runUpd("analyze " + in(c.name).string() + " --output " +
                               (out() / "scored.ply").string() + " --stats-json " +
                               (out() / "stats.json").string() + " " + extra);
    if (c.says.empty()) {
      EXPECT_EQ(r.exit_code, 0) << c.name << ": " << r.output;
      EXPECT_NO_THROW(io::readPly((out() / "scored.ply").string())) << c.name;
    } else {
      EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.output;
      EXPECT_EQ(lines(r.output), 1u) << c.name << ": " << r.output;
      EXPECT_NE(r.output.find(in(c.name).string()), std::string::npos) << r.output;
      EXPECT_NE(r.output.find(c.says), std::string::npos)
          << c.name << ": expected '" << c.says << "' in: " << r.output;
      EXPECT_TRUE(fs::is_empty(out())) << c.name << ": an output was written";
    }
    return r;
  }
};

std::string cut(const std::string& s, std::size_t keep) { return s.substr(0, keep); }

// Where the data of a sample starts (after its header's last line).
std::size_t dataStart(const std::string& s, const std::string& last_header_line) {
  return s.find(last_header_line) + last_header_line.size();
}

TEST_F(BadInput, TruncatedAndCorruptPcd) {
  const auto p = samples::grid();  // 36 points
  const std::string ascii = samples::pcdAscii(p);
  const std::size_t a0 = dataStart(ascii, "DATA ascii\n");
  const std::string lines18 = ascii.substr(0, a0);
  std::string half = lines18;
  for (std::size_t k = 0, pos = a0; k < 18; ++k) {
    const std::size_t nl = ascii.find('\n', pos);
    half += ascii.substr(pos, nl + 1 - pos);
    pos = nl + 1;
  }
  std::string bad_number = ascii;
  bad_number.replace(bad_number.find('\n', a0) + 1, 1, "x");
  const std::string bin = samples::pcdBinary(p);
  const std::size_t b0 = dataStart(bin, "DATA binary\n");
  const std::string comp = samples::pcdBinaryCompressed(p);
  const std::size_t c0 = dataStart(comp, "DATA binary_compressed\n");
  std::string comp_size = comp;
  comp_size[c0 + 4] = '\x7f';  // an uncompressed size the points do not have
  std::string comp_lzf = comp;
  comp_lzf[c0 + 8] = '\x70';   // a back-reference before the start of the output
  std::string no_z = bin;
  no_z.replace(no_z.find("FIELDS x y z"), 12, "FIELDS x y q");
  for (const Case& c : std::vector<Case>{
           {"ascii_cut_at_a_line.pcd", half, "truncated PCD: 18 of 36 points in the DATA ascii"},
           {"ascii_cut_in_a_line.pcd", cut(half, half.rfind(' ')), "2 values, the FIELDS/COUNT header says 3"},
           {"ascii_cut_before_width.pcd", cut(ascii, ascii.find("WIDTH")), "truncated or invalid PCD header: no DATA line"},
           {"ascii_cut_before_data.pcd", cut(ascii, ascii.find("DATA")), "truncated or invalid PCD header: no DATA line"},
           {"ascii_cut_after_data.pcd", cut(ascii, a0), "truncated PCD: 0 of 36 points"},
           {"ascii_bad_number.pcd", bad_number, "is not a number"},
           {"binary_cut.pcd", cut(bin, b0 + 200), "truncated PCD: DATA binary needs"},
           {"binary_no_z.pcd", no_z, "has no x/y/z fields (fields: x y q)"},
           {"compressed_cut.pcd", cut(comp, c0 + 100), "truncated PCD: the binary_compressed block needs"},
           {"compressed_cut_in_sizes.pcd", cut(comp, c0 + 5), "the binary_compressed block header is missing"},
           {"compressed_bad_size.pcd", comp_size, "corrupt"},
           {"compressed_bad_lzf.pcd", comp_lzf, "corrupt"}}) {
    analyze(c);
  }
}

TEST_F(BadInput, TruncatedAndCorruptPly) {
  const auto p = samples::grid();
  const std::string ascii = samples::plyAscii(p);
  const std::size_t a0 = dataStart(ascii, "end_header\n");
  std::string bad_number = ascii;
  bad_number.replace(a0, 1, "z");
  const std::string le = samples::plyBinary(p, false);
  const std::string be = samples::plyBinary(p, true);
  const std::size_t b0 = dataStart(le, "end_header\n");
  std::string bad_format = le;
  bad_format.replace(bad_format.find("binary_little_endian"), 20, "binary_middle_endian");
  for (const Case& c : std::vector<Case>{
           {"ascii_cut.ply", cut(ascii, a0 + 100), "truncated PLY"},
           {"ascii_cut_in_the_header.ply", cut(ascii, 30), "no end_header line"},
           {"ascii_bad_number.ply", bad_number, "is not a number"},
           {"le_cut.ply", cut(le, b0 + 100), "truncated PLY: the header declares 36 vertices"},
           {"be_cut.ply", cut(be, b0 + 100), "truncated PLY: the header declares 36 vertices"},
           {"le_cut_in_the_faces.ply", cut(le, le.size() - 2), ""},  // every vertex is there
           {"bad_format.ply", bad_format, "unknown format 'binary_middle_endian'"}}) {
    analyze(c);
  }
}

TEST_F(BadInput, TruncatedAndCorruptXyzAndKittiBin) {
  const auto p = samples::grid();
  const std::string xyz = samples::xyzText(p);
  const std::string bin = samples::kittiBin(p);
  std::string bad = xyz;
  bad.replace(bad.find('\n', 10) + 1, 1, "@");
  for (const Case& c : std::vector<Case>{
           {"cut_in_a_line.xyz", cut(xyz, xyz.find(' ', xyz.size() / 2) + 1), "expected 3 values like the first point line, got"},
           {"bad_number.xyz", bad, "line 3: '@"},
           {"cut.bin", cut(bin, bin.size() - 5), "571 bytes is not a whole number of 16-byte points"},
           {"cut_at_a_point.bin", cut(bin, 16 * 20), ""}}) {
    analyze(c);
  }
}

TEST_F(BadInput, AnotherFormatUnderTheWrongExtension) {
  const auto p = samples::grid();
  for (const Case& c : std::vector<Case>{
           {"ply_as.pcd", samples::plyAscii(p), "is a PLY file, not .pcd (rename it to .ply)"},
           {"pcd_as.ply", samples::pcdBinary(p), "is a PCD file, not .ply (rename it to .pcd)"},
           {"ply_as.xyz", samples::plyBinary(p, false), "is a PLY file, not .xyz (rename it to .ply)"},
           {"pcd_as.bin", samples::pcdAscii(p), "is a PCD file, not .bin (rename it to .pcd)"},
           {"xyz_as.bin", samples::xyzText(p), "is text, not a KITTI .bin scan"},
           {"bin_as.xyz", samples::kittiBin(p), "is not a number"},
           {"bin_as.ply", samples::kittiBin(p), "not a PLY file (no 'ply' magic line)"},
           {"gzip_as.pcd", std::string("\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03", 10), "is gzip-compressed data"},
           {"cloud.las", samples::kittiBin(p), "unsupported point cloud extension '.las'"}}) {
    analyze(c);
  }
}

// PCD and PLY need a header: an empty file is not one. XYZ and KITTI .bin have none: an empty
// file is a cloud of no points, scored as such.
TEST_F(BadInput, EmptyFiles) {
  for (const Case& c : std::vector<Case>{{"empty.pcd", "", "empty file, not a PCD file (no header)"},
                                         {"empty.ply", "", "not a PLY file (no 'ply' magic line)"},
                                         {"empty.xyz", "", ""},
                                         {"empty.bin", "", ""}}) {
    analyze(c);
  }
  EXPECT_EQ(json::parse(std::ifstream(out() / "stats.json"))["points_in"], 0);
}

// Only NaN or Inf: every point is counted invalid, none scored, exit 0, a valid (empty) PLY.
TEST_F(BadInput, CloudsOfOnlyNanOrInf) {
  for (const char* v : {"nan", "inf", "-inf"}) {
    std::string text;
    for (int i = 0; i < 50; ++i) text += std::string(v) + " 0 " + v + "\n";
    for (const char* pre : {"", "--no-preprocess"}) {
      analyze({std::string("only_") + v + ".xyz", text, ""}, pre);
      const json s = json::parse(std::ifstream(out() / "stats.json"));
      EXPECT_EQ(s["points_in"], 50) << v << pre;
      EXPECT_EQ(s["points_scored"], 0) << v << pre;
      EXPECT_TRUE(io::readPly((out() / "scored.ply").string()).empty());
    }
  }
}

// A coordinate of 1e30 m makes the cloud's extent too large for the voxel grid or the
// neighbour grid: one line naming the parameter and its value, nothing written.
TEST_F(BadInput, CoordinatesOf1e30) {
  std::string text = samples::xyzText(samples::grid());
  text += "1e30 1e30 1e30\n";
  analyze({"far.xyz", text, ""}, "--no-preprocess --knn 8");  // the k-d tree takes it
  const CmdResult r = runUpd("analyze " + in("far.xyz").string() + " --output " +
                             (out() / "far.ply").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(lines(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find("PreprocessParams.voxel_m = 0.02"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out() / "far.ply"));
  const CmdResult n = runUpd("analyze " + in("far.xyz").string() + " --no-preprocess");
  EXPECT_EQ(n.exit_code, 1) << n.output;
  EXPECT_NE(n.output.find("NormalParams.radius_m = 0.1"), std::string::npos) << n.output;
}

// Robot configs: each bad one stops the run before any input is read, naming the file, the
// section, the key and the value. An absent key keeps its default.
TEST_F(BadInput, Configs) {
  writeBytes(in("cloud.xyz"), samples::xyzText(samples::grid()));
  const struct {
    const char* name;
    const char* text;  ///< nullptr: the file does not exist
    const char* says;  ///< "" = accepted
  } cases[] = {
      {"missing.ini", nullptr, "missing.ini: not found"},
      {"unknown_key.ini", "[UpdParams]\nradius = 0.5\n", "[UpdParams] unknown key 'radius'"},
      {"unknown_section.ini", "[UPDParams]\nradius_m = 0.5\n", "unknown section [UPDParams]"},
      {"duplicated_key.ini", "[UpdParams]\nradius_m = 0.5\n; later\nradius_m = 0.7\n",
       "[UpdParams] radius_m is given twice (lines 2 and 4)"},
      {"duplicated_section.ini", "[UpdParams]\nradius_m = 0.5\n[ClassifyParams]\n[UpdParams]\nradius_m = 0.7\n",
       "[UpdParams] radius_m is given twice (lines 2 and 5)"},
      {"out_of_range.ini", "[UpdParams]\nradius_m = -1\n", "UpdParams.radius_m = -1: must be > 0"},
      {"out_of_range_deg.ini", "[ClassifyParams]\nmax_slope_deg = 95\n", "max_slope"},
      {"no_value.ini", "[UpdParams]\nradius_m =\n", "[UpdParams] radius_m = '': not a number"},
      {"not_a_number.ini", "[UpdParams]\nradius_m = half a metre\n", "radius_m = 'half a metre': not a number"},
      {"absent_key.ini", "[UpdParams]\n", ""},
  };
  for (const auto& c : cases) {
    if (c.text) writeBytes(in(c.name), c.text);
    fs::remove_all(out());
    fs::create_directories(out());
    const CmdResult r = runUpd("analyze " + in("cloud.xyz").string() + " --config " +
                               in(c.name).string() + " --output " + (out() / "s.ply").string());
    if (!*c.says) {
      EXPECT_EQ(r.exit_code, 0) << c.name << ": " << r.output;
      continue;
    }
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.output;
    EXPECT_EQ(lines(r.output), 1u) << r.output;
    EXPECT_NE(r.output.find(in(c.name).string()), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.name << ": " << r.output;
    EXPECT_TRUE(fs::is_empty(out())) << c.name;
  }
}

// Range images a driver can deliver: the frame is skipped with a reason naming what is wrong
// (playback counts it in summary.json's frames_skipped), never read out of bounds.
TEST(BadRangeImage, ZeroSizeMismatchedOrWithoutFocalLength) {
  auto scan = [](int w, int h, int cam_w, int cam_h, double f) {
    mrpt::obs::CObservation3DRangeScan o;
    o.hasRangeImage = true;
    o.rangeImage.setZero(h, w);
    if (w > 0 && h > 0) o.rangeImage(h / 2, w / 2) = 1000;
    o.rangeUnits = 1e-3f;
    o.cameraParams.ncols = cam_w;
    o.cameraParams.nrows = cam_h;
    o.cameraParams.fx(f);
    o.cameraParams.fy(f);
    o.cameraParams.cx(cam_w / 2.0);
    o.cameraParams.cy(cam_h / 2.0);
    return mrpt_bridge::toCloud(o);
  };
  const auto zero = scan(0, 0, 640, 480, 525);
  EXPECT_FALSE(zero.ok());
  EXPECT_EQ(zero.skipped_reason, "CObservation3DRangeScan has neither a range image nor 3D points");
  const auto mismatched = scan(320, 240, 640, 480, 525);
  EXPECT_FALSE(mismatched.ok());
  EXPECT_NE(mismatched.skipped_reason.find("are for 640x480 but the range image is 320x240"),
            std::string::npos)
      << mismatched.skipped_reason;
  for (double f : {0.0, -525.0, std::nan("")}) {
    const auto no_focal = scan(64, 48, 64, 48, f);
    EXPECT_EQ(no_focal.skipped_reason, "CObservation3DRangeScan: the depth camera has no focal length")
        << f;
  }
  const auto good = scan(64, 48, 64, 48, 50);
  ASSERT_TRUE(good.ok()) << good.skipped_reason;
  EXPECT_EQ(good.cloud_in_robot.size(), 64u * 48u);
}

// A tmpfs mounted for the test (root only): read-only, or of a few kB to fill up.
class ScratchMount {
 public:
  ScratchMount(const fs::path& where, const std::string& options) : where_(where) {
    fs::create_directories(where);
    mounted_ = ::geteuid() == 0 &&
               ::mount("tmpfs", where.c_str(), "tmpfs", 0, options.c_str()) == 0;
  }
  ~ScratchMount() {
    if (mounted_) ::umount2(where_.c_str(), MNT_DETACH);
  }
  ScratchMount(const ScratchMount&) = delete;
  ScratchMount& operator=(const ScratchMount&) = delete;
  bool mounted() const { return mounted_; }

 private:
  fs::path where_;
  bool mounted_ = false;
};

// Nothing but whole files: no temporary file left, every file there non-empty.
void expectNoPartialFiles(const fs::path& dir) {
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
    if (e.is_regular_file()) {
      EXPECT_GT(e.file_size(), 0u) << e.path();
    }
  }
}

TEST_F(BadInput, OutputFolderNotWritable) {
  writeBytes(in("cloud.xyz"), samples::xyzText(samples::grid()));
  writeBytes(out() / "a_file", "x");
  const fs::path under_file = out() / "a_file" / "scored.ply";
  CmdResult r = runUpd("analyze " + in("cloud.xyz").string() + " --output " + under_file.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(lines(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find(under_file.string()), std::string::npos) << r.output;

  const fs::path ro = dir_.path() / "read_only";
  const ScratchMount mount(ro, "ro,size=64k");
  if (!mount.mounted()) {
    fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
    if (::geteuid() == 0) GTEST_SKIP() << "read-only case: cannot mount a tmpfs (not permitted here)";
  }
  r = runUpd("analyze " + in("cloud.xyz").string() + " --output " + (ro / "scored.ply").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(lines(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find((ro / "scored.ply").string()), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_empty(ro));
  if (!mount.mounted()) fs::permissions(ro, fs::perms::owner_all);
}

// A disk that fills up while the outputs are written: one line naming the file that did not
// fit, exit 1, no temporary or partial file on the full disk.
TEST_F(BadInput, FullDisk) {
  if (::geteuid() != 0) GTEST_SKIP() << "full-disk case needs root to mount a 64 kB tmpfs";
  const fs::path disk = dir_.path() / "full";
  const ScratchMount mount(disk, "size=64k");
  if (!mount.mounted()) GTEST_SKIP() << "full-disk case: cannot mount a tmpfs (not permitted here)";
  const CmdResult scene = runUpd("scene rocks --output " + in("rocks.ply").string());
  ASSERT_EQ(scene.exit_code, 0) << scene.output;
  const fs::path ply = disk / "scored.ply";
  CmdResult r = runUpd("analyze " + in("rocks.ply").string() + " --output " + ply.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(lines(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find(ply.string()), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_empty(disk)) << "left on the full disk";

  const fs::path rawlog = dir_.path() / "run.rawlog";
  const CmdResult sim = runUpd("simulate --world mixed --frames 3 --output " + rawlog.string());
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  r = runUpd("playback " + rawlog.string() + " --config " + kConfig + " --quiet --output " +
             (disk / "maps").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(lines(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find((disk / "maps").string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(disk / "maps" / "summary.json"));
  expectNoPartialFiles(disk);
}

}  // namespace
}  // namespace upd
