#include "viosfm/io/colmap_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Reference models written by COLMAP 3.8 (see testdata/README.md).
fs::path TestData(const std::string& name) {
  return viosfm::testing::SourcePath("io/testdata/" + name);
}

const char* kTextFiles[] = {"cameras.txt", "images.txt", "points3D.txt"};
const char* kBinaryFiles[] = {"cameras.bin", "images.bin", "points3D.bin"};

std::string ReadBytes(const fs::path& path) {
  return ReadTextFile(path);
}

// Byte equality of the three files; reports the first differing offset.
void ExpectSameFiles(const fs::path& expected, const fs::path& actual, const char* const* names) {
  for (int i = 0; i < 3; ++i) {
    const std::string a = ReadBytes(expected / names[i]);
    const std::string b = ReadBytes(actual / names[i]);
    size_t first_difference = 0;
    while (first_difference < a.size() && first_difference < b.size() &&
           a[first_difference] == b[first_difference]) {
      ++first_difference;
    }
    EXPECT_TRUE(a == b) << names[i] << " differs from " << expected / names[i] << " at byte "
                        << first_difference << " (sizes " << a.size() << " vs " << b.size() << ")";
  }
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Copies a reference model into a scratch folder.
fs::path CopyModel(const std::string& name) {
  const fs::path folder = viosfm::testing::MakeScratchFolder(name) / "model";
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(TestData(name))) {
    fs::copy_file(entry.path(), folder / entry.path().filename());
  }
  return folder;
}

// Replaces the `line_number`-th line (1-based) of a text file.
void ReplaceLine(const fs::path& path, int line_number, const std::string& replacement) {
  std::istringstream in(ReadBytes(path));
  std::string out, line;
  for (int number = 1; std::getline(in, line); ++number) {
    out += (number == line_number ? replacement : line) + "\n";
  }
  WriteBytes(path, out);
}

std::string ReadError(const std::function<void()>& read) {
  try {
    read();
  } catch (const InputError& error) {
    return error.what();
  }
  ADD_FAILURE() << "no InputError thrown";
  return "";
}

class ColmapModelRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(ColmapModelRoundTrip, TextToTextIsByteIdentical) {
  const fs::path source = TestData(GetParam() + "_txt");
  const fs::path out = viosfm::testing::MakeScratchFolder("text") / "model";
  WriteColmapModelText(out, ReadColmapModelText(source));
  ExpectSameFiles(source, out, kTextFiles);
}

TEST_P(ColmapModelRoundTrip, BinaryToBinaryIsByteIdentical) {
  for (const std::string suffix : {"_bin", "_txt_to_bin"}) {
    const fs::path source = TestData(GetParam() + suffix);
    const fs::path out = viosfm::testing::MakeScratchFolder("binary") / "model";
    WriteColmapModelBinary(out, ReadColmapModelBinary(source));
    ExpectSameFiles(source, out, kBinaryFiles);
  }
}

// COLMAP's model_converter BIN -> TXT: X_txt was written by COLMAP from X_bin.
TEST_P(ColmapModelRoundTrip, BinaryToTextMatchesColmap) {
  Reconstruction reconstruction = ReadColmapModelBinary(TestData(GetParam() + "_bin"));
  ReorderAsColmapAfterRead(&reconstruction);
  const fs::path out = viosfm::testing::MakeScratchFolder("bin2txt") / "model";
  WriteColmapModelText(out, reconstruction);
  ExpectSameFiles(TestData(GetParam() + "_txt"), out, kTextFiles);
}

// COLMAP's model_converter TXT -> BIN: X_txt_to_bin was written by COLMAP from X_txt.
TEST_P(ColmapModelRoundTrip, TextToBinaryMatchesColmap) {
  Reconstruction reconstruction = ReadColmapModelText(TestData(GetParam() + "_txt"));
  ReorderAsColmapAfterRead(&reconstruction);
  const fs::path out = viosfm::testing::MakeScratchFolder("txt2bin") / "model";
  WriteColmapModelBinary(out, reconstruction);
  ExpectSameFiles(TestData(GetParam() + "_txt_to_bin"), out, kBinaryFiles);
}

// Without reordering, conversions keep the order: text -> binary -> text is
// the identity, and the binary and text readers agree.
TEST_P(ColmapModelRoundTrip, TextBinaryTextIsByteIdentical) {
  const fs::path source = TestData(GetParam() + "_txt");
  const fs::path binary = viosfm::testing::MakeScratchFolder("t2b") / "model";
  const fs::path text = viosfm::testing::MakeScratchFolder("b2t") / "model";
  WriteColmapModelBinary(binary, ReadColmapModelText(source));
  WriteColmapModelText(text, ReadColmapModel(binary));
  ExpectSameFiles(source, text, kTextFiles);
}

INSTANTIATE_TEST_SUITE_P(Colmap38, ColmapModelRoundTrip,
                         ::testing::Values("colmap_fountain", "colmap_multicam"));

TEST(ColmapModelTest, ReadsFountainContent) {
  const Reconstruction reconstruction = ReadColmapModel(TestData("colmap_fountain_txt"));
  ASSERT_EQ(reconstruction.NumCameras(), 1u);
  const Camera& camera = reconstruction.GetCamera(1);
  EXPECT_EQ(camera.model_id, CameraModelId::kSimpleRadial);
  EXPECT_EQ(camera.width, 3072u);
  EXPECT_EQ(camera.height, 2048u);
  EXPECT_EQ(camera.params,
            (std::vector<double>{2752.5354627566685, 1535.5, 1023.5, -0.010751085836105652}))
      << "COLMAP's principal point (1536, 1024) in viosfm's convention";
  EXPECT_EQ(reconstruction.NumRegImages(), 3u);
  EXPECT_EQ(reconstruction.NumPoints3D(), 174u);
  const Image* image = reconstruction.ImageByName("0006.jpg");
  ASSERT_NE(image, nullptr);
  EXPECT_EQ(image->image_id, 3u);
  EXPECT_EQ(image->timestamp_ns, std::nullopt);  // "0006" is a frame index
  EXPECT_EQ(image->cam_from_world.rotation.w(), 0.99999989828548241);
  EXPECT_EQ(image->cam_from_world.translation.x(), 4.9487198518113766);
  // Header statistic "mean observations per image: 166.33333333333334".
  EXPECT_EQ(reconstruction.ComputeNumObservations(), 499u);
  // Every observation is linked both ways.
  for (const auto& [point3D_id, point3D] : reconstruction.Points3D()) {
    for (const TrackElement& element : point3D.track) {
      EXPECT_EQ(reconstruction.GetImage(element.image_id).points2D[element.point2D_idx].point3D_id,
                point3D_id);
    }
  }
}

TEST(ColmapModelTest, ReadsOpenCvAndPinholeCameras) {
  const Reconstruction reconstruction = ReadColmapModel(TestData("colmap_multicam_bin"));
  ASSERT_EQ(reconstruction.NumCameras(), 2u);
  EXPECT_EQ(reconstruction.GetCamera(1).model_id, CameraModelId::kOpenCV);
  EXPECT_EQ(reconstruction.GetCamera(1).params,
            (std::vector<double>{2750.5, 2752.25, 1535, 1023, -0.0107, 0.0021, 0.0001, -0.0002}))
      << "principal point in viosfm's convention: COLMAP's minus 0.5";
  EXPECT_EQ(reconstruction.GetCamera(2).model_id, CameraModelId::kPinhole);
  EXPECT_EQ(reconstruction.GetCamera(2).params,
            (std::vector<double>{2760, 2761.5, 1535.5, 1023.5}));
  EXPECT_EQ(reconstruction.GetImage(2).camera_id, 2u);
  EXPECT_EQ(reconstruction.NumPoints3D(), 12u);
}

TEST(ColmapModelTest, WritesColmapFormattingDetails) {
  Reconstruction reconstruction;
  Camera camera;
  camera.camera_id = 5;
  camera.model_id = CameraModelId::kPinhole;
  camera.width = 640;
  camera.height = 480;
  camera.params = {500, 500.25, 319.5, 239.5};  // viosfm's convention: COLMAP's - 0.5
  reconstruction.AddCamera(camera);
  Image image;
  image.image_id = 2;
  image.camera_id = 5;
  image.name = "cam0/1403715273262142976.png";
  image.registered = true;
  image.points2D = {Point2D{Eigen::Vector2d(1.0, 1.5), kInvalidPoint3DId},
                    Point2D{Eigen::Vector2d(0.1, 2.5), kInvalidPoint3DId}};
  reconstruction.AddImage(image);
  Image unregistered = image;
  unregistered.image_id = 3;
  unregistered.name = "other.png";
  unregistered.registered = false;
  reconstruction.AddImage(unregistered);
  Image empty = image;
  empty.image_id = 4;
  empty.name = "empty.png";
  empty.points2D.clear();
  reconstruction.AddImage(empty);
  reconstruction.AddPoint3DWithId(
      7, Point3D{Eigen::Vector3d(1, -2, 1e-5), Vector3ub(255, 0, 9), 0.25, {{2, 1}}});
  reconstruction.AddPoint3DWithId(8, Point3D{Eigen::Vector3d(0, 0, 0), Vector3ub(1, 2, 3), -1, {}});

  const fs::path out = viosfm::testing::MakeScratchFolder("format") / "model";
  WriteColmapModelFolder(out, reconstruction, ColmapModelFormat::kText);
  EXPECT_EQ(ReadBytes(out / "cameras.txt"),
            "# Camera list with one line of data per camera:\n"
            "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
            "# Number of cameras: 1\n"
            "5 PINHOLE 640 480 500 500.25 320 240\n");
  EXPECT_EQ(ReadBytes(out / "images.txt"),
            "# Image list with two lines of data per image:\n"
            "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
            "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
            "# Number of images: 2, mean observations per image: 0.5\n"
            "2 1 0 0 0 0 0 0 5 cam0/1403715273262142976.png\n"
            "1.5 2 -1 0.59999999999999998 3 7\n"
            "4 1 0 0 0 0 0 0 5 empty.png\n"
            "\n");
  EXPECT_EQ(ReadBytes(out / "points3D.txt"),
            "# 3D point list with one line of data per point:\n"
            "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
            "# Number of points: 2, mean track length: 0.5\n"
            "7 1 -2 1.0000000000000001e-05 255 0 9 0.25 2 1\n"
            "8 0 0 0 1 2 3 -1 \n");

  // Read back: the image name gives the time stamp, the empty line no keypoints.
  const Reconstruction read = ReadColmapModel(out);
  EXPECT_EQ(read.NumImages(), 2u);
  EXPECT_EQ(read.GetImage(2).timestamp_ns, 1403715273262142976);
  EXPECT_TRUE(read.GetImage(4).points2D.empty());
  EXPECT_EQ(read.GetImage(2).points2D[1].point3D_id, 7u);
  EXPECT_TRUE(read.GetPoint3D(8).track.empty());

  // The folder is replaced as a whole.
  WriteColmapModelFolder(out, read, ColmapModelFormat::kBinary);
  EXPECT_FALSE(fs::exists(out / "cameras.txt"));
  EXPECT_TRUE(fs::exists(out / "points3D.bin"));
  EXPECT_EQ(ReadColmapModel(out).NumPoints3D(), 2u);
}

TEST(ColmapModelTest, TruncatedBinaryFileNamesFileAndOffset) {
  const fs::path folder = CopyModel("colmap_fountain_bin");
  const std::string bytes = ReadBytes(folder / "images.bin");
  WriteBytes(folder / "images.bin", bytes.substr(0, 20000));
  const std::string message = ReadError([&] { ReadColmapModelBinary(folder); });
  EXPECT_THAT(message, HasSubstr((folder / "images.bin").string()));
  EXPECT_THAT(message, HasSubstr("byte offset"));
  EXPECT_THAT(message, HasSubstr("image record 2 of 3"));
  EXPECT_THAT(message, HasSubstr("truncated"));

  // Cut inside a fixed-size field.
  const std::string cameras = ReadBytes(folder / "cameras.bin");
  WriteBytes(folder / "cameras.bin", cameras.substr(0, cameras.size() - 3));
  const std::string camera_message = ReadError([&] { ReadColmapModelBinary(folder); });
  EXPECT_THAT(camera_message, HasSubstr("cameras.bin: at byte offset 56 (camera record 1 of 1)"));
  EXPECT_THAT(camera_message, HasSubstr("parameter 4 of 4 of a SIMPLE_RADIAL camera"));
}

TEST(ColmapModelTest, BinaryUnknownModelAndTrailingBytes) {
  const fs::path folder = CopyModel("colmap_fountain_bin");
  std::string cameras = ReadBytes(folder / "cameras.bin");
  cameras[12] = 42;  // model id of the first camera (after count and id)
  WriteBytes(folder / "cameras.bin", cameras);
  EXPECT_THAT(ReadError([&] { ReadColmapModelBinary(folder); }),
              HasSubstr("unknown camera model id 42"));
  cameras[12] = 2;
  WriteBytes(folder / "cameras.bin", cameras + "x");
  EXPECT_THAT(ReadError([&] { ReadColmapModelBinary(folder); }),
              HasSubstr("expected the end of the file, found 1 more bytes"));
}

TEST(ColmapModelTest, GarbledTextLinesNameFileAndLine) {
  const fs::path folder = CopyModel("colmap_fountain_txt");
  const std::string images = ReadBytes(folder / "images.txt");

  ReplaceLine(folder / "images.txt", 5, "3 0.99 abc 0 0 1 2 3 1 0006.jpg");
  std::string message = ReadError([&] { ReadColmapModelText(folder); });
  EXPECT_THAT(message, HasSubstr((folder / "images.txt").string() + ":5: expected QX"));
  EXPECT_THAT(message, HasSubstr("'abc'"));

  // A quaternion far from unit: the tolerance of every reader (1e-3).
  ReplaceLine(folder / "images.txt", 5, "3 0.5 0 0 0 1 2 3 1 0006.jpg");
  EXPECT_THAT(ReadError([&] { ReadColmapModelText(folder); }),
              HasSubstr("images.txt:5: expected a unit quaternion QW QX QY QZ: its norm is 0.5"));

  WriteBytes(folder / "images.txt", images);
  ReplaceLine(folder / "images.txt", 6, "1.5 2.5 -1 7");
  EXPECT_THAT(ReadError([&] { ReadColmapModelText(folder); }),
              HasSubstr("images.txt:6: expected keypoints as triples"));

  WriteBytes(folder / "images.txt", images);
  ReplaceLine(folder / "cameras.txt", 4, "1 FISHEYE_X 3072 2048 1 2 3");
  EXPECT_THAT(ReadError([&] { ReadColmapModelText(folder); }),
              HasSubstr("cameras.txt:4: unknown camera model 'FISHEYE_X'"));

  ReplaceLine(folder / "cameras.txt", 4, "1 OPENCV 3072 2048 1 2 3");
  EXPECT_THAT(ReadError([&] { ReadColmapModelText(folder); }),
              HasSubstr("cameras.txt:4: camera model OPENCV expects 8 parameters, found 3"));

  ReplaceLine(folder / "cameras.txt", 4, "1 PINHOLE 3072 2048 1 2 3 4");
  // Track of the first point (line 4) now refers to an image that is not there.
  const std::string points = ReadBytes(folder / "points3D.txt");
  ReplaceLine(folder / "points3D.txt", 4, "127 -6.4 -5.1 21.3 152 100 117 1.6 3 497 99 374 2 445");
  EXPECT_THAT(ReadError([&] { ReadColmapModelText(folder); }),
              HasSubstr("points3D.txt:4: 3D point 127: track element (99, 374) refers to image "
                        "99, which is not in the images file"));

  // A track that drops an observation the image lists.
  ReplaceLine(folder / "points3D.txt", 4, "127 -6.4 -5.1 21.3 152 100 117 1.6 3 497 1 374");
  EXPECT_THAT(ReadError([&] { ReadColmapModelText(folder); }),
              HasSubstr("observes 3D point 127, whose track in the points3D file does not list "
                        "it"));
  WriteBytes(folder / "points3D.txt", points);
  EXPECT_EQ(ReadColmapModelText(folder).NumPoints3D(), 174u);
}

// Found by fuzz/fuzz_colmap_text: a text image name with a NUL was read,
// and writing the model as binary then failed a CHECK (internal error).
// Names are file names: no control characters, no spaces at either end.
TEST(ColmapModelTest, ImageNamesBothFormatsCannotHoldAreRejected) {
  const fs::path folder = CopyModel("colmap_fountain_txt");
  for (const std::string& name :
       {std::string("00\0006.jpg", 8), std::string("0006\x01.jpg"), std::string("a\tb.jpg")}) {
    ReplaceLine(folder / "images.txt", 5, "3 1 0 0 0 1 2 3 1 " + name);
    EXPECT_THAT(ReadError([&] { ReadColmapModelText(folder); }),
                HasSubstr("images.txt:5: image 3: image name has a control character"))
        << name;
  }
}

// Found by fuzz/fuzz_colmap_binary: a NaN keypoint coordinate was read from
// a binary model and did not survive a conversion to text and back. COLMAP
// never writes non-finite numbers; a model holding them is corrupt.
TEST(ColmapModelTest, NonFiniteNumbersAreRejected) {
  const fs::path folder = CopyModel("colmap_multicam_bin");
  const std::string images = ReadBytes(folder / "images.bin");
  // The first image's first keypoint x: after the count (8), id (4), pose
  // (56), camera id (4), the name and its NUL, and the keypoint count (8).
  const size_t name_end = images.find('\0', 8 + 4 + 56 + 4);
  ASSERT_NE(name_end, std::string::npos);
  std::string corrupt = images;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(&corrupt[name_end + 1 + 8], &nan, sizeof(nan));
  WriteBytes(folder / "images.bin", corrupt);
  EXPECT_THAT(ReadError([&] { ReadColmapModelBinary(folder); }),
              HasSubstr("expected a finite number as keypoint x (double), found nan"));

  const fs::path text = CopyModel("colmap_fountain_txt");
  ReplaceLine(text / "points3D.txt", 4, "127 -6.4 inf 21.3 152 100 117 1.6 3 497 1 374 2 445");
  EXPECT_THAT(ReadError([&] { ReadColmapModelText(text); }),
              HasSubstr("points3D.txt:4: expected Y (a finite number), found 'inf'"));
}

TEST(ColmapModelTest, MissingFolderOrFile) {
  EXPECT_THAT(ReadError([] { ReadColmapModel("/nonexistent/model"); }),
              HasSubstr("/nonexistent/model: COLMAP model folder does not exist"));
  const fs::path folder = CopyModel("colmap_fountain_txt");
  fs::remove(folder / "points3D.txt");
  EXPECT_THAT(ReadError([&] { ReadColmapModel(folder); }),
              HasSubstr("points3D.txt: file does not exist"));
}

}  // namespace
}  // namespace viosfm
