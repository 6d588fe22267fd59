// SIFT keypoints with RootSIFT descriptors (OpenCV 4.6's cv::SIFT), stored
// the way COLMAP stores its own:
//  - keypoints in raw (distorted) pixel coordinates in viosfm's convention
//    (the centre of the top-left pixel is (0, 0), as OpenCV's; io/ adds 0.5
//    for COLMAP's files), after removing cv::SIFT 4.6's bias of +0.25 pixel
//    (its upsampled first octave is misaligned by a quarter pixel; see
//    sift.cc);
//  - the affine shape of FeatureKeypoint::FromScaleOrientation(x, y, scale,
//    orientation) with scale = the Gaussian scale sigma in pixels (OpenCV's
//    KeyPoint::size is a diameter, 2 sigma) and orientation in radians,
//    measured from the +x axis towards +y in image coordinates (y down), i.e.
//    OpenCV's KeyPoint::angle (degrees, same direction) times pi / 180;
//  - descriptors normalised (RootSIFT: L1-normalise, then element-wise
//    square root, which gives a unit L2 norm; or plain L2 normalisation) and
//    quantised as COLMAP's FeatureDescriptorsToUnsignedByte does:
//    min(255, round(512 * value)).
// The descriptor layout is OpenCV's (4 x 4 spatial cells, row-major, each
// with 8 orientation bins). COLMAP's VLFeat extractor reorders its
// descriptors to Lowe's layout, which may number the orientation bins in
// the other direction: viosfm descriptors match viosfm descriptors; do not
// mix them with descriptors COLMAP extracted.
//
// Geometry works on undistorted normalised coordinates: UndistortKeypoints.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/scene/features.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/grey_image.h"
#include "viosfm/util/option_fields.h"

namespace viosfm {

struct SiftOptions {
  // Keypoints kept per image, the strongest by DoG response. Default 8192
  // (COLMAP's SiftExtraction.max_num_features).
  int max_num_features = 8192;
  // RootSIFT (true) or L2-normalised SIFT (false) descriptors. Default true
  // (COLMAP's default normalisation is L1_ROOT as well).
  bool root_sift = true;
  // Minimum absolute DoG value of a keypoint, intensities in [0, 1]. Default
  // 0.02 / 3 (COLMAP's peak_threshold 0.02 / octave_resolution, VLFeat's
  // semantics). OpenCV's contrastThreshold is this times num_octave_layers
  // (OpenCV divides it by the layers), i.e. 0.02 here instead of OpenCV's
  // default 0.04, which keeps about twice as many weak keypoints in
  // low-texture indoor images.
  double peak_threshold = 0.02 / 3.0;
  // Maximum ratio of principal curvatures of a keypoint (rejects edges).
  // Default 10 (COLMAP and OpenCV).
  double edge_threshold = 10.0;
  // DoG levels per octave. Default 3 (COLMAP's octave_resolution, OpenCV's
  // nOctaveLayers).
  int num_octave_layers = 3;
  // The scale space's first octave: -1 starts from the image doubled in
  // size (Lowe's, VLFeat's, COLMAP's and cv::SIFT's choice, which finds
  // keypoints of sigma 0.8 to 1.6 pixels), 0 from the image itself (no
  // keypoint below sigma 1.6; about a quarter of the pyramid's pixels).
  // cv::SIFT's detector always doubles, so 0 detects with viosfm's own
  // (features/dog_detector.h) and lets cv::SIFT describe. Default -1.
  int first_octave = -1;
  // Pixels, the longest side the extraction works on: a larger image is
  // first reduced to it (area averaging, as COLMAP's max_image_size), and
  // its keypoints are given in the image's own pixels. 0 (default): every
  // image as it is.
  int max_image_size = 0;
  // Worker threads of the batch extraction (feature_extraction.h), each
  // extracting one image at a time. Default 2.
  int num_threads = 2;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"max_num_features", "SIFT keypoints kept per image, the strongest", kShapesStoredData},
          self.max_num_features);
    visit({"root_sift", "RootSIFT (true) or L2-normalised SIFT descriptors", kShapesStoredData},
          self.root_sift);
    visit({"peak_threshold", "minimum absolute DoG value of a keypoint", kShapesStoredData},
          self.peak_threshold);
    visit({"edge_threshold", "maximum ratio of principal curvatures", kShapesStoredData},
          self.edge_threshold);
    visit({"num_octave_layers", "DoG levels per octave", kShapesStoredData},
          self.num_octave_layers);
    visit({"first_octave", "first octave of the scale space: -1 (image doubled) or 0",
           kShapesStoredData},
          self.first_octave);
    visit({"max_image_size", "pixels, longest side extracted on (larger images reduced); 0: any",
           kShapesStoredData},
          self.max_image_size);
    visit({"num_threads", "worker threads of the extraction", kRunOnly}, self.num_threads);
  }
};

struct ImageFeatures {
  FeatureKeypoints keypoints;
  FeatureDescriptors descriptors;  // one row of 128 bytes per keypoint
};

// Detects and describes SIFT keypoints, ordered by decreasing response.
// Throws InputError if the options are invalid, InternalError if the image's
// pixel count does not match its size.
ImageFeatures ExtractSift(const GreyImage& image, const SiftOptions& options);

// Descriptor normalisations on float descriptors (one a row); rows that are
// all zero stay zero.
using FeatureDescriptorsFloat =
    Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
FeatureDescriptorsFloat L2NormalizeDescriptors(const FeatureDescriptorsFloat& descriptors);
FeatureDescriptorsFloat RootSiftNormalizeDescriptors(const FeatureDescriptorsFloat& descriptors);
// min(255, max(0, round(512 * value))), COLMAP's quantisation of unit-norm
// descriptors.
FeatureDescriptors QuantizeDescriptors(const FeatureDescriptorsFloat& descriptors);

// Keypoint positions -> undistorted normalised camera coordinates (x/z, y/z)
// through sensor/camera_models.h's ImageToCam. Throws InputError if the
// camera model cannot project.
std::vector<Eigen::Vector2d> UndistortKeypoints(const Camera& camera,
                                                const FeatureKeypoints& keypoints);

}  // namespace viosfm
