// Feature tracks from the verified matches of many image pairs.
//
// Every keypoint (image_id, point2D_idx) is a node and every match an edge;
// the connected components are the tracks. A component that holds two
// different keypoints of the same image is inconsistent (a 3D point projects
// to one place in an image): at least one of its matches is wrong.
//
// Conflict policy kSplit (the default) rebuilds such a component from its
// matches, best supported first, with a union-find that refuses any union
// which would put two keypoints of one image into the same set. A match is
// supported by the triangles it closes (keypoints matched to both of its
// ends): a correct match inside a track seen in n images closes up to n - 2
// of them, while a wrong match that bridges two tracks closes none, so the
// wrong match comes last and is the one refused. The result is the two
// tracks as they would have been without it, instead of losing both (kDrop)
// or keeping one long track with a wrong observation. Refused matches are
// counted; the keypoints stay in their own consistent pieces.
// kDrop discards inconsistent components entirely (the conservative choice
// when matches are known to be unreliable).
//
// The output depends only on the set of matches: the order of the pairs, the
// order of matches within a pair, the orientation of a pair ((1, 2) or
// (2, 1)) and duplicates do not change it. Track elements are sorted by
// (image_id, point2D_idx), tracks by their first elements.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "viosfm/scene/features.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/types.h"

namespace viosfm {

// Observations of one scene point, at most one a image, sorted by
// (image_id, point2D_idx).
struct Track {
  std::vector<TrackElement> elements;

  size_t Length() const { return elements.size(); }
};

enum class TrackConflictPolicy {
  kSplit,  // rebuild with best-supported matches first, refusing conflicts
  kDrop,   // discard the whole inconsistent component
};
// "split", "drop": the option texts (util/option_fields.h).
inline std::string OptionText(TrackConflictPolicy policy) {
  return policy == TrackConflictPolicy::kSplit ? "split" : "drop";
}
inline void ParseOptionText(const std::string& text, TrackConflictPolicy* policy) {
  if (text == "split") {
    *policy = TrackConflictPolicy::kSplit;
  } else if (text == "drop") {
    *policy = TrackConflictPolicy::kDrop;
  } else {
    throw InputError("expected split or drop");
  }
}

struct TrackBuilderOptions {
  // Tracks with fewer observations are discarded, >= 2. Default 2.
  int min_track_length = 2;
  // What to do with a component holding two keypoints of one image.
  // Default kSplit (see the top of this file).
  TrackConflictPolicy conflict_policy = TrackConflictPolicy::kSplit;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"min_track_length", "tracks with fewer observations are discarded", kRunOnly},
          self.min_track_length);
    visit({"conflict_policy", "split or drop a track holding two keypoints of one image", kRunOnly},
          self.conflict_policy);
  }
};

struct TrackStatistics {
  size_t num_pairs = 0;
  // Matches read (with duplicates), and distinct matches (edges) used.
  size_t num_input_matches = 0;
  size_t num_unique_matches = 0;
  // Matches between an image and itself, ignored.
  size_t num_self_matches = 0;
  // Connected components of the match graph, and those among them that were
  // inconsistent.
  size_t num_components = 0;
  size_t num_inconsistent_components = 0;
  // kSplit: matches refused because they joined two keypoints of one image,
  // and the consistent pieces (of any length) the inconsistent components
  // were split into.
  size_t num_refused_matches = 0;
  size_t num_split_pieces = 0;
  // kDrop: components discarded as inconsistent.
  size_t num_dropped_inconsistent = 0;
  // Consistent tracks (or pieces) discarded as shorter than min_track_length.
  size_t num_dropped_short = 0;
  // Tracks output, and their total number of observations.
  size_t num_tracks = 0;
  size_t num_observations = 0;
  // length_histogram[n] = number of output tracks with n observations.
  std::vector<size_t> length_histogram;

  // One line: "tracks 1234 (obs 5678, mean length 4.6), ...".
  std::string Summary() const;
};

struct TrackBuildResult {
  std::vector<Track> tracks;
  TrackStatistics statistics;
};

// Builds the tracks of the matches (see the top of this file). CHECKs options.
TrackBuildResult BuildTracks(const std::vector<ImagePairMatches>& pair_matches,
                             const TrackBuilderOptions& options = {});

// The tracks of matches that arrive a few pairs at a time (the mapper beside
// the verification, verified_pair_stream.h): after each AddPairs, Result()
// is BuildTracks of every pair added so far, track for track and figure for
// figure. Only the connected components the new matches touch are built
// again (the result of a component depends on its matches alone), so
// adding the pairs of a batch costs what their components hold, not what
// every pair does.
class IncrementalTrackBuilder {
 public:
  // The images the pairs may name, with their keypoint counts (a match
  // indexing a keypoint beyond its image's count, or an unknown image:
  // InputError). CHECKs options.
  IncrementalTrackBuilder(const std::vector<std::pair<image_t, size_t>>& num_keypoints_of_image,
                          const TrackBuilderOptions& options = {});

  // One more image the pairs may name (CHECK: not listed before).
  void AddImage(image_t image_id, size_t num_keypoints);
  void AddPairs(const std::vector<ImagePairMatches>& pair_matches);
  TrackBuildResult Result() const;

 private:
  struct Component {
    std::vector<uint32_t> nodes;
    std::vector<std::pair<uint32_t, uint32_t>> edges;  // node ids, unique after a build
    // The component's tracks (or pieces) as built, any length, each sorted
    // by key.
    std::vector<std::vector<uint64_t>> pieces;
    bool inconsistent = false;
    size_t num_refused_matches = 0;
  };
  uint32_t NodeOf(image_t image_id, point2D_t point2D_idx);
  uint32_t Find(uint32_t node);
  void Build(Component* component) const;

  TrackBuilderOptions options_;
  std::unordered_map<image_t, size_t> image_index_;
  // Per image, the node id of each keypoint (kNoNode until matched).
  std::vector<std::vector<uint32_t>> node_of_keypoint_;
  std::vector<uint64_t> keys_;                          // per node: image id << 32 | point2D_idx
  std::vector<uint32_t> parent_;                        // union-find over nodes
  std::unordered_map<uint32_t, Component> components_;  // by root
  size_t num_pairs_ = 0;
  size_t num_input_matches_ = 0;
  size_t num_self_matches_ = 0;
};

}  // namespace viosfm
