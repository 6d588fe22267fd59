// Grey textures for the simulator's renderer: a mip-mapped raster with
// trilinear sampling, and procedural generators deterministic from a seed.
//
// Texture coordinates are in texels of the finest level: texel (i, j) (column
// i, row j) covers [i, i + 1) x [j, j + 1), so its centre is at (i + 0.5,
// j + 0.5). Textures TILE (wrap around) in both directions; width and height
// are powers of two so that every mip level tiles exactly.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "viosfm/sensor/grey_image.h"

namespace viosfm {

class Texture {
 public:
  Texture() = default;
  // `texels` is row-major, width * height values in [0, 1]; width and height
  // must be powers of two (checked). Builds the mip pyramid: each level is the
  // 2x2 box average of the one before, down to a level one texel wide or high.
  Texture(int width, int height, std::vector<float> texels);

  int width() const { return width_; }
  int height() const { return height_; }
  int num_levels() const { return static_cast<int>(levels_.size()); }
  // Texel (i, j) of `level` (indices wrap).
  float Texel(int level, int i, int j) const;

  // Value at (u, v) (texels of level 0) for a pixel whose footprint on the
  // texture is `footprint` texels wide: bilinear within the mip level(s)
  // log2(footprint), linear between the two nearest levels (trilinear).
  // footprint <= 1 samples level 0 only.
  float Sample(double u, double v, double footprint) const;
  // Bilinear sample of one level (u, v still in level-0 texels).
  float SampleLevel(int level, double u, double v) const;

 private:
  struct Level {
    int width = 0;
    int height = 0;
    std::vector<float> texels;
  };
  int width_ = 0;
  int height_ = 0;
  std::vector<Level> levels_;
};

struct ProceduralTextureOptions {
  int width = 512;   // texels, a power of two
  int height = 512;  // texels, a power of two
  uint64_t seed = 0;
  // Relative weights of the layers (0 switches a layer off).
  double noise_weight = 0.35;             // multi-scale value noise (wavelengths 4 .. 256 texels)
  double blobs_per_megatexel = 1500;      // soft discs/ellipses, radius 2 .. 40 texels
  double posters_per_megatexel = 60;      // framed rectangles, 30 .. 200 texels
  double text_blocks_per_megatexel = 60;  // rows of short strokes (text-like marks)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// A grey texture with detail at many scales (value noise, blobs, posters and
// text-like marks), contrast-stretched to about [0.05, 0.95]. The same options
// give the same texels.
Texture MakeProceduralTexture(const ProceduralTextureOptions& options);

// A checkerboard of `square` x `square` texel squares, values `dark` and
// `bright`, the square at texel (0, 0) dark. width, height and square are
// powers of two with square <= width, height, so the pattern tiles exactly.
Texture MakeCheckerboardTexture(int width, int height, int square, float dark = 0.1f,
                                float bright = 0.9f);

// The texture with its level-0 values remapped to mean + contrast * (value -
// 0.5), clamped to [0, 1] (e.g. contrast 0.1 for a weakly textured surface).
Texture WithContrast(const Texture& texture, float mean, float contrast);

// A size x size texture (size a power of two) of a grey image: the centred
// square of side min(width, height) resampled to size x size texels, by the
// area-weighted box filter when shrinking and bilinearly when enlarging;
// texel = grey / 255. Rows are flipped (texel row 0 is the image's bottom
// row), so on a surface whose v axis points up the photo stands upright. A
// size x size image is copied exactly.
Texture TextureFromImage(const GreyImage& image, int size);

// The width x height window (powers of two) of `texture`'s level 0 starting
// at texel (i0, j0), wrapping around: texel (i, j) of the result is texel
// (i0 + i, j0 + j) of `texture`. A window as large as the texture is a
// cyclic shift of it, which still tiles seamlessly.
Texture CropTexture(const Texture& texture, int i0, int j0, int width, int height);

// Smallest power of two >= value (value >= 1).
int NextPowerOfTwo(int value);

}  // namespace viosfm
