// The structure of a bundle adjustment problem that decides what each
// linear solver costs (sfm/linear_solver_chooser.h): how many free images,
// observations and points, and how full the reduced camera matrix is.
#pragma once

#include <cstddef>
#include <vector>

#include "viosfm/scene/reconstruction.h"
#include "viosfm/util/types.h"

namespace viosfm {

struct BaProblemStructure {
  size_t num_free_images = 0;  // n: the camera blocks of the reduced camera matrix
  size_t num_points = 0;       // points observed by a free image
  // Observations of those points in registered images (held ones included:
  // each is a residual block of the problem).
  size_t num_observations = 0;
  // E: pairs of free images that observe a common point, i.e. the non-zero
  // off-diagonal 6x6 blocks of the (upper half of the) reduced camera matrix.
  size_t num_covisible_pairs = 0;
  // The work of a sparse Cholesky factorisation of the reduced camera
  // matrix in 6x6 blocks: sum over the factor's block columns of the squared
  // count of its non-zero blocks, under the approximate minimum degree
  // ordering a sparse solver uses. Unlike E^2 / n it tells a band (a walk
  // seen once: little fill) from the same number of pairs spread over the
  // matrix (revisits: the factor fills in). 0 unless computed
  // (ComputeBaProblemStructure's with_factorization).
  double factorization_block_flops = 0.0;

  // X = E^2 / (n * observations). E^2 / n estimates the work of a sparse
  // Cholesky factorisation of the reduced camera matrix in blocks: n^3 / 4
  // when every camera sees every other (E = n^2 / 2), n b^2 for a band of b
  // neighbours (E = n b); dividing by the observations, which set the rest
  // of an iteration's work, makes X the factorisation's share. 0 without
  // observations.
  double FillPerObservation() const;

  // factorization_block_flops / observations: the factorisation's work
  // against the rest of an iteration's. 0 without observations.
  double FactorizationPerObservation() const;
  // factorization_block_flops / free images: the factorisation's work per
  // camera, which does not change with the features per image (the pattern
  // of the reduced camera matrix is the co-visibility's). 0 without images.
  double FactorizationPerImage() const;
};

// The structure of adjusting `free_images` (registered images of
// `reconstruction`; others are held constant). Deterministic; costs
// O(sum over points of track length^2) bit operations and n^2 / 8 bytes.
// `with_factorization`: also factorization_block_flops, from a symbolic
// factorisation of the n x n block pattern (up to n^3 / 3 operations when
// every camera sees every other: a fraction of one iteration's cost).
BaProblemStructure ComputeBaProblemStructure(const Reconstruction& reconstruction,
                                             const std::vector<image_t>& free_images,
                                             bool with_factorization = false);

}  // namespace viosfm
