// libFuzzer target: the other file readers of io/ on the same input: PLY
// point clouds (ASCII and binary), vocabulary-tree files, image pair lists,
// pair-decision CSV reports and the simulator's scene.csv. What the PLY and
// vocabulary readers accept must survive their writers (write -> read gives
// the same values again).
#include <cstring>

#include "fuzz_util.h"
#include "viosfm/io/pair_list.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/scene_structure_io.h"
#include "viosfm/io/verification_report.h"
#include "viosfm/io/vocabulary_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm;
  using namespace viosfm::fuzz;
  const std::filesystem::path path = ScratchFolder() / "input";
  const std::filesystem::path again = ScratchFolder() / "again";
  WriteBytes(path, AsText(data, size));

  PlyPoints points;
  if (AcceptsInput([&] { points = ReadPly(path); })) {
    WritePlyPoints(again, points.xyz, points.rgb);
    const PlyPoints reread = ReadPly(again);
    Require(reread.xyz.size() == points.xyz.size(), "PLY write -> read keeps the points");
    Require(reread.rgb == points.rgb, "PLY write -> read keeps the colours");
    for (size_t i = 0; i < points.xyz.size(); ++i) {
      Require(std::memcmp(reread.xyz[i].data(), points.xyz[i].data(), 3 * sizeof(double)) == 0,
              "PLY write -> read keeps every coordinate bit for bit");
    }
  }
  VocabularyData vocabulary;
  if (AcceptsInput([&] { vocabulary = ReadVocabulary(path); })) {
    WriteVocabulary(again, vocabulary);
    AcceptsInput([&] { ReadVocabulary(again); });
  }
  AcceptsInput([&] { ReadImagePairList(path); });
  AcceptsInput([&] { ReadPairDecisionsCsv(path); });
  AcceptsInput([&] { ReadSceneStructure(path); });
  return 0;
}
