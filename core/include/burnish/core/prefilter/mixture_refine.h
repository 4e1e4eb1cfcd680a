// The lobe mixture fitted to the shaded ground truth itself: an opt-in refinement of the moment fit
// (MixturePyramid) for final exports. The moment fit merges lobes by their moments, so a Gaussian
// lobe stands for each cluster of normals; where a cluster is not Gaussian (heavy-tailed noise, a
// sharp core with a wide skirt) its lobe is too broad and the highlight loses its peak and energy,
// and each lobe's shape differs from the Blinn-Phong lobes it stands for. Here every texel's lobes
// (weights, mean slopes, covariances) are refined by Levenberg-Marquardt (Eigen, analytic
// derivatives) so that the mixture's value Σ share·D(h)·max(0, n·l) matches the footprint's ground
// truth (evaluate's definition: the mean of D_s(n·h)·max(0, n·l) over its finest normals), and its
// energy, at a
// training set of light/view pairs: a fixed set over several views (not evaluate's own pairs), and
// per lobe nine half vectors on its axes at 0, ±1 and ±2 standard deviations, where the highlight is.
// Each lobe's covariance stays at least the base lobe's (Σ = v·I + LLᵀ), the texel's total weight
// is kept (the stored moments stay premultiplied, so filtering still merges them exactly), and a
// texel keeps its moment fit wherever the refinement does not lower the training error.
#pragma once

#include <burnish/core/prefilter/fitted_lobe.h>
#include <burnish/core/prefilter/lobe_mixture.h>

#include <vector>

namespace burnish {

/// The weight of the training energy in the shaded fit's objective: the pairs' squared errors e_i²
/// plus (kShadedFitEnergyWeight·Σe_i/√n)². Without it a least-squares fit to a footprint of scattered
/// normals trades energy for shape. 8 real maps (core/bench/mixture_study.py --shaded-fit, 96 cases, K = 3):
/// weight 0 / 1 / 4: mean ratio to LEAN's error 0.311 / 0.315 / 0.335, cases worse than LEAN 2 / 3 / 5,
/// outside the energy band [0.97, 1.03] 35 / 29 / 19, energy 0.50-1.05 / 0.63-1.05 / 0.70-1.14.
inline constexpr double kShadedFitEnergyWeight = 1.0;

/// The fixed training pairs of the shaded fit: half angles 0.75° to 55° in 13 rings, 12 azimuths a
/// ring (offset from evaluate's), the view 10°, 35° or 60° from the normal by turns (a light below
/// 3° above the horizon takes the next lower view). None is one of evaluate's default pairs.
std::vector<DirectionPair> shadedFitDirections();

/// One texel's lobes refined against its ground truth: `truth[i]` at `directions[i]`. The base
/// variance v is the floor of every lobe's variance (MixturePyramid::minVariance). Returns
/// `fitted` itself when the refinement does not lower the objective (the squared errors and the
/// energy's, kShadedFitEnergyWeight) or leaves a
/// non-finite value; otherwise the refined lobes, in the same slots, with `fitted`'s total weight
/// (a lobe whose share falls below 1e-4 is dropped, its weight given to the others).
LobeMixture refineMixtureToTruth(const LobeMixture& fitted, const std::vector<DirectionPair>& directions,
                                 const std::vector<double>& truth, double v);

/// Refines every texel of every level of `mixture` (built from `pyramid` with base power s, or
/// each finest texel's own power `texelPowers`) against its footprint's ground truth at
/// shadedFitDirections() and at the half vectors on its lobes' axes. Deterministic, in parallel
/// over texels. Pass it to MixturePyramid::build as `refine` (buildShadedMixture does).
void refineMixturePyramid(MixturePyramid& mixture, const NormalPyramid& pyramid, double s,
                          const std::vector<double>* texelPowers = nullptr);

/// MixturePyramid::build with refineMixturePyramid as its refinement.
MixturePyramid buildShadedMixture(const NormalPyramid& pyramid, double s, int k, int lastLevel = -1,
                                  const std::vector<double>* texelPowers = nullptr);

} // namespace burnish
