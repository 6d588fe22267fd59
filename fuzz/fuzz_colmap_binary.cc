// libFuzzer target: the COLMAP binary model reader (io/colmap_model.h). The
// input is cameras.bin, images.bin and points3D.bin separated by
// kFileSeparator. What is accepted must survive the writers: binary ->
// binary -> binary gives the same bytes twice, and binary -> text -> binary
// the same bytes as binary -> binary.
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
  WriteBytes(input / "cameras.bin", files[0]);
  WriteBytes(input / "images.bin", files[1]);
  WriteBytes(input / "points3D.bin", files[2]);
  Reconstruction model;
  if (!AcceptsInput([&] { model = ReadColmapModelBinary(input); })) return 0;

  const fs::path binary1 = ScratchFolder() / "binary1";
  const fs::path binary2 = ScratchFolder() / "binary2";
  const fs::path text = ScratchFolder() / "text";
  const fs::path binary3 = ScratchFolder() / "binary3";
  WriteColmapModelBinary(binary1, model);
  WriteColmapModelBinary(binary2, ReadColmapModelBinary(binary1));
  WriteColmapModelText(text, model);
  // Text holds what binary holds: numbers at 17 digits, names to the line end.
  Reconstruction from_text;
  if (!AcceptsInput([&] { from_text = ReadColmapModelText(text); })) {
    Require(false, "a model the binary reader accepts is readable after writing it as text");
  }
  WriteColmapModelBinary(binary3, from_text);
  for (const char* name : {"cameras.bin", "images.bin", "points3D.bin"}) {
    const std::string first = ReadTextFile(binary1 / name);
    Require(first == ReadTextFile(binary2 / name), "binary -> binary round trip is byte-identical");
    Require(first == ReadTextFile(binary3 / name), "binary -> text -> binary is byte-identical");
  }
  return 0;
}
