// The plain data of a visual vocabulary tree (Nister & Stewenius 2006): the
// cluster centres of every node of a hierarchical k-means tree. It is what a
// vocabulary file holds (io/vocabulary_io.h reads and writes it) and what
// retrieval/vocabulary_tree.h builds its quantiser from.
//
// Layout: node 0 is the root (its centre is unused and stored as zeros). The
// children of node n are the nodes first_child[n] .. first_child[n] +
// num_children[n] - 1 (contiguous, always after n). A node without children
// is a leaf and has a visual word id word_of_node[n] in [0, num_words); the
// inner nodes have word_of_node[n] == -1.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace viosfm {

struct VocabularyData {
  int32_t branching = 0;              // maximum number of children of a node
  int32_t depth = 0;                  // maximum number of levels below the root
  int32_t descriptor_dim = 0;         // floats per centre (128 for SIFT)
  int32_t num_words = 0;              // number of leaves
  std::vector<float> centers;         // num_nodes() x descriptor_dim, row-major
  std::vector<int32_t> first_child;   // per node; -1 for a leaf
  std::vector<int32_t> num_children;  // per node; 0 for a leaf
  std::vector<int32_t> word_of_node;  // per node; -1 for an inner node

  int64_t num_nodes() const { return static_cast<int64_t>(first_child.size()); }

  // Empty if the arrays describe a consistent tree, else what is wrong.
  std::string Validate() const {
    if (branching < 2) return "branching must be >= 2, got " + std::to_string(branching);
    if (depth < 1) return "depth must be >= 1, got " + std::to_string(depth);
    if (descriptor_dim < 1) return "descriptor_dim must be >= 1";
    const int64_t n = num_nodes();
    if (n < 1) return "the tree has no root node";
    if (static_cast<int64_t>(num_children.size()) != n ||
        static_cast<int64_t>(word_of_node.size()) != n) {
      return "first_child, num_children and word_of_node differ in length";
    }
    if (static_cast<int64_t>(centers.size()) != n * descriptor_dim) {
      return "centers has " + std::to_string(centers.size()) + " floats, expected num_nodes * " +
             "descriptor_dim = " + std::to_string(n * descriptor_dim);
    }
    if (num_words < 1 || num_words > n) {
      return "num_words " + std::to_string(num_words) +
             " outside [1, num_nodes = " + std::to_string(n) + "]";
    }
    std::vector<int32_t> parent_count(n, 0);
    std::vector<char> word_seen(num_words, 0);
    int64_t leaves = 0;
    for (int64_t node = 0; node < n; ++node) {
      const std::string where = "node " + std::to_string(node) + ": ";
      const int32_t first = first_child[node];
      const int32_t count = num_children[node];
      if (count == 0) {
        if (first != -1) return where + "a leaf must have first_child -1";
        const int32_t word = word_of_node[node];
        if (word < 0 || word >= num_words) {
          return where + "leaf word id " + std::to_string(word) + " outside [0, " +
                 std::to_string(num_words) + ")";
        }
        if (word_seen[word]) return where + "word id " + std::to_string(word) + " used twice";
        word_seen[word] = 1;
        ++leaves;
        continue;
      }
      if (count < 0 || count > branching) {
        return where + "num_children " + std::to_string(count) + " outside [0, branching]";
      }
      if (word_of_node[node] != -1) return where + "an inner node must have word id -1";
      if (first <= node || static_cast<int64_t>(first) + count > n) {
        return where + "children [" + std::to_string(first) + ", " +
               std::to_string(static_cast<int64_t>(first) + count) + ") not after the node " +
               "and inside the tree";
      }
      for (int32_t child = first; child < first + count; ++child) ++parent_count[child];
    }
    if (parent_count[0] != 0) return "the root is a child of another node";
    for (int64_t node = 1; node < n; ++node) {
      if (parent_count[node] != 1) {
        return "node " + std::to_string(node) + " has " + std::to_string(parent_count[node]) +
               " parents, expected 1";
      }
    }
    if (leaves != num_words) {
      return std::to_string(leaves) + " leaves but num_words = " + std::to_string(num_words);
    }
    return "";
  }
};

}  // namespace viosfm
