// Class maps: the shipped SemanticKITTI and RELLIS-3D maps load and say what the data sets'
// documentation says; bad files fail with one line naming the file and line.
#include "upd/io/class_map.h"

#include "io_test_util.h"

#include <fstream>

namespace upd::io {
namespace {

using core::Label;

const std::string kShare = std::string(UPD_SOURCE_DIR) + "/share/class_maps/";

TEST(ClassMap, ShippedSemanticKittiMapsGroundAndObstacles) {
  const ClassMap m = readClassMap(kShare + "semantic-kitti.txt");
  EXPECT_EQ(m.classes.size(), 34u);
  EXPECT_EQ(m.classes.at(40), Label::Traversable);     // road
  EXPECT_EQ(m.classes.at(72), Label::Traversable);     // terrain
  EXPECT_EQ(m.classes.at(70), Label::NonTraversable);  // vegetation
  EXPECT_EQ(m.classes.at(254), Label::NonTraversable); // moving-person
  EXPECT_EQ(m.classes.at(0), Label::Unknown);          // unlabeled
  EXPECT_EQ(m.names.at(48), "sidewalk");
}

TEST(ClassMap, ShippedRellisMapsOffRoadGround) {
  const ClassMap m = readClassMap(kShare + "rellis-3d.txt");
  EXPECT_EQ(m.classes.size(), 20u);
  for (int id : {1, 3, 10, 23, 31, 33}) EXPECT_EQ(m.classes.at(id), Label::Traversable) << id;
  for (int id : {4, 5, 8, 17, 18, 19, 27, 34}) {
    EXPECT_EQ(m.classes.at(id), Label::NonTraversable) << id;
  }
  EXPECT_EQ(m.classes.at(7), Label::Unknown);  // sky
}

TEST(ClassMap, LabelsUseTheLower16BitsAndUnlistedIdsFail) {
  const ClassMap m = readClassMap(kShare + "semantic-kitti.txt");
  // Instance ids live in the upper 16 bits and must not change the class.
  const std::vector<std::uint32_t> labels = {40u, (7u << 16) | 10u, 0u};
  const auto truth = truthFromLabels(labels, m, "x.label");
  EXPECT_EQ(truth, (std::vector<Label>{Label::Traversable, Label::NonTraversable, Label::Unknown}));
  try {
    truthFromLabels({40u, 41u}, m, "x.label");
    FAIL() << "class 41 is not in the map";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("x.label: point 1 has class id 41"), std::string::npos)
        << e.what();
  }
}

TEST(ClassMap, BadFilesNameFileAndLine) {
  const test::TempDir tmp;
  const std::string f = (tmp.path() / "bad.txt").string();
  const auto expectError = [&](const std::string& text, const std::string& part) {
    std::ofstream(f) << text;
    try {
      readClassMap(f);
      FAIL() << "accepted: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    }
  };
  expectError("# c\n1 traversable a\n2 drivable b\n", f + ":3: class 'drivable'");
  expectError("1 traversable\n1 ignore\n", f + ":2: class id 1 listed twice");
  expectError("x traversable\n", f + ":1: class id 'x'");
  expectError("70000 ignore\n", f + ":1: class id '70000'");
  expectError("5\n", f + ":1: expected");
  expectError("# nothing\n", "no class listed");
  EXPECT_THROW(readClassMap((tmp.path() / "missing.txt").string()), std::runtime_error);
}

}  // namespace
}  // namespace upd::io
