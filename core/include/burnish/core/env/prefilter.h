// The prefiltered mipmapped radiance environment map (PMREM): each mip of a cube (env/cube.h)
// filtered by a cosine-power lobe whose power drops per mip or follows a gloss encoding.
#pragma once

#include <burnish/core/env/cube.h>
#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/util/result.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace burnish {

/// The lobe each mip is filtered with, about the reflection vector R (with N = V = R).
enum class LobeModel {
    /// (R·L)^n: what a single cube-map tap can show (AMD CubeMapGen's cosine power filter).
    Phong,
    /// (N·H)^n with N = V = R, i.e. cos^n(θ/2) = ((1 + R·L)/2)^(n/2): the Blinn-Phong highlight at
    /// normal incidence, close to Phong with n/4.
    // Lagarde 2012, "Relationship between Phong and Blinn lighting model": acos(R·E) = 2 acos(N·H)
    BlinnPhong,
};
const char* lobeModelName(LobeModel lobe);

struct PrefilterOptions {
    LobeModel lobe = LobeModel::Phong;
    /// Output mips; 0 is the full chain down to 1×1.
    int mips = 0;
    /// Power per mip from a drop factor: n_m = topPower · powerDrop^m.
    // Lagarde 2011, "AMD Cubemapgen for physically based rendering": 2048, 0.25 → 2048, 512, 128, ...
    double topPower = 2048.0;
    double powerDrop = 0.25;
    /// When set, the power per mip follows the encoding instead: mip m ↔ gloss g = 1 − m/(mips − 1)
    /// (the stored value is g for gloss-like encodings, 1 − g for roughness-like ones), n = power(v).
    // Lazarov 2011, "Physically Based Lighting in Call of Duty: Black Ops": the mip is selected from gloss
    std::optional<GlossEncoding> encoding;
    /// The lobe is cut where its weight falls below this fraction of its peak (the relative energy
    /// left out is about the same).
    double lobeCutoff = 1e-5;
    /// Source texels per lobe standard deviation: each mip reads the coarsest box-filtered source
    /// level that still has this many (more is slower and closer to the brute-force reference).
    double texelsPerSigma = 2.5;
    /// Called with the fraction done (0..1) from the calling thread, once per output mip.
    std::function<void(double)> progress;
};

/// The power of each of `mips` output levels under the options (clamped to [0, kMaxPower]).
std::vector<double> prefilterPowers(const PrefilterOptions& options, int mips);
/// The mip (fractional, in [0, mips − 1]) a gloss value g ∈ [0, 1] reads: (1 − g)·(mips − 1).
// Lazarov 2011: texCUBElod(uv, float4(R, nMips − gloss·nMips)), with the last mip at g = 0
double mipForGloss(double g, int mips);

struct PrefilteredEnvironment {
    CubeMap radiance;
    std::vector<double> powers;    // per mip
    std::vector<int> sourceLevels; // the box-filtered source level each mip read
    std::vector<double> seconds;   // wall time per mip
    LobeModel lobe = LobeModel::Phong;
};

/// Filters `source` (level 0 is used) into a radiance cube of the same face size: texel of mip m =
/// Σ L(d) w(R·d) Ω(d) / Σ w(R·d) Ω(d) over source texels d, with R the texel's direction and w the
/// lobe of power n_m. The integral runs over directions (not per face), so texels that touch across a
/// cube edge agree. Errors: empty or non-power-of-two source, mips out of range, bad options.
Result<PrefilteredEnvironment> prefilterRadiance(const CubeMap& source, const PrefilterOptions& options);

/// The peak memory of `burnish env` making a cube of face size `faceSize` with its full mip chain from
/// an input of `inputTexels` texels (an equirectangular image, or the six face files together; 0 for
/// the procedural studio): the process, 48 bytes per texel of the finest level's six faces (the source,
/// its box chain, the prefiltered chain, the staged files) and 32 per input texel (its float copies).
/// Measured peaks (core/bench/command_memory.sh, courtyard.exr 1024×512) against this: face 256 181 /
/// 186 MB, 512 241 / 243 MB, 1024 443 / 469 MB, 2048 1362 / 1375 MB; the procedural studio at 512 222 /
/// 226 MB.
std::uint64_t estimatedEnvironmentBytes(int faceSize, std::uint64_t inputTexels);

/// The lobe's weight for cosine c = R·L (0 outside its support), never NaN.
double lobeWeight(LobeModel lobe, double power, double c);

/// Brute force: the same normalized lobe integral at one direction over every level-0 texel of
/// `source`, with no cut and no coarser source level.
glm::dvec3 referencePrefilteredRadiance(const CubeMap& source, const glm::dvec3& R, LobeModel lobe,
                                        double power);

} // namespace burnish
