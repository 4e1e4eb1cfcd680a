// Filtered importance sampling (FIS) of an environment at shading time: a few mip-biased taps of
// the box-filtered source chain along directions drawn from the specular lobe. The CPU version here
// is the reference the renderer's GLSL twin is checked against.
//
// The quantity estimated is the lobe-weighted mean radiance about the reflection (the value a
// prefiltered map stores when N = V): E[L(l)] with l = reflect(−V, h), h drawn from the
// distribution (or l drawn directly for Phong), directions under the surface (N·l ≤ 0) dropped from
// both sums. referenceLobeRadiance is the same integral by brute force.
#pragma once

#include <burnish/core/env/cube.h>
#include <burnish/core/env/prefilter.h>

#include <utility>

namespace burnish {

/// The i-th of n Hammersley points in [0, 1)²: (i/n, radical inverse of i in base 2).
// Hammersley & Handscomb 1964 via Colbert & Křivánek 2007, "GPU-Based Importance Sampling"
std::pair<double, double> hammersley(unsigned i, unsigned n);

enum class SampleDistribution {
    /// Phong lobe (R·L)^n, l drawn about R directly: cosθ = u^(1/(n+1)).
    Phong,
    /// Normalized Blinn-Phong NDF (n+2)/(2π)(N·H)^n: cosθ_h = u^(1/(n+2)).
    BlinnPhong,
    /// Beckmann with m = sqrt(2/(n+2)), slopes by Box–Muller with per-axis σ = m/√2.
    // Baker & Hill 2012, "Rock-Solid Shading": h_x = σ sqrt(−2 log ξ2) cos 2πξ1, H = normalize(h_x, h_y, 1)
    Beckmann,
    /// GGX with α = sqrt(2/(n+2)) (ndf.h's bridge): tan²θ_h = α² u/(1 − u).
    // Walter et al. 2007, "Microfacet Models for Refraction", eq. 35
    Ggx,
    /// LEAN: a slope-space Gaussian with mean B and covariance Σ (σx², σy², ρσxσy) by Box–Muller.
    // Baker & Hill 2012: h_x = σx z_x + μx, h_y = σy(ρ z_x + sqrt(1 − ρ²) z_y) + μy
    Lean,
};
const char* sampleDistributionName(SampleDistribution d);

/// A lobe to sample: `power` for the isotropic ones; LEAN takes the slope mean and covariance in the
/// tangent frame of N (its power is unused).
struct SpecularLobe {
    SampleDistribution distribution = SampleDistribution::BlinnPhong;
    double power = 64.0;
    double meanX = 0.0, meanY = 0.0;                    // LEAN B
    double sigmaXX = 1e-2, sigmaYY = 1e-2, sigmaXY = 0; // LEAN Σ (1/s on the diagonal included)
};

struct LobeSample {
    glm::dvec3 h; // tangent-frame half vector (z along N); for Phong the sampled l itself
    double pdfH;  // density of h per steradian (for Phong: of l)
};

/// Draws a half vector (tangent frame) from the lobe for (u1, u2) ∈ [0, 1)². Never NaN: ξ2 is taken as
/// 1 − u2 ∈ (0, 1] in the Box–Muller logarithm.
LobeSample sampleLobe(const SpecularLobe& lobe, double u1, double u2);
/// The density sampleLobe draws h with (tangent frame, per steradian).
double lobePdfH(const SpecularLobe& lobe, const glm::dvec3& h);

/// Mip level for a tap: 0.5·log2(Ω_s/Ω_p) + 1 with Ω_s = 1/(N·pdf_l), Ω_p = 4π/(6 w²), clamped to
/// [0, mips − 1].
// Colbert & Křivánek 2007, "GPU-Based Importance Sampling", eq. 13
double fisLod(double pdfL, unsigned samples, int faceSize, int mips);

/// FIS estimate with `samples` Hammersley points, trilinear mip-biased taps of `chain` (a box-filtered
/// chain, see buildBoxMips). N, V unit vectors. Black when no sample is above the surface.
glm::dvec3 filteredImportanceSample(const CubeMap& chain, const glm::dvec3& N, const glm::dvec3& V,
                                    const SpecularLobe& lobe, unsigned samples);

/// Brute force over every level-0 texel: Σ L(l) p(l) Ω / Σ p(l) Ω over N·l > 0, p the density of l.
glm::dvec3 referenceLobeRadiance(const CubeMap& cube, const glm::dvec3& N, const glm::dvec3& V,
                                 const SpecularLobe& lobe);

// ---------------------------------------------------------------------------------------------
// Error of a prefiltered map per mip against the brute-force reference, with run times.

struct EnvironmentMipError {
    int mip = 0;
    int size = 0;
    double power = 0.0;
    int sourceLevel = 0;
    double prefilterSeconds = 0.0;
    /// The prefilter's own error: texel values of the mip against referencePrefilteredRadiance at the
    /// texel centres nearest the test directions: sqrt(Σ|Δ|²/Σ|ref|²) over directions and channels, and
    /// the largest |Δ| over the mean |ref|.
    double relativeRms = 0.0;
    double maxRelativeToMean = 0.0;
    /// What a renderer sees: seamless bilinear lookups of the mip at the test directions themselves
    /// against the reference there (adds the mip's resolution error to the prefilter's).
    double lookupRelativeRms = 0.0;
    double referenceSeconds = 0.0;
    /// FIS with the lobe's own distribution (Phong or Blinn-Phong) and `fisSamples` taps against its
    /// brute-force referenceLobeRadiance (V = N = R), at the same texel centres.
    unsigned fisSamples = 0;
    double fisRelativeRms = 0.0;
    double fisSeconds = 0.0;
    /// The fewest taps (powers of two up to kMaxFisSamples) with which FIS is within fisTolerance
    /// (relative RMS) of the prefiltered map at this mip; 0 when none is.
    unsigned fisSamplesToMatch = 0;
};

struct ReferenceComparison {
    unsigned directions = 0;
    double fisTolerance = 0.0;
    std::vector<EnvironmentMipError> mips;
};

inline constexpr unsigned kMaxFisSamples = 4096;

/// Compares every mip of `prefiltered` with the brute-force integrals of `source` (level 0 used) at
/// `directions` fixed, well-spread directions (a spherical Hammersley set, deterministic).
Result<ReferenceComparison> compareWithReference(const PrefilteredEnvironment& prefiltered,
                                                 const CubeMap& source, unsigned directions,
                                                 unsigned fisSamples, double fisTolerance = 0.02);

/// The i-th of n directions spread over the sphere (z = 1 − 2(i + 0.5)/n, φ from the radical inverse).
glm::dvec3 sphereDirection(unsigned i, unsigned n);

/// An orthonormal tangent frame (T, B) about unit N, continuous away from N = −Z.
// Duff et al. 2017, "Building an Orthonormal Basis, Revisited"
void tangentFrame(const glm::dvec3& N, glm::dvec3& T, glm::dvec3& B);

} // namespace burnish
