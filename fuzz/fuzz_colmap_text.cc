// libFuzzer target: the COLMAP text model reader (io/colmap_model.h). The
// input is cameras.txt, images.txt and points3D.txt separated by
// kFileSeparator. What is accepted must survive the writers: text -> text
// and text -> binary -> text give the same bytes as the first write.
#include "fuzz_util.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/util/file_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm;
  using namespace viosfm::fuzz;
  namespace fs = std::filesystem;
  const std::vector<std::string_view> files = SplitFiles(AsText(data, size), 3);
  const fs::path input = ScratchFolder() / "input";
  fs::create_directories(input);
  WriteBytes(input / "cameras.txt", files[0]);
  WriteBytes(input / "images.txt", files[1]);
  WriteBytes(input / "points3D.txt", files[2]);
  Reconstruction model;
  if (!AcceptsInput([&] { model = ReadColmapModelText(input); })) return 0;

  const fs::path text1 = ScratchFolder() / "text1";
  const fs::path text2 = ScratchFolder() / "text2";
  const fs::path binary = ScratchFolder() / "binary";
  const fs::path text3 = ScratchFolder() / "text3";
  WriteColmapModelText(text1, model);
  WriteColmapModelText(text2, ReadColmapModelText(text1));
  WriteColmapModelBinary(binary, model);
  WriteColmapModelText(text3, ReadColmapModelBinary(binary));
  for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
    const std::string first = ReadTextFile(text1 / name);
    Require(first == ReadTextFile(text2 / name), "text -> text round trip is byte-identical");
    Require(first == ReadTextFile(text3 / name), "text -> binary -> text is byte-identical");
  }
  return 0;
}
