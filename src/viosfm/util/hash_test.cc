#include "viosfm/util/hash.h"

#include <gtest/gtest.h>

#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

// The reference values of the FNV authors' test suite
// (http://www.isthe.com/chongo/src/fnv/test_fnv.c, FNV1A_64).
TEST(Fnv1a64, ReferenceVectors) {
  EXPECT_EQ(Fnv1a64Hash(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(Fnv1a64Hash("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(Fnv1a64Hash("foobar"), 0x85944171f73967e8ULL);
  EXPECT_EQ(HashToHex(Fnv1a64Hash("a")), "af63dc4c8601ec8c");
  EXPECT_EQ(HashToHex(0x1), "0000000000000001");
}

TEST(Fnv1a64, IncrementalEqualsWhole) {
  Fnv1a64 hash;
  hash.Update("foo");
  hash.Update("bar");
  EXPECT_EQ(hash.digest(), Fnv1a64Hash("foobar"));
  EXPECT_EQ(hash.HexDigest(), "85944171f73967e8");
}

TEST(Fnv1a64, FieldsKeepTheirBoundaries) {
  Fnv1a64 ab_c, a_bc;
  ab_c.UpdateField("ab");
  ab_c.UpdateField("c");
  a_bc.UpdateField("a");
  a_bc.UpdateField("bc");
  EXPECT_NE(ab_c.digest(), a_bc.digest());
  Fnv1a64 zero, negative_zero;
  zero.UpdateValue(0.0);
  negative_zero.UpdateValue(-0.0);
  EXPECT_NE(zero.digest(), negative_zero.digest());
}

TEST(HashFile, ImagesOfTheSameSizeWithOtherPixelsDiffer) {
  const std::filesystem::path dir = testing::MakeScratchFolder("hash_image");
  std::string pixels(752 * 480, '\x40');
  testing::WriteTextFile(dir / "a.pgm", "P5 752 480 255\n" + pixels);
  pixels[752 * 240 + 376] = '\x41';  // one grey level of one pixel
  testing::WriteTextFile(dir / "b.pgm", "P5 752 480 255\n" + pixels);
  const FileHash a = HashFile(dir / "a.pgm");
  const FileHash b = HashFile(dir / "b.pgm");
  EXPECT_EQ(a.size, b.size);
  EXPECT_NE(a.hash, b.hash);
}

TEST(HashFile, SizeAndContentAcrossBlocks) {
  const std::filesystem::path dir = testing::MakeScratchFolder("hash_file");
  // More than one 1 MiB block, so the blocks are chained.
  std::string content(3 * (1 << 20) / 2, 'x');
  content[12345] = 'y';
  testing::WriteTextFile(dir / "big.bin", content);
  const FileHash hash = HashFile(dir / "big.bin");
  EXPECT_EQ(hash.size, content.size());
  // The file read in blocks gives the hash of its content in one piece.
  EXPECT_EQ(hash.hash, Xxh3Hash(content.data(), content.size()));
  // One byte changed anywhere changes the hash.
  content[content.size() - 1] = 'z';
  testing::WriteTextFile(dir / "big.bin", content);
  EXPECT_NE(HashFile(dir / "big.bin").hash, hash.hash);

  testing::WriteTextFile(dir / "empty", "");
  // XXH3_64bits of no bytes (seed 0), the xxHash specification's value.
  EXPECT_EQ(HashFile(dir / "empty").ToString(), "0 bytes, xxh3 2d06800538d394c2");
  const InputError error = testing::ExpectInputError([&] { HashFile(dir / "absent"); });
  EXPECT_EQ(error.path(), (dir / "absent").string());
}

}  // namespace
}  // namespace viosfm
