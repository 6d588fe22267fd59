#include "viosfm/sfm/tracks.h"

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <numeric>
#include <sstream>
#include <utility>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// A keypoint as one sortable number: image id in the high, index in the low bits.
using NodeKey = uint64_t;

NodeKey MakeKey(image_t image_id, point2D_t point2D_idx) {
  return (static_cast<uint64_t>(image_id) << 32) | static_cast<uint64_t>(point2D_idx);
}
image_t KeyImage(NodeKey key) {
  return static_cast<image_t>(key >> 32);
}
TrackElement KeyElement(NodeKey key) {
  return TrackElement{KeyImage(key), static_cast<point2D_t>(key & 0xffffffffu)};
}

class UnionFind {
 public:
  explicit UnionFind(size_t size) : parent_(size) {
    std::iota(parent_.begin(), parent_.end(), size_t{0});
  }
  size_t Find(size_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  // Links the root `child` below the root `root`.
  void Link(size_t child, size_t root) { parent_[child] = root; }

 private:
  std::vector<size_t> parent_;
};

// Whether two sorted vectors share an element.
bool Intersects(const std::vector<image_t>& a, const std::vector<image_t>& b) {
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (*ia == *ib) return true;
    if (*ia < *ib) {
      ++ia;
    } else {
      ++ib;
    }
  }
  return false;
}

size_t CountCommon(const std::vector<size_t>& a, const std::vector<size_t>& b) {
  size_t count = 0;
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (*ia == *ib) {
      ++count;
      ++ia;
      ++ib;
    } else if (*ia < *ib) {
      ++ia;
    } else {
      ++ib;
    }
  }
  return count;
}

// Splits an inconsistent component (keys: its nodes' keys, sorted; edges:
// pairs of indices u < v into keys, sorted, unique) into consistent pieces,
// accepting the best-supported matches first. Returns the pieces as lists of
// indices into keys (each sorted) and adds the refused matches to *refused.
std::vector<std::vector<size_t>> SplitComponent(
    const std::vector<NodeKey>& keys, const std::vector<std::pair<size_t, size_t>>& local_edges,
    size_t* refused) {
  const size_t num_nodes = keys.size();
  std::vector<std::vector<size_t>> adjacency(num_nodes);
  for (const auto& [u, v] : local_edges) {
    adjacency[u].push_back(v);
    adjacency[v].push_back(u);
  }
  for (std::vector<size_t>& neighbours : adjacency) std::sort(neighbours.begin(), neighbours.end());

  struct RankedEdge {
    size_t support;     // triangles closed by the match
    size_t degree_sum;  // matches at its two ends
    size_t u;
    size_t v;
  };
  std::vector<RankedEdge> ranked;
  ranked.reserve(local_edges.size());
  for (const auto& [u, v] : local_edges) {
    ranked.push_back(
        {CountCommon(adjacency[u], adjacency[v]), adjacency[u].size() + adjacency[v].size(), u, v});
  }
  std::sort(ranked.begin(), ranked.end(), [](const RankedEdge& a, const RankedEdge& b) {
    if (a.support != b.support) return a.support > b.support;
    if (a.degree_sum != b.degree_sum) return a.degree_sum > b.degree_sum;
    if (a.u != b.u) return a.u < b.u;
    return a.v < b.v;
  });

  UnionFind sets(num_nodes);
  // Sorted image ids of each set, valid at its root.
  std::vector<std::vector<image_t>> images(num_nodes);
  for (size_t i = 0; i < num_nodes; ++i) images[i] = {KeyImage(keys[i])};
  for (const RankedEdge& edge : ranked) {
    size_t root_u = sets.Find(edge.u);
    size_t root_v = sets.Find(edge.v);
    if (root_u == root_v) continue;
    if (Intersects(images[root_u], images[root_v])) {
      ++*refused;
      continue;
    }
    if (images[root_u].size() < images[root_v].size()) std::swap(root_u, root_v);
    std::vector<image_t> merged;
    merged.reserve(images[root_u].size() + images[root_v].size());
    std::merge(images[root_u].begin(), images[root_u].end(), images[root_v].begin(),
               images[root_v].end(), std::back_inserter(merged));
    images[root_u] = std::move(merged);
    images[root_v].clear();
    sets.Link(root_v, root_u);
  }

  std::vector<std::vector<size_t>> pieces;
  std::vector<size_t> piece_of_root(num_nodes, SIZE_MAX);
  for (size_t i = 0; i < num_nodes; ++i) {
    const size_t root = sets.Find(i);
    if (piece_of_root[root] == SIZE_MAX) {
      piece_of_root[root] = pieces.size();
      pieces.emplace_back();
    }
    pieces[piece_of_root[root]].push_back(i);
  }
  return pieces;
}

// Orders the tracks by their first elements (nodes are sorted within each
// track, and tracks are disjoint) and counts them, their observations and
// their lengths.
void SortTracksAndCount(TrackBuildResult* result) {
  std::sort(result->tracks.begin(), result->tracks.end(), [](const Track& a, const Track& b) {
    const TrackElement& ea = a.elements.front();
    const TrackElement& eb = b.elements.front();
    return MakeKey(ea.image_id, ea.point2D_idx) < MakeKey(eb.image_id, eb.point2D_idx);
  });
  TrackStatistics& stats = result->statistics;
  stats.num_tracks = result->tracks.size();
  for (const Track& track : result->tracks) {
    stats.num_observations += track.Length();
    if (stats.length_histogram.size() <= track.Length()) {
      stats.length_histogram.resize(track.Length() + 1, 0);
    }
    ++stats.length_histogram[track.Length()];
  }
}

// The matches as a graph: the matched keypoints' keys (sorted, unique) and
// the matches as pairs of indices u < v into them (sorted, unique).
struct MatchGraph {
  std::vector<NodeKey> keys;
  std::vector<std::pair<size_t, size_t>> edges;
};

// The graph of `pair_matches`, counting the input, self and distinct
// matches into `stats`.
MatchGraph CollectMatchGraph(const std::vector<ImagePairMatches>& pair_matches,
                             TrackStatistics* stats) {
  // Matches as edges between node keys, smaller key first, sorted, unique.
  std::vector<std::pair<NodeKey, NodeKey>> key_edges;
  for (const ImagePairMatches& pair : pair_matches) {
    stats->num_input_matches += pair.matches.size();
    if (pair.image_id1 == pair.image_id2) {
      stats->num_self_matches += pair.matches.size();
      continue;
    }
    for (const FeatureMatch& match : pair.matches) {
      const NodeKey a = MakeKey(pair.image_id1, match.point2D_idx1);
      const NodeKey b = MakeKey(pair.image_id2, match.point2D_idx2);
      key_edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(key_edges.begin(), key_edges.end());
  key_edges.erase(std::unique(key_edges.begin(), key_edges.end()), key_edges.end());
  stats->num_unique_matches = key_edges.size();

  MatchGraph graph;
  std::vector<NodeKey>& keys = graph.keys;
  keys.reserve(2 * key_edges.size());
  for (const auto& [a, b] : key_edges) {
    keys.push_back(a);
    keys.push_back(b);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const auto index_of = [&keys](NodeKey key) {
    return static_cast<size_t>(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin());
  };
  graph.edges.reserve(key_edges.size());
  for (const auto& [a, b] : key_edges) graph.edges.emplace_back(index_of(a), index_of(b));
  return graph;
}

// The graph's connected components, in the order of their smallest node,
// nodes sorted within; each marked inconsistent when it holds two
// keypoints of one image.
struct Components {
  std::vector<size_t> of_node;
  std::vector<std::vector<size_t>> nodes;
  std::vector<bool> inconsistent;
};

Components FindComponents(const MatchGraph& graph) {
  const size_t num_nodes = graph.keys.size();
  UnionFind sets(num_nodes);
  for (const auto& [u, v] : graph.edges) {
    const size_t root_u = sets.Find(u);
    const size_t root_v = sets.Find(v);
    if (root_u == root_v) continue;
    // The smaller index becomes the root, so roots do not depend on edge order.
    if (root_u < root_v) {
      sets.Link(root_v, root_u);
    } else {
      sets.Link(root_u, root_v);
    }
  }
  Components components;
  components.of_node.resize(num_nodes);
  std::vector<size_t> component_of_root(num_nodes, SIZE_MAX);
  for (size_t i = 0; i < num_nodes; ++i) {
    const size_t root = sets.Find(i);
    if (component_of_root[root] == SIZE_MAX) {
      component_of_root[root] = components.nodes.size();
      components.nodes.emplace_back();
    }
    components.of_node[i] = component_of_root[root];
    components.nodes[component_of_root[root]].push_back(i);
  }
  components.inconsistent.assign(components.nodes.size(), false);
  for (size_t c = 0; c < components.nodes.size(); ++c) {
    const std::vector<size_t>& nodes = components.nodes[c];
    for (size_t k = 1; k < nodes.size(); ++k) {
      if (KeyImage(graph.keys[nodes[k]]) == KeyImage(graph.keys[nodes[k - 1]])) {
        components.inconsistent[c] = true;
        break;
      }
    }
  }
  return components;
}

// The track of `nodes` (sorted indices into keys), or a count of a short one.
void EmitTrack(const std::vector<NodeKey>& keys, const std::vector<size_t>& nodes,
               const TrackBuilderOptions& options, TrackBuildResult* result) {
  if (nodes.size() < static_cast<size_t>(options.min_track_length)) {
    ++result->statistics.num_dropped_short;
    return;
  }
  Track track;
  track.elements.reserve(nodes.size());
  for (size_t node : nodes) track.elements.push_back(KeyElement(keys[node]));
  result->tracks.push_back(std::move(track));
}

// Splits the inconsistent component of `nodes` (sorted global indices, so
// sorted by key too) along its `edges` (global indices) and emits the pieces.
void SplitAndEmit(const std::vector<NodeKey>& keys, const std::vector<size_t>& nodes,
                  const std::vector<std::pair<size_t, size_t>>& edges,
                  const TrackBuilderOptions& options, TrackBuildResult* result) {
  TrackStatistics& stats = result->statistics;
  std::vector<NodeKey> component_keys;
  component_keys.reserve(nodes.size());
  for (const size_t node : nodes) component_keys.push_back(keys[node]);
  const auto local = [&nodes](size_t global) {
    return static_cast<size_t>(std::lower_bound(nodes.begin(), nodes.end(), global) -
                               nodes.begin());
  };
  std::vector<std::pair<size_t, size_t>> local_edges;
  local_edges.reserve(edges.size());
  for (const auto& [u, v] : edges) local_edges.emplace_back(local(u), local(v));
  const std::vector<std::vector<size_t>> pieces =
      SplitComponent(component_keys, local_edges, &stats.num_refused_matches);
  stats.num_split_pieces += pieces.size();
  for (const std::vector<size_t>& piece : pieces) {
    std::vector<size_t> global;
    global.reserve(piece.size());
    for (const size_t i : piece) global.push_back(nodes[i]);
    EmitTrack(keys, global, options, result);
  }
}

}  // namespace

std::string TrackBuilderOptions::Validate() const {
  if (min_track_length < 2) return "min_track_length must be >= 2";
  if (conflict_policy != TrackConflictPolicy::kSplit &&
      conflict_policy != TrackConflictPolicy::kDrop) {
    return "conflict_policy must be kSplit or kDrop";
  }
  return "";
}

std::string TrackStatistics::Summary() const {
  std::ostringstream out;
  const double mean_length =
      num_tracks > 0 ? static_cast<double>(num_observations) / static_cast<double>(num_tracks)
                     : 0.0;
  out << "tracks " << num_tracks << " (observations " << num_observations << ", mean length "
      << mean_length << "), matches " << num_unique_matches << " distinct of " << num_input_matches
      << ", inconsistent components " << num_inconsistent_components << " (refused matches "
      << num_refused_matches << ", split pieces " << num_split_pieces << ", dropped "
      << num_dropped_inconsistent << "), short dropped " << num_dropped_short;
  return out.str();
}

TrackBuildResult BuildTracks(const std::vector<ImagePairMatches>& pair_matches,
                             const TrackBuilderOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  TrackBuildResult result;
  TrackStatistics& stats = result.statistics;
  stats.num_pairs = pair_matches.size();
  const MatchGraph graph = CollectMatchGraph(pair_matches, &stats);
  const Components components = FindComponents(graph);
  stats.num_components = components.nodes.size();
  for (const bool inconsistent : components.inconsistent) {
    if (inconsistent) ++stats.num_inconsistent_components;
  }
  // Edges of the inconsistent components (only needed for kSplit).
  std::vector<std::vector<std::pair<size_t, size_t>>> component_edges(components.nodes.size());
  if (options.conflict_policy == TrackConflictPolicy::kSplit) {
    for (const auto& edge : graph.edges) {
      const size_t c = components.of_node[edge.first];
      if (components.inconsistent[c]) component_edges[c].push_back(edge);
    }
  }
  for (size_t c = 0; c < components.nodes.size(); ++c) {
    if (!components.inconsistent[c]) {
      EmitTrack(graph.keys, components.nodes[c], options, &result);
    } else if (options.conflict_policy == TrackConflictPolicy::kDrop) {
      ++stats.num_dropped_inconsistent;
    } else {
      SplitAndEmit(graph.keys, components.nodes[c], component_edges[c], options, &result);
    }
  }
  SortTracksAndCount(&result);
  return result;
}

}  // namespace viosfm

namespace viosfm {
namespace {

constexpr uint32_t kNoNode = UINT32_MAX;

}  // namespace

IncrementalTrackBuilder::IncrementalTrackBuilder(
    const std::vector<std::pair<image_t, size_t>>& num_keypoints_of_image,
    const TrackBuilderOptions& options)
    : options_(options) {
  VIOSFM_CHECK(options_.Check()) << options_.Validate();
  for (const auto& [image_id, num_keypoints] : num_keypoints_of_image) {
    AddImage(image_id, num_keypoints);
  }
}

void IncrementalTrackBuilder::AddImage(image_t image_id, size_t num_keypoints) {
  VIOSFM_CHECK(image_index_.emplace(image_id, node_of_keypoint_.size()).second)
      << "image " << image_id << " listed twice";
  node_of_keypoint_.emplace_back(num_keypoints, kNoNode);
}

uint32_t IncrementalTrackBuilder::NodeOf(image_t image_id, point2D_t point2D_idx) {
  uint32_t& node = node_of_keypoint_[image_index_.at(image_id)][point2D_idx];
  if (node == kNoNode) {
    VIOSFM_CHECK_LT(keys_.size(), size_t{kNoNode}) << "too many matched keypoints";
    node = static_cast<uint32_t>(keys_.size());
    keys_.push_back(MakeKey(image_id, point2D_idx));
    parent_.push_back(node);
    components_[node].nodes = {node};
  }
  return node;
}

uint32_t IncrementalTrackBuilder::Find(uint32_t node) {
  while (parent_[node] != node) {
    parent_[node] = parent_[parent_[node]];
    node = parent_[node];
  }
  return node;
}

void IncrementalTrackBuilder::AddPairs(const std::vector<ImagePairMatches>& pair_matches) {
  std::vector<uint32_t> touched;
  for (const ImagePairMatches& pair : pair_matches) {
    ++num_pairs_;
    num_input_matches_ += pair.matches.size();
    if (pair.image_id1 == pair.image_id2) {
      num_self_matches_ += pair.matches.size();
      continue;
    }
    const auto it1 = image_index_.find(pair.image_id1);
    const auto it2 = image_index_.find(pair.image_id2);
    if (it1 == image_index_.end() || it2 == image_index_.end()) {
      throw InputError("tracks: pair (images " + std::to_string(pair.image_id1) + ", " +
                       std::to_string(pair.image_id2) + ") names an unknown image");
    }
    const size_t size1 = node_of_keypoint_[it1->second].size();
    const size_t size2 = node_of_keypoint_[it2->second].size();
    for (const FeatureMatch& match : pair.matches) {
      if (match.point2D_idx1 >= size1 || match.point2D_idx2 >= size2) {
        throw InputError("tracks: pair (images " + std::to_string(pair.image_id1) + ", " +
                         std::to_string(pair.image_id2) +
                         ") matches a keypoint beyond its image's");
      }
      const uint32_t u = NodeOf(pair.image_id1, match.point2D_idx1);
      const uint32_t v = NodeOf(pair.image_id2, match.point2D_idx2);
      uint32_t root_u = Find(u);
      uint32_t root_v = Find(v);
      if (root_u != root_v) {
        // The smaller component goes into the larger.
        if (components_.at(root_u).nodes.size() < components_.at(root_v).nodes.size()) {
          std::swap(root_u, root_v);
        }
        Component& into = components_.at(root_u);
        Component& from = components_.at(root_v);
        into.nodes.insert(into.nodes.end(), from.nodes.begin(), from.nodes.end());
        into.edges.insert(into.edges.end(), from.edges.begin(), from.edges.end());
        components_.erase(root_v);
        parent_[root_v] = root_u;
      }
      components_.at(root_u).edges.emplace_back(u, v);
      touched.push_back(root_u);
    }
  }
  for (uint32_t& root : touched) root = Find(root);
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  for (const uint32_t root : touched) Build(&components_.at(root));
}

void IncrementalTrackBuilder::Build(Component* component) const {
  // Nodes by key, and each node's place in that order.
  std::vector<std::pair<uint64_t, uint32_t>> by_key;
  by_key.reserve(component->nodes.size());
  for (const uint32_t node : component->nodes) by_key.emplace_back(keys_[node], node);
  std::sort(by_key.begin(), by_key.end());
  std::vector<NodeKey> keys;
  keys.reserve(by_key.size());
  for (const auto& entry : by_key) keys.push_back(entry.first);
  // The edges as pairs of key indices, smaller first, unique (a match given
  // twice counts once).
  std::vector<std::pair<uint32_t, size_t>> local_of_node;
  local_of_node.reserve(by_key.size());
  for (size_t i = 0; i < by_key.size(); ++i) local_of_node.emplace_back(by_key[i].second, i);
  std::sort(local_of_node.begin(), local_of_node.end());
  const auto local = [&](uint32_t node) {
    return std::lower_bound(local_of_node.begin(), local_of_node.end(),
                            std::make_pair(node, size_t{0}))
        ->second;
  };
  std::vector<std::pair<size_t, size_t>> local_edges;
  local_edges.reserve(component->edges.size());
  for (const auto& [u, v] : component->edges) {
    const size_t lu = local(u);
    const size_t lv = local(v);
    local_edges.emplace_back(std::min(lu, lv), std::max(lu, lv));
  }
  std::sort(local_edges.begin(), local_edges.end());
  local_edges.erase(std::unique(local_edges.begin(), local_edges.end()), local_edges.end());
  component->edges.clear();
  for (const auto& [lu, lv] : local_edges) {
    component->edges.emplace_back(by_key[lu].second, by_key[lv].second);
  }
  component->edges.shrink_to_fit();

  component->inconsistent = false;
  for (size_t k = 1; k < keys.size(); ++k) {
    if (KeyImage(keys[k]) == KeyImage(keys[k - 1])) {
      component->inconsistent = true;
      break;
    }
  }
  component->pieces.clear();
  component->num_refused_matches = 0;
  if (!component->inconsistent) {
    component->pieces.push_back(std::move(keys));
  } else if (options_.conflict_policy == TrackConflictPolicy::kSplit) {
    for (const std::vector<size_t>& piece :
         SplitComponent(keys, local_edges, &component->num_refused_matches)) {
      std::vector<uint64_t> piece_keys;
      piece_keys.reserve(piece.size());
      for (const size_t i : piece) piece_keys.push_back(keys[i]);
      component->pieces.push_back(std::move(piece_keys));
    }
  }
}

TrackBuildResult IncrementalTrackBuilder::Result() const {
  TrackBuildResult result;
  TrackStatistics& stats = result.statistics;
  stats.num_pairs = num_pairs_;
  stats.num_input_matches = num_input_matches_;
  stats.num_self_matches = num_self_matches_;
  for (const auto& [root, component] : components_) {
    ++stats.num_components;
    stats.num_unique_matches += component.edges.size();
    if (component.inconsistent) {
      ++stats.num_inconsistent_components;
      if (options_.conflict_policy == TrackConflictPolicy::kDrop) {
        ++stats.num_dropped_inconsistent;
        continue;
      }
      stats.num_refused_matches += component.num_refused_matches;
      stats.num_split_pieces += component.pieces.size();
    }
    for (const std::vector<uint64_t>& piece : component.pieces) {
      if (piece.size() < static_cast<size_t>(options_.min_track_length)) {
        ++stats.num_dropped_short;
        continue;
      }
      Track track;
      track.elements.reserve(piece.size());
      for (const uint64_t key : piece) track.elements.push_back(KeyElement(key));
      result.tracks.push_back(std::move(track));
    }
  }
  SortTracksAndCount(&result);
  return result;
}

}  // namespace viosfm
