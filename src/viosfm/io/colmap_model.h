// COLMAP 3.8 sparse model files: cameras, images, points3D as .txt or .bin.
//
// Text (one record a line, '#' comment lines at the top):
//   cameras.txt   CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]
//   images.txt    IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME   (cam_from_world)
//                 X Y POINT3D_ID ...   (second line; POINT3D_ID -1 for none)
//   points3D.txt  POINT3D_ID X Y Z R G B ERROR IMAGE_ID POINT2D_IDX ...
// Binary (little-endian; each file starts with a uint64 record count):
//   cameras.bin   uint32 id, int32 model id, uint64 width, uint64 height,
//                 double params[number of the model's parameters]
//   images.bin    uint32 id, double qw qx qy qz tx ty tz, uint32 camera id,
//                 name + '\0', uint64 n, n x (double x, double y, uint64 point3D id
//                 (2^64-1 for none))
//   points3D.bin  uint64 id, double x y z, uint8 r g b, double error,
//                 uint64 n, n x (uint32 image id, uint32 point2D idx)
//
// How COLMAP 3.8 writes them (src/base/reconstruction.cc, Write*Text and
// Write*Binary), which the writers here reproduce byte for byte:
//  - Numbers in text go through an ostream with precision(17) and the default
//    float format, i.e. printf("%.17g"): 2752.5354627566685, 1536,
//    9.2978401871913083e-05. Colours print as integers. Lines end in '\n'.
//    A line's fields are separated by single spaces, with no trailing space;
//    an image without keypoints has an empty second line.
//  - Headers: "# Camera list with one line of data per camera:",
//    "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]", "# Number of cameras: N";
//    "# Image list with two lines of data per image:",
//    "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME",
//    "#   POINTS2D[] as (X, Y, POINT3D_ID)",
//    "# Number of images: N, mean observations per image: M";
//    "# 3D point list with one line of data per point:",
//    "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)",
//    "# Number of points: N, mean track length: M". N counts registered images;
//    M is (keypoints of registered images with a 3D point) / N, %.17g, 0 if N == 0.
//  - Only registered images are written.
//  - ORDER: entries are written in the iteration order of COLMAP's
//    std::unordered_map tables, not sorted by id. After COLMAP reads a model,
//    that order is the iteration order of an unordered_map into which the ids
//    were inserted in file order, which generally differs from the file order
//    (e.g. points 127 126 125 ... come out as 159 33 160 34 ...), so COLMAP's
//    own model_converter does not reproduce its input's point order. This
//    module therefore keeps the file order (Reconstruction remembers insertion
//    order): reading and writing the same format reproduces the file byte for
//    byte. ReorderAsColmapAfterRead() applies COLMAP's reordering, so that a
//    conversion reproduces the bytes COLMAP's model_converter writes.
//  - Quaternions: COLMAP normalises qvec when reading and writing. Files
//    written at 17 digits are unit to the last bit, so the readers here keep
//    the values as read (normalising only if the norm is off by more than
//    1e-12, e.g. a hand-written file), which keeps round trips exact. A norm
//    off by more than kFileRotationTolerance (1e-3, the tolerance of every
//    reader, io/rotation_checks.h) is an error.
//
// Readers throw InputError naming the file and the line (text) or byte offset
// and record (binary) and what was expected: unknown camera model, wrong
// parameter count, non-numeric field, truncated file, a reference to a missing
// camera or image, a keypoint and a track that disagree. Writers write each
// file atomically.
#pragma once

#include <filesystem>

#include "viosfm/scene/reconstruction.h"

namespace viosfm {

enum class ColmapModelFormat { kText, kBinary };

// cameras.txt, images.txt, points3D.txt in `folder`.
Reconstruction ReadColmapModelText(const std::filesystem::path& folder);
// cameras.bin, images.bin, points3D.bin in `folder`.
Reconstruction ReadColmapModelBinary(const std::filesystem::path& folder);
// Binary if `folder`/cameras.bin exists, else text (as COLMAP decides).
Reconstruction ReadColmapModel(const std::filesystem::path& folder);

// Write the three files into `folder` (created if missing), each atomically.
void WriteColmapModelText(const std::filesystem::path& folder,
                          const Reconstruction& reconstruction);
void WriteColmapModelBinary(const std::filesystem::path& folder,
                            const Reconstruction& reconstruction);
void WriteColmapModel(const std::filesystem::path& folder, const Reconstruction& reconstruction,
                      ColmapModelFormat format);
// Writes a complete model folder atomically: the files go to a temporary
// sibling folder that then replaces `folder` (an existing one is replaced only
// once all files are written).
void WriteColmapModelFolder(const std::filesystem::path& folder,
                            const Reconstruction& reconstruction, ColmapModelFormat format);

// Reorders cameras, images and points as COLMAP 3.8 holds them after reading
// a model whose entries are in the current order: the iteration order of a
// std::unordered_map (libstdc++, the library COLMAP is built with on this
// platform) into which the ids were inserted in that order. Writing afterwards
// gives the bytes of COLMAP's model_converter.
void ReorderAsColmapAfterRead(Reconstruction* reconstruction);

}  // namespace viosfm
