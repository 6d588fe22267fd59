#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "viosfm/report/plot_canvas.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// Sub-pixel coordinates for OpenCV's drawing functions (fixed point).
constexpr int kShift = 4;
constexpr double kOne = 1 << kShift;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
// Hershey simplex at scale 1 has capitals about 22 px high. Its glyphs are
// wider than a sans-serif's: at 0.64 s px capitals (SVG text of size s has
// about 0.72 s) a line of text is about as long as the SVG's, which the
// layout's legend boxes are sized for.
constexpr double kFontScalePerPx = 0.64 / 22.0;

cv::Scalar Bgr(const Color& color) {
  return cv::Scalar(color.b, color.g, color.r);
}

}  // namespace

struct PngCanvas::Impl {
  cv::Mat image;  // BGR
  double scale = 1.0;

  cv::Point Device(double x, double y) const {
    return cv::Point(static_cast<int>(std::lround(x * scale * kOne)),
                     static_cast<int>(std::lround(y * scale * kOne)));
  }
  int Thickness(double width) const {
    return std::max(1, static_cast<int>(std::lround(width * scale)));
  }
  void Segment(double x1, double y1, double x2, double y2, const PlotStroke& stroke) {
    cv::line(image, Device(x1, y1), Device(x2, y2), Bgr(stroke.color), Thickness(stroke.width),
             cv::LINE_AA, kShift);
  }
  // A dashed segment, `phase` px into the 6-on 4-off pattern; returns the new phase.
  double Dashed(double x1, double y1, double x2, double y2, const PlotStroke& stroke,
                double phase) {
    const double length = std::hypot(x2 - x1, y2 - y1);
    double at = 0.0;
    while (at < length) {
      const double in_period = std::fmod(phase + at, 10.0);
      const double run = in_period < 6.0 ? 6.0 - in_period : 10.0 - in_period;
      const double to = std::min(length, at + run);
      if (in_period < 6.0) {
        const double a = at / length, b = to / length;
        Segment(x1 + a * (x2 - x1), y1 + a * (y2 - y1), x1 + b * (x2 - x1), y1 + b * (y2 - y1),
                stroke);
      }
      at = to;
    }
    return phase + length;
  }
};

PngCanvas::PngCanvas(double width, double height, double scale) : impl_(std::make_unique<Impl>()) {
  VIOSFM_CHECK(scale > 0.0 && width > 0.0 && height > 0.0);
  impl_->scale = scale;
  impl_->image =
      cv::Mat(static_cast<int>(std::ceil(height * scale)),
              static_cast<int>(std::ceil(width * scale)), CV_8UC3, cv::Scalar(255, 255, 255));
}

PngCanvas::~PngCanvas() = default;

void PngCanvas::Line(double x1, double y1, double x2, double y2, const PlotStroke& stroke) {
  if (stroke.dashed) {
    impl_->Dashed(x1, y1, x2, y2, stroke, 0.0);
  } else {
    impl_->Segment(x1, y1, x2, y2, stroke);
  }
}

void PngCanvas::Polyline(const std::vector<std::pair<double, double>>& points,
                         const PlotStroke& stroke) {
  if (points.size() < 2) return;
  if (stroke.dashed) {
    double phase = 0.0;
    for (size_t i = 1; i < points.size(); ++i) {
      phase = impl_->Dashed(points[i - 1].first, points[i - 1].second, points[i].first,
                            points[i].second, stroke, phase);
    }
    return;
  }
  std::vector<cv::Point> device;
  device.reserve(points.size());
  for (const auto& [x, y] : points) device.push_back(impl_->Device(x, y));
  cv::polylines(impl_->image, device, false, Bgr(stroke.color), impl_->Thickness(stroke.width),
                cv::LINE_AA, kShift);
}

void PngCanvas::Rect(double x, double y, double width, double height, const PlotRectStyle& style) {
  const double s = impl_->scale;
  const cv::Rect area(static_cast<int>(std::lround(x * s)), static_cast<int>(std::lround(y * s)),
                      std::max(1, static_cast<int>(std::lround(width * s))),
                      std::max(1, static_cast<int>(std::lround(height * s))));
  const cv::Rect clipped = area & cv::Rect(0, 0, impl_->image.cols, impl_->image.rows);
  if (style.fill && clipped.area() > 0) {
    cv::Mat region = impl_->image(clipped);
    if (style.fill_opacity >= 1.0) {
      region.setTo(Bgr(*style.fill));
    } else {
      const cv::Mat fill(region.size(), region.type(), Bgr(*style.fill));
      cv::addWeighted(fill, style.fill_opacity, region, 1.0 - style.fill_opacity, 0.0, region);
    }
  }
  if (style.outline) {
    const PlotStroke& stroke = *style.outline;
    Line(x, y, x + width, y, stroke);
    Line(x + width, y, x + width, y + height, stroke);
    Line(x + width, y + height, x, y + height, stroke);
    Line(x, y + height, x, y, stroke);
  }
}

void PngCanvas::Circle(double cx, double cy, double radius, const Color& fill) {
  cv::circle(impl_->image, impl_->Device(cx, cy),
             static_cast<int>(std::lround(radius * impl_->scale * kOne)), Bgr(fill), cv::FILLED,
             cv::LINE_AA, kShift);
}

void PngCanvas::Text(double x, double y, const std::string& text, const PlotTextStyle& style) {
  if (text.empty()) return;
  const double s = impl_->scale;
  const double font_scale = style.size * kFontScalePerPx * s;
  const int thickness = std::max(1, static_cast<int>(std::lround((style.bold ? 1.9 : 1.1) * s)));
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, font_scale, thickness, &baseline);
  const double shift = style.anchor == TextAnchor::kStart    ? 0.0
                       : style.anchor == TextAnchor::kMiddle ? 0.5 * size.width
                                                             : static_cast<double>(size.width);
  const cv::Scalar color = Bgr(style.color.value_or(Color{0, 0, 0}));
  if (!style.vertical) {
    cv::putText(impl_->image, text,
                cv::Point(static_cast<int>(std::lround(x * s - shift)),
                          static_cast<int>(std::lround(y * s))),
                kFont, font_scale, color, thickness, cv::LINE_AA);
    return;
  }
  // Drawn horizontally on a white patch, turned by 90 degrees counter-clockwise and
  // blended in where it is darker than the page.
  const int pad = thickness + 2;
  cv::Mat patch(size.height + baseline + 2 * pad, size.width + 2 * pad, CV_8UC3,
                cv::Scalar(255, 255, 255));
  cv::putText(patch, text, cv::Point(pad, pad + size.height), kFont, font_scale, color, thickness,
              cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(patch, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  // The baseline runs upward along x; the anchor is along it.
  const int left = static_cast<int>(std::lround(x * s)) - (pad + size.height);
  const int top = static_cast<int>(std::lround(y * s - (patch.cols - 2 * pad - shift))) - pad;
  const cv::Rect target(left, top, turned.cols, turned.rows);
  const cv::Rect clipped = target & cv::Rect(0, 0, impl_->image.cols, impl_->image.rows);
  if (clipped.area() <= 0) return;
  cv::Mat destination = impl_->image(clipped);
  const cv::Mat source = turned(clipped - target.tl());
  cv::min(destination, source, destination);
}

std::vector<uint8_t> PngCanvas::Encode() const {
  std::vector<uint8_t> bytes;
  if (!cv::imencode(".png", impl_->image, bytes)) {
    throw InputError("the plot could not be encoded as PNG");
  }
  return bytes;
}

}  // namespace viosfm
