#include "viosfm/sim/texture.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

bool IsPowerOfTwo(int value) {
  return value > 0 && (value & (value - 1)) == 0;
}

// A raster being painted, with wrap-around addressing.
class Canvas {
 public:
  Canvas(int width, int height, float value)
      : width_(width), height_(height), texels_(static_cast<size_t>(width) * height, value) {}

  float& at(int i, int j) {
    return texels_[static_cast<size_t>(j & (height_ - 1)) * width_ + (i & (width_ - 1))];
  }
  int width() const { return width_; }
  int height() const { return height_; }
  std::vector<float>& texels() { return texels_; }

  // Blends `value` with opacity `alpha` into the axis-aligned box
  // [x0, x1) x [y0, y1), anti-aliased by the exact area coverage of each texel.
  void FillBox(double x0, double y0, double x1, double y1, float value, float alpha) {
    const int i_begin = static_cast<int>(std::floor(x0));
    const int i_end = static_cast<int>(std::ceil(x1));
    const int j_begin = static_cast<int>(std::floor(y0));
    const int j_end = static_cast<int>(std::ceil(y1));
    for (int j = j_begin; j < j_end; ++j) {
      const double cover_y =
          std::clamp(std::min<double>(j + 1, y1) - std::max<double>(j, y0), 0.0, 1.0);
      for (int i = i_begin; i < i_end; ++i) {
        const double cover_x =
            std::clamp(std::min<double>(i + 1, x1) - std::max<double>(i, x0), 0.0, 1.0);
        const float a = alpha * static_cast<float>(cover_x * cover_y);
        float& texel = at(i, j);
        texel += a * (value - texel);
      }
    }
  }

  // Blends a soft-edged ellipse (semi-axes ra, rb, rotated by angle).
  void FillEllipse(double cx, double cy, double ra, double rb, double angle, float value,
                   float alpha) {
    const double extent = std::max(ra, rb) + 1.0;
    const double c = std::cos(angle);
    const double s = std::sin(angle);
    const double r_min = std::min(ra, rb);
    for (int j = static_cast<int>(std::floor(cy - extent)); j <= static_cast<int>(cy + extent);
         ++j) {
      for (int i = static_cast<int>(std::floor(cx - extent)); i <= static_cast<int>(cx + extent);
           ++i) {
        const double dx = i + 0.5 - cx;
        const double dy = j + 0.5 - cy;
        const double a = (c * dx + s * dy) / ra;
        const double b = (-s * dx + c * dy) / rb;
        const double normalized = std::sqrt(a * a + b * b);
        const double cover = std::clamp(0.5 + (1.0 - normalized) * r_min, 0.0, 1.0);
        if (cover <= 0.0) continue;
        float& texel = at(i, j);
        texel += alpha * static_cast<float>(cover) * (value - texel);
      }
    }
  }

 private:
  int width_;
  int height_;
  std::vector<float> texels_;
};

double LogUniform(Random& random, double low, double high) {
  return std::exp(random.Uniform(std::log(low), std::log(high)));
}

// Adds value noise of the given wavelength (a power of two, texels) and
// amplitude, tiling with the canvas.
void AddValueNoise(Canvas& canvas, int wavelength, double amplitude, Random& random) {
  const int cells_x = std::max(1, canvas.width() / wavelength);
  const int cells_y = std::max(1, canvas.height() / wavelength);
  std::vector<double> lattice(static_cast<size_t>(cells_x) * cells_y);
  for (double& value : lattice) value = random.Uniform(-1.0, 1.0);
  const auto node = [&](int i, int j) {
    return lattice[static_cast<size_t>(((j % cells_y) + cells_y) % cells_y) * cells_x +
                   ((i % cells_x) + cells_x) % cells_x];
  };
  const double cell_w = static_cast<double>(canvas.width()) / cells_x;
  const double cell_h = static_cast<double>(canvas.height()) / cells_y;
  for (int j = 0; j < canvas.height(); ++j) {
    const double y = (j + 0.5) / cell_h;
    const int y0 = static_cast<int>(std::floor(y));
    double fy = y - y0;
    fy = fy * fy * (3.0 - 2.0 * fy);
    for (int i = 0; i < canvas.width(); ++i) {
      const double x = (i + 0.5) / cell_w;
      const int x0 = static_cast<int>(std::floor(x));
      double fx = x - x0;
      fx = fx * fx * (3.0 - 2.0 * fx);
      const double top = node(x0, y0) + fx * (node(x0 + 1, y0) - node(x0, y0));
      const double bottom = node(x0, y0 + 1) + fx * (node(x0 + 1, y0 + 1) - node(x0, y0 + 1));
      canvas.at(i, j) += static_cast<float>(amplitude * (top + fy * (bottom - top)));
    }
  }
}

void AddPoster(Canvas& canvas, Random& random) {
  const double w = LogUniform(random, 30.0, 200.0);
  const double h = LogUniform(random, 30.0, 200.0);
  const double x0 = random.Uniform(0.0, canvas.width());
  const double y0 = random.Uniform(0.0, canvas.height());
  const float fill = static_cast<float>(random.Uniform(0.0, 1.0));
  const double border = random.Uniform(1.5, 5.0);
  const float frame = fill > 0.5f ? static_cast<float>(random.Uniform(0.0, 0.3))
                                  : static_cast<float>(random.Uniform(0.7, 1.0));
  canvas.FillBox(x0, y0, x0 + w, y0 + h, frame, 1.0f);
  canvas.FillBox(x0 + border, y0 + border, x0 + w - border, y0 + h - border, fill, 0.85f);
  // A few inner panels (pictures, headings).
  const int num_panels = static_cast<int>(random.UniformInt(0, 3));
  for (int k = 0; k < num_panels; ++k) {
    const double pw = random.Uniform(0.15, 0.6) * (w - 2 * border);
    const double ph = random.Uniform(0.1, 0.5) * (h - 2 * border);
    const double px = x0 + border + random.Uniform(0.0, w - 2 * border - pw);
    const double py = y0 + border + random.Uniform(0.0, h - 2 * border - ph);
    canvas.FillBox(px, py, px + pw, py + ph, static_cast<float>(random.Uniform(0.0, 1.0)), 0.9f);
  }
}

void AddTextBlock(Canvas& canvas, Random& random) {
  const double row_height = random.Uniform(5.0, 14.0);
  const int num_rows = static_cast<int>(random.UniformInt(2, 6));
  const double block_width = random.Uniform(40.0, 180.0);
  const double x0 = random.Uniform(0.0, canvas.width());
  const double y0 = random.Uniform(0.0, canvas.height());
  const bool dark_ink = random.Uniform() < 0.75;
  const float ink = dark_ink ? static_cast<float>(random.Uniform(0.0, 0.2))
                             : static_cast<float>(random.Uniform(0.8, 1.0));
  const double stroke = std::max(1.0, row_height * random.Uniform(0.12, 0.22));
  for (int row = 0; row < num_rows; ++row) {
    const double baseline = y0 + row * row_height * 1.6;
    double x = x0;
    const double row_end = x0 + block_width * random.Uniform(0.5, 1.0);
    while (x < row_end) {
      const int letters = static_cast<int>(random.UniformInt(2, 7));
      for (int k = 0; k < letters && x < row_end; ++k) {
        const double letter_w = row_height * random.Uniform(0.35, 0.7);
        const double top = baseline + row_height * random.Uniform(0.0, 0.35);
        const double bottom = baseline + row_height;
        switch (random.UniformInt(0, 3)) {
          case 0:  // vertical bar
            canvas.FillBox(x, top, x + stroke, bottom, ink, 1.0f);
            break;
          case 1:  // bar with a foot
            canvas.FillBox(x, top, x + stroke, bottom, ink, 1.0f);
            canvas.FillBox(x, bottom - stroke, x + letter_w, bottom, ink, 1.0f);
            break;
          case 2:  // box-like letter
            canvas.FillBox(x, top, x + letter_w, top + stroke, ink, 1.0f);
            canvas.FillBox(x, bottom - stroke, x + letter_w, bottom, ink, 1.0f);
            canvas.FillBox(x, top, x + stroke, bottom, ink, 1.0f);
            break;
          default:  // bar with a cap
            canvas.FillBox(x + 0.5 * letter_w - 0.5 * stroke, top,
                           x + 0.5 * letter_w + 0.5 * stroke, bottom, ink, 1.0f);
            canvas.FillBox(x, top, x + letter_w, top + stroke, ink, 1.0f);
            break;
        }
        x += letter_w + stroke * 1.5;
      }
      x += row_height * random.Uniform(0.6, 1.2);  // word gap
    }
  }
}

}  // namespace

Texture TextureFromImage(const GreyImage& image, int size) {
  VIOSFM_CHECK(IsPowerOfTwo(size)) << size;
  VIOSFM_CHECK(image.width > 0 && image.height > 0);
  const int side = std::min(image.width, image.height);
  const int x0 = (image.width - side) / 2;
  const int y0 = (image.height - side) / 2;
  const double scale = static_cast<double>(side) / size;  // source pixels per texel
  const auto pixel = [&](int x, int y) {
    return image.at(x0 + std::clamp(x, 0, side - 1), y0 + std::clamp(y, 0, side - 1)) / 255.0;
  };
  std::vector<float> texels(static_cast<size_t>(size) * size);
  if (scale >= 1.0) {
    // Box filter: the average of the source over the texel's footprint
    // [i * scale, (i + 1) * scale), pixels weighted by their overlap.
    std::vector<std::vector<std::pair<int, double>>> weights(size);
    for (int i = 0; i < size; ++i) {
      const double a = i * scale;
      const double b = (i + 1) * scale;
      for (int x = static_cast<int>(std::floor(a)); x < static_cast<int>(std::ceil(b)); ++x) {
        const double overlap = std::min<double>(x + 1, b) - std::max<double>(x, a);
        if (overlap > 1e-12) weights[i].emplace_back(x, overlap / scale);
      }
    }
    for (int j = 0; j < size; ++j) {
      for (int i = 0; i < size; ++i) {
        double sum = 0.0;
        for (const auto& [y, wy] : weights[j]) {
          for (const auto& [x, wx] : weights[i]) sum += wx * wy * pixel(x, y);
        }
        texels[static_cast<size_t>(size - 1 - j) * size + i] = static_cast<float>(sum);
      }
    }
  } else {
    // Bilinear between the source pixel centres (edges clamped).
    for (int j = 0; j < size; ++j) {
      const double y = (j + 0.5) * scale - 0.5;
      const int y_floor = static_cast<int>(std::floor(y));
      const double fy = y - y_floor;
      for (int i = 0; i < size; ++i) {
        const double x = (i + 0.5) * scale - 0.5;
        const int x_floor = static_cast<int>(std::floor(x));
        const double fx = x - x_floor;
        const double value =
            (1 - fy) * ((1 - fx) * pixel(x_floor, y_floor) + fx * pixel(x_floor + 1, y_floor)) +
            fy * ((1 - fx) * pixel(x_floor, y_floor + 1) + fx * pixel(x_floor + 1, y_floor + 1));
        texels[static_cast<size_t>(size - 1 - j) * size + i] = static_cast<float>(value);
      }
    }
  }
  return Texture(size, size, std::move(texels));
}

Texture CropTexture(const Texture& texture, int i0, int j0, int width, int height) {
  VIOSFM_CHECK(IsPowerOfTwo(width) && IsPowerOfTwo(height)) << width << " x " << height;
  std::vector<float> texels(static_cast<size_t>(width) * height);
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      texels[static_cast<size_t>(j) * width + i] = texture.Texel(0, i0 + i, j0 + j);
    }
  }
  return Texture(width, height, std::move(texels));
}

int NextPowerOfTwo(int value) {
  VIOSFM_CHECK_GE(value, 1);
  int power = 1;
  while (power < value) power *= 2;
  return power;
}

Texture::Texture(int width, int height, std::vector<float> texels)
    : width_(width), height_(height) {
  VIOSFM_CHECK(IsPowerOfTwo(width) && IsPowerOfTwo(height))
      << "texture size " << width << " x " << height << " is not a power of two";
  VIOSFM_CHECK_EQ(texels.size(), static_cast<size_t>(width) * height);
  levels_.push_back(Level{width, height, std::move(texels)});
  while (levels_.back().width > 1 && levels_.back().height > 1) {
    const Level& fine = levels_.back();
    Level coarse{fine.width / 2, fine.height / 2, {}};
    coarse.texels.resize(static_cast<size_t>(coarse.width) * coarse.height);
    for (int j = 0; j < coarse.height; ++j) {
      const float* row0 = &fine.texels[static_cast<size_t>(2 * j) * fine.width];
      const float* row1 = row0 + fine.width;
      for (int i = 0; i < coarse.width; ++i) {
        coarse.texels[static_cast<size_t>(j) * coarse.width + i] =
            0.25f * (row0[2 * i] + row0[2 * i + 1] + row1[2 * i] + row1[2 * i + 1]);
      }
    }
    levels_.push_back(std::move(coarse));
  }
}

float Texture::Texel(int level, int i, int j) const {
  const Level& l = levels_[level];
  return l.texels[static_cast<size_t>(j & (l.height - 1)) * l.width + (i & (l.width - 1))];
}

float Texture::SampleLevel(int level, double u, double v) const {
  const Level& l = levels_[level];
  const double scale = 1.0 / static_cast<double>(1 << level);
  const double x = u * scale - 0.5;
  const double y = v * scale - 0.5;
  const double xf = std::floor(x);
  const double yf = std::floor(y);
  const float fx = static_cast<float>(x - xf);
  const float fy = static_cast<float>(y - yf);
  // Wrap through int64 so large coordinates do not overflow.
  const int i0 = static_cast<int>(static_cast<int64_t>(xf) & (l.width - 1));
  const int j0 = static_cast<int>(static_cast<int64_t>(yf) & (l.height - 1));
  const int i1 = (i0 + 1) & (l.width - 1);
  const int j1 = (j0 + 1) & (l.height - 1);
  const float* row0 = &l.texels[static_cast<size_t>(j0) * l.width];
  const float* row1 = &l.texels[static_cast<size_t>(j1) * l.width];
  const float top = row0[i0] + fx * (row0[i1] - row0[i0]);
  const float bottom = row1[i0] + fx * (row1[i1] - row1[i0]);
  return top + fy * (bottom - top);
}

float Texture::Sample(double u, double v, double footprint) const {
  VIOSFM_CHECK(!levels_.empty()) << "sampling an empty texture";
  if (!(footprint > 1.0)) return SampleLevel(0, u, v);
  const double level = std::min(std::log2(footprint), static_cast<double>(num_levels() - 1));
  const int l0 = static_cast<int>(level);
  const float f = static_cast<float>(level - l0);
  const float a = SampleLevel(l0, u, v);
  if (l0 + 1 >= num_levels() || f <= 0.0f) return a;
  return a + f * (SampleLevel(l0 + 1, u, v) - a);
}

std::string ProceduralTextureOptions::Validate() const {
  if (!IsPowerOfTwo(width) || width < 8) return "width must be a power of two >= 8";
  if (!IsPowerOfTwo(height) || height < 8) return "height must be a power of two >= 8";
  if (!(noise_weight >= 0.0)) return "noise_weight must be >= 0";
  if (!(blobs_per_megatexel >= 0.0)) return "blobs_per_megatexel must be >= 0";
  if (!(posters_per_megatexel >= 0.0)) return "posters_per_megatexel must be >= 0";
  if (!(text_blocks_per_megatexel >= 0.0)) return "text_blocks_per_megatexel must be >= 0";
  return "";
}

Texture MakeProceduralTexture(const ProceduralTextureOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  Random random(options.seed);
  Canvas canvas(options.width, options.height, 0.5f);
  const double megatexels = static_cast<double>(options.width) * options.height / 1e6;

  // Base: value noise, amplitude growing with the wavelength (pink-ish).
  if (options.noise_weight > 0.0) {
    for (int wavelength = 4; wavelength <= 256; wavelength *= 2) {
      AddValueNoise(canvas, wavelength,
                    options.noise_weight * 0.25 * std::pow(wavelength / 256.0, 0.5), random);
    }
  }
  const auto count = [&](double per_megatexel) {
    return static_cast<int>(std::lround(per_megatexel * megatexels));
  };
  const int num_posters = count(options.posters_per_megatexel);
  for (int k = 0; k < num_posters; ++k) AddPoster(canvas, random);
  const int num_blobs = count(options.blobs_per_megatexel);
  for (int k = 0; k < num_blobs; ++k) {
    const double ra = LogUniform(random, 2.0, 40.0);
    const double rb = ra * LogUniform(random, 0.5, 2.0);
    canvas.FillEllipse(random.Uniform(0.0, options.width), random.Uniform(0.0, options.height), ra,
                       rb, random.Uniform(0.0, M_PI), static_cast<float>(random.Uniform()),
                       static_cast<float>(random.Uniform(0.4, 0.9)));
  }
  const int num_text = count(options.text_blocks_per_megatexel);
  for (int k = 0; k < num_text; ++k) AddTextBlock(canvas, random);

  // Contrast stretch: the 1st..99th percentiles to [0.05, 0.95].
  std::vector<float>& texels = canvas.texels();
  std::vector<float> sorted = texels;
  const size_t lo_index = sorted.size() / 100;
  const size_t hi_index = sorted.size() - 1 - sorted.size() / 100;
  std::nth_element(sorted.begin(), sorted.begin() + lo_index, sorted.end());
  const float lo = sorted[lo_index];
  std::nth_element(sorted.begin(), sorted.begin() + hi_index, sorted.end());
  const float hi = sorted[hi_index];
  const float scale = hi > lo ? 0.9f / (hi - lo) : 1.0f;
  for (float& texel : texels) texel = std::clamp(0.05f + (texel - lo) * scale, 0.0f, 1.0f);
  return Texture(options.width, options.height, std::move(texels));
}

Texture WithContrast(const Texture& texture, float mean, float contrast) {
  VIOSFM_CHECK_GT(texture.width(), 0);
  std::vector<float> texels(static_cast<size_t>(texture.width()) * texture.height());
  for (int j = 0; j < texture.height(); ++j) {
    for (int i = 0; i < texture.width(); ++i) {
      texels[static_cast<size_t>(j) * texture.width() + i] =
          std::clamp(mean + contrast * (texture.Texel(0, i, j) - 0.5f), 0.0f, 1.0f);
    }
  }
  return Texture(texture.width(), texture.height(), std::move(texels));
}

Texture MakeCheckerboardTexture(int width, int height, int square, float dark, float bright) {
  VIOSFM_CHECK(IsPowerOfTwo(width) && IsPowerOfTwo(height) && IsPowerOfTwo(square));
  VIOSFM_CHECK(square <= width && square <= height);
  std::vector<float> texels(static_cast<size_t>(width) * height);
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      texels[static_cast<size_t>(j) * width + i] =
          ((i / square + j / square) % 2 == 0) ? dark : bright;
    }
  }
  return Texture(width, height, std::move(texels));
}

}  // namespace viosfm
