// The scene structure ground truth file (scene.csv) of `viosfm simulate`:
// a header line starting with '#', then one row per textured quad:
//
//   id,region,floor,texture_id,origin_x,origin_y,origin_z,axis_u_x,axis_u_y,
//   axis_u_z,axis_v_x,axis_v_y,axis_v_z
//
// metres, world frame, numbers with 17 significant digits so that
// write -> read reproduces every value. Region names must not contain commas.
#pragma once

#include <filesystem>

#include "viosfm/scene/scene_structure.h"

namespace viosfm {

// Writes atomically.
void WriteSceneStructure(const std::filesystem::path& path, const SceneStructure& structure);
// Throws InputError naming the file and line for a missing file, a row with
// the wrong number of fields or a field that is not a number.
SceneStructure ReadSceneStructure(const std::filesystem::path& path);

}  // namespace viosfm
