// The learned classifier: it learns a separable rule, its file round-trips in every format, bad
// files fail with one line naming the file, and damaged ones (cut short, a byte changed) and
// ones made or edited by hand (no checksum) are refused before OpenCV parses them.
#include "upd/learn/classifier.h"

#include "../../libs/learn/src/model_bytes.h"
#include "error_of.h"
#include "temp_dir.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace upd::learn {
namespace {

using core::kFeatureCount;
using core::Label;

// Points whose zeta (feature 0) is below 0.9 or whose slope (feature 1) is above 0.5 are
// obstacles; the other features are noise.
void makeData(int n, int seed, std::vector<float>& f, std::vector<Label>& t) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  f.resize(std::size_t(n) * kFeatureCount);
  t.resize(n);
  for (int i = 0; i < n; ++i) {
    float* row = &f[std::size_t(i) * kFeatureCount];
    for (int j = 0; j < kFeatureCount; ++j) row[j] = u(rng);
    row[0] = 0.7f + 0.3f * u(rng);
    t[i] = row[0] < 0.9f || row[1] > 0.5f ? Label::NonTraversable : Label::Traversable;
  }
}

double accuracy(const PointClassifier& c, const std::vector<float>& f, const std::vector<Label>& t) {
  const std::vector<float> p = c.probabilityOfFeatures(f);
  int right = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_GE(p[i], 0.f);
    EXPECT_LE(p[i], 1.f);
    right += (p[i] >= 0.5f) == (t[i] == Label::NonTraversable);
  }
  return double(right) / t.size();
}

TEST(PointClassifier, EveryKindLearnsASeparableRule) {
  std::vector<float> f, g;
  std::vector<Label> t, u;
  makeData(3000, 1, f, t);
  makeData(1000, 2, g, u);
  for (ModelKind kind : {ModelKind::RandomTrees, ModelKind::Boost, ModelKind::Svm}) {
    TrainParams p;
    p.kind = kind;
    p.trees = 30;
    const auto c = PointClassifier::train(f, t, core::FeatureParams{}, p);
    EXPECT_GT(accuracy(*c, g, u), 0.93) << toString(kind);
  }
}

// Random trees of `trees` trees trained on n points of makeData(seed), into f and t.
std::shared_ptr<PointClassifier> smallModel(int n, int seed, int trees,
                                            const core::FeatureParams& fp, std::vector<float>& f,
                                            std::vector<Label>& t) {
  makeData(n, seed, f, t);
  TrainParams p;
  p.trees = trees;
  return PointClassifier::train(f, t, fp, p);
}

TEST(PointClassifier, FileRoundTripsAndBadFilesFail) {
  std::vector<float> f;
  std::vector<Label> t;
  core::FeatureParams fp;
  fp.radius_m = 0.6;
  const auto c = smallModel(800, 3, 10, fp, f, t);
  TrainParams p;
  const test::TempDir tmp;
  const std::string path = (tmp.path() / "m.yml").string();
  c->save(path);
  const auto back = PointClassifier::load(path);
  EXPECT_EQ(back->kind(), ModelKind::RandomTrees);
  EXPECT_EQ(back->featureParams().radius_m, 0.6);
  EXPECT_EQ(back->probabilityOfFeatures(f), c->probabilityOfFeatures(f));
  EXPECT_EQ(c->featureImportance().size(), std::size_t(kFeatureCount));

  const std::string gz = (tmp.path() / "m.yml.gz").string();  // compressed, as shipped
  c->save(gz);
  EXPECT_EQ(PointClassifier::load(gz)->probabilityOfFeatures(f), c->probabilityOfFeatures(f));

  registerLoader();
  EXPECT_NE(core::loadPointLabeler(path), nullptr);
  const std::string junk = (tmp.path() / "junk.yml").string();
  std::ofstream(junk) << detail::withChecksum("%YAML:1.0\nfoo: 1\n", ".yml");
  const auto expectOneLine = [](const std::string& file, const std::string& part) {
    try {
      PointClassifier::load(file);
      FAIL() << file;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  };
  expectOneLine(junk, "not an UPD-Nav classifier");
  expectOneLine((tmp.path() / "none.yml").string(), "no such file");
  expectOneLine((tmp.path() / "m.model").string(), "extension");
  EXPECT_THROW(c->save((tmp.path() / "m.bin").string()), std::invalid_argument);
  std::vector<Label> one_class(t.size(), Label::Traversable);
  EXPECT_THROW(PointClassifier::train(f, one_class, fp, p), std::invalid_argument);
}

// PointClassifier::load's error on path, or "" when it loads.
std::string loadError(const std::string& path) {
  return test::errorOf([&] { PointClassifier::load(path); });
}

TEST(PointClassifier, DamagedFilesAreRefusedAsDamage) {
  std::vector<float> f;
  std::vector<Label> t;
  const auto c = smallModel(600, 4, 5, core::FeatureParams{}, f, t);
  const test::TempDir tmp;
  // Every format round-trips; the text ones carry their checksum after their first line.
  for (const char* name : {"m.yml", "m.xml", "m.json", "m.yml.gz"}) {
    c->save(tmp.file(name));
    EXPECT_EQ(PointClassifier::load(tmp.file(name))->probabilityOfFeatures(f),
              c->probabilityOfFeatures(f))
        << name;
  }
  const std::string yml = test::readFileBytes(tmp.file("m.yml"));
  const std::string xml = test::readFileBytes(tmp.file("m.xml"));
  const std::string json = test::readFileBytes(tmp.file("m.json"));
  const std::size_t yml_line2 = yml.find('\n') + 1;
  ASSERT_EQ(yml.compare(yml_line2, 16, "# upd-nav crc32 "), 0) << yml.substr(0, 80);
  ASSERT_EQ(xml.compare(xml.find('\n') + 1, 19, "<!-- upd-nav crc32 "), 0) << xml.substr(0, 80);
  ASSERT_EQ(json.compare(json.find('\n') + 1, 22, "    \"upd_nav_crc32\": \""), 0)
      << json.substr(0, 80);
  // (A digit in the model's last lines, one that OpenCV would read as another number.)
  const auto digitChanged = [](std::string text) {
    const std::size_t at = text.find_last_of("123456789");
    text[at] = text[at] == '1' ? '2' : '1';
    return text;
  };
  std::string bad_line = yml;
  bad_line.replace(yml_line2 + 16, 8, "zzzzzzzz");
  const std::string gz = test::readFileBytes(tmp.file("m.yml.gz"));
  std::string flipped_gz = gz;
  flipped_gz[gz.size() / 2] = static_cast<char>(flipped_gz[gz.size() / 2] ^ 0x10);
  // Each case: the damaged bytes, the extension they are read as, what the message says.
  const std::string cases[][3] = {
      {digitChanged(yml), ".yml", "damaged: its text does not match its checksum"},
      {yml.substr(0, yml.size() - 10), ".yml", "damaged: cut short: "},
      {yml + "x: 1\n", ".yml", "damaged: 5 bytes more than were written"},
      {bad_line, ".yml", "damaged: its checksum line ('zzzzzzzz of "},
      {digitChanged(xml), ".xml", "damaged: its text does not match its checksum"},
      {digitChanged(json), ".json", "damaged: its text does not match its checksum"},
      {gz.substr(0, gz.size() - 100), ".yml.gz", "damaged: cut short"},
      {flipped_gz, ".yml.gz", "damaged: "},
      {gz + "junk", ".yml.gz", "damaged: 4 bytes after the end of the compressed data"},
  };
  int n = 0;
  for (const auto& [text, ext, expected] : cases) {
    const std::string path = tmp.file("damaged" + std::to_string(n++) + ext);
    test::writeFileBytes(path, text);
    const std::string what = loadError(path);
    EXPECT_NE(what.find("classifier '" + path + "': " + expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  // OpenCV's parse error (of a text whose checksum matches), in one line with its line number.
  const std::string broken = tmp.file("broken.yml");
  test::writeFileBytes(broken, detail::withChecksum("%YAML:1.0\n---\nupd_point_classifier:\n"
                                                    "   kind: rtrees\n  - x\n",
                                                    ".yml"));
  const std::string what = loadError(broken);
  EXPECT_NE(what.find("OpenCV cannot read it (line "), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

// loadError in a child process, or "hung" where it has not answered within 20 s (the child
// killed): a parser that loops forever fails the test instead of hanging it.
std::string loadErrorOrHang(const std::string& path) {
  int fds[2];
  if (pipe(fds) != 0) return "no pipe";
  const pid_t child = fork();
  if (child == 0) {
    const std::string what = loadError(path);
    (void)!write(fds[1], what.data(), what.size());
    _exit(0);
  }
  close(fds[1]);
  std::string what;
  pollfd p{fds[0], POLLIN, 0};
  char buf[4096];
  while (poll(&p, 1, 20000) > 0) {
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n <= 0) break;
    what.append(buf, static_cast<std::size_t>(n));
  }
  const bool answered = p.revents != 0;
  close(fds[0]);
  if (!answered) kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  return answered ? what : "hung";
}

// A model made or edited by hand (no checksum) is refused in one line before OpenCV sees it:
// one OpenCV wrote without its checksum line; text on which OpenCV 4.6's YAML parser loops
// forever (a document marker with text after it, text after the document's end); and the
// fuzzer's finds (tests/fuzz/regressions/classifier: those hangs, and a tree's split of a
// variable the model does not declare, on which OpenCV's reader dereferenced null).
TEST(PointClassifier, ModelsMadeOrEditedByHandAreRefusedBeforeOpenCV) {
  std::vector<float> f;
  std::vector<Label> t;
  const auto c = smallModel(300, 5, 2, core::FeatureParams{}, f, t);
  const test::TempDir tmp;
  c->save(tmp.file("m.yml"));
  c->save(tmp.file("m.json"));
  const std::string yml = test::readFileBytes(tmp.file("m.yml"));
  const std::string json = test::readFileBytes(tmp.file("m.json"));
  const auto withoutLine2 = [](const std::string& text) {
    const std::size_t line2 = text.find('\n') + 1;
    return text.substr(0, line2) + text.substr(text.find('\n', line2) + 1);
  };
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, std::string>> files = {
      {tmp.file("by_hand.yml"), withoutLine2(yml)},
      {tmp.file("by_hand.json"), withoutLine2(json)},
      {tmp.file("marker.yml"), "%YAML:1.0\n---e:h\nima-\nc"},
      {tmp.file("ended.yml"), "%YAML:1.0\n---\n...\n-"},
  };
  for (const auto& [path, text] : files) test::writeFileBytes(path, text);
  const fs::path finds = fs::path(UPD_SOURCE_DIR) / "tests" / "fuzz" / "regressions" / "classifier";
  for (const auto& entry : fs::directory_iterator(finds)) files.emplace_back(entry.path(), "");
  ASSERT_GE(files.size(), 7u) << finds;
  for (const auto& file : files) {
    const std::string& path = file.first;
    const std::string what = loadErrorOrHang(path);
    const bool json_file = path.size() > 5 && path.substr(path.size() - 5) == ".json";
    EXPECT_NE(what.find("classifier '" + path + "': no checksum " +
                        (json_file ? "member" : "line") + " after its first line"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace upd::learn
