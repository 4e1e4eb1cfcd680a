#include <burnish/core/env/sampling.h>

#include <burnish/core/util/low_discrepancy.h>

#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/numeric.h>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace burnish {

using glm::dvec3;

namespace {

/// Box–Muller of (u1, u2): two independent standard normals. ξ2 = 1 − u2 ∈ (0, 1] keeps log finite.
// Baker & Hill 2012, "Rock-Solid Shading": z_x = sqrt(−2 log ξ2) cos 2πξ1, z_y = sqrt(−2 log ξ2) sin 2πξ1
void boxMuller(double u1, double u2, double& zx, double& zy) {
    const double xi2 = std::max(1.0 - u2, 1e-300); // u2 < 1 from Hammersley; 1e-300 guards u2 = 1 inputs
    const double r = std::sqrt(-2.0 * std::log(xi2));
    zx = r * std::cos(2.0 * kPi<double> * u1);
    zy = r * std::sin(2.0 * kPi<double> * u1);
}

struct LeanParams {
    double sx, sy, rho, det;
};

LeanParams leanParams(const SpecularLobe& lobe) {
    // Variances floored at kMinVariance (a power of 1e9) and |ρ| kept below 1 so the Gaussian is proper.
    const double sxx = std::max(lobe.sigmaXX, kMinVariance), syy = std::max(lobe.sigmaYY, kMinVariance);
    const double sx = std::sqrt(sxx), sy = std::sqrt(syy);
    const double rho = std::clamp(lobe.sigmaXY / (sx * sy), -0.999, 0.999);
    return {sx, sy, rho, sxx * syy * (1.0 - rho * rho)};
}

dvec3 fromSlopes(double hx, double hy) {
    return glm::normalize(dvec3(hx, hy, 1.0));
}

/// The Beckmann per-axis slope variance of a power: σ² = m²/2 = 1/(n+2).
double beckmannSlopeVariance(double n) {
    const double m = beckmannRoughnessFromPower(n);
    return 0.5 * m * m;
}

} // namespace

std::pair<double, double> hammersley(unsigned i, unsigned n) {
    return {n > 0 ? double(i) / double(n) : 0.0, radicalInverse2(i)};
}

const char* sampleDistributionName(SampleDistribution d) {
    switch (d) {
    case SampleDistribution::Phong:
        return "phong";
    case SampleDistribution::BlinnPhong:
        return "blinn-phong";
    case SampleDistribution::Beckmann:
        return "beckmann";
    case SampleDistribution::Ggx:
        return "ggx";
    case SampleDistribution::Lean:
        return "lean";
    }
    return "?";
}

void tangentFrame(const glm::dvec3& N, glm::dvec3& T, glm::dvec3& B) {
    // Duff et al. 2017, "Building an Orthonormal Basis, Revisited", listing 3
    const double sign = std::copysign(1.0, N.z);
    const double a = -1.0 / (sign + N.z);
    const double b = N.x * N.y * a;
    T = dvec3(1.0 + sign * N.x * N.x * a, sign * b, -sign * N.x);
    B = dvec3(b, sign + N.y * N.y * a, -N.y);
}

LobeSample sampleLobe(const SpecularLobe& lobe, double u1, double u2) {
    const double n = clampPower(lobe.power);
    const double phi = 2.0 * kPi<double> * u1;
    const double xi = std::max(1.0 - u2, 0.0); // in (0, 1] for u2 ∈ [0, 1)
    auto polar = [&](double cosTheta) {
        const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
        return dvec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
    };
    switch (lobe.distribution) {
    case SampleDistribution::Phong: {
        // Lagarde 2011: the Phong lobe (n+1)/(2π) cos^n θ; its CDF inverts to cosθ = ξ^(1/(n+1))
        const dvec3 l = polar(std::pow(xi, 1.0 / (n + 1.0)));
        return {l, lobePdfH(lobe, l)};
    }
    case SampleDistribution::BlinnPhong: {
        // Lazarov 2011: D(h) cosθ_h = (n+2)/(2π) cos^(n+1) θ_h, so cosθ_h = ξ^(1/(n+2))
        const dvec3 h = polar(std::pow(xi, 1.0 / (n + 2.0)));
        return {h, lobePdfH(lobe, h)};
    }
    case SampleDistribution::Beckmann: {
        double zx, zy;
        boxMuller(u1, u2, zx, zy);
        const double sigma = std::sqrt(beckmannSlopeVariance(n));
        const dvec3 h = fromSlopes(sigma * zx, sigma * zy);
        return {h, lobePdfH(lobe, h)};
    }
    case SampleDistribution::Ggx: {
        const double alpha = ggxAlphaFromPower(n);
        // Walter et al. 2007, eq. 35: tan²θ_h = α² ξ/(1 − ξ), written with cos² to stay finite at ξ → 1.
        const double u = std::min(u2, 1.0 - 1e-12); // u2 = 1 would put h on the horizon
        const double cos2 = (1.0 - u) / (1.0 + (alpha * alpha - 1.0) * u);
        const dvec3 h = polar(std::sqrt(std::clamp(cos2, 0.0, 1.0)));
        return {h, lobePdfH(lobe, h)};
    }
    case SampleDistribution::Lean: {
        double zx, zy;
        boxMuller(u1, u2, zx, zy);
        const LeanParams p = leanParams(lobe);
        const double hx = p.sx * zx + lobe.meanX;
        const double hy = p.sy * (p.rho * zx + std::sqrt(1.0 - p.rho * p.rho) * zy) + lobe.meanY;
        const dvec3 h = fromSlopes(hx, hy);
        return {h, lobePdfH(lobe, h)};
    }
    }
    return {dvec3(0, 0, 1), 1.0};
}

double lobePdfH(const SpecularLobe& lobe, const glm::dvec3& h) {
    const double n = clampPower(lobe.power);
    const double cosTheta = h.z;
    if (!(cosTheta > 0.0)) return 0.0;
    switch (lobe.distribution) {
    case SampleDistribution::Phong:
        return phongLobeNorm(n) * powCos(cosTheta, n);
    case SampleDistribution::BlinnPhong:
        return blinnPhongNdf(cosTheta, n) * cosTheta;
    case SampleDistribution::Beckmann:
        return beckmannNdf(cosTheta, beckmannRoughnessFromPower(n)) * cosTheta;
    case SampleDistribution::Ggx:
        return ggxNdf(cosTheta, ggxAlphaFromPower(n)) * cosTheta;
    case SampleDistribution::Lean: {
        // Olano & Baker 2010, "LEAN Mapping": D(h) = P(slope)/cos⁴θ_h with P the slope-space Gaussian;
        // the density of h is D cosθ_h.
        const LeanParams p = leanParams(lobe);
        const double c = std::max(cosTheta, kMinCosine); // slopes are h.xy/h.z: bounded at grazing h
        const double x = h.x / c - lobe.meanX, y = h.y / c - lobe.meanY;
        const double sxx = p.sx * p.sx, syy = p.sy * p.sy, sxy = p.rho * p.sx * p.sy;
        const double q = (syy * x * x - 2.0 * sxy * x * y + sxx * y * y) / p.det;
        // exp(−q/2) underflows to 0 for far slopes; the 1/c³ factor is bounded by kMinCosine above.
        return std::exp(-0.5 * q) / (2.0 * kPi<double> * std::sqrt(p.det) * c * c * c);
    }
    }
    return 0.0;
}

double fisLod(double pdfL, unsigned samples, int faceSize, int mips) {
    const double maxLod = double(std::max(mips, 1) - 1);
    if (!(pdfL > 0.0) || samples == 0 || faceSize <= 0) return maxLod;
    // Colbert & Křivánek 2007, eq. 13: lod = max(0.5 log2(Ω_s/Ω_p) + 1, 0), Ω_s = 1/(N p), Ω_p = 4π/(6 w²)
    const double omegaS = 1.0 / (double(samples) * pdfL);
    const double omegaP = 4.0 * kPi<double> / (6.0 * double(faceSize) * double(faceSize));
    const double lod = 0.5 * std::log2(omegaS / omegaP) + 1.0;
    return std::isfinite(lod) ? std::clamp(lod, 0.0, maxLod) : (lod > 0 ? maxLod : 0.0);
}

glm::dvec3 filteredImportanceSample(const CubeMap& chain, const glm::dvec3& Nin, const glm::dvec3& Vin,
                                    const SpecularLobe& lobe, unsigned samples) {
    if (chain.levels.empty() || samples == 0) return {};
    const dvec3 N = glm::normalize(Nin), V = glm::normalize(Vin);
    const bool phong = lobe.distribution == SampleDistribution::Phong;
    // Phong samples l about the reflection vector; the others sample h about N.
    const dvec3 axis = phong ? glm::normalize(2.0 * glm::dot(N, V) * N - V) : N;
    dvec3 T, B;
    tangentFrame(axis, T, B);
    const dvec3 Vt(glm::dot(V, T), glm::dot(V, B), glm::dot(V, axis));
    dvec3 sum(0.0);
    unsigned used = 0;
    for (unsigned i = 0; i < samples; ++i) {
        const auto [u1, u2] = hammersley(i, samples);
        const LobeSample s = sampleLobe(lobe, u1, u2);
        dvec3 lt;
        double pdfL;
        if (phong) {
            lt = s.h;
            pdfL = s.pdfH;
        } else {
            const double VoH = glm::dot(Vt, s.h);
            if (!(VoH > 0.0)) continue;
            // Baker & Hill 2012: L_i = −reflect(V, H_i); the Jacobian of h → l is 1/(4 v·h)
            lt = 2.0 * VoH * s.h - Vt;
            pdfL = s.pdfH / (4.0 * VoH);
        }
        const dvec3 l = lt.x * T + lt.y * B + lt.z * axis;
        if (!(glm::dot(l, N) > 0.0)) continue;
        sum += sampleCubeLod(chain, l, fisLod(pdfL, samples, chain.faceSize(), chain.mipCount()));
        ++used;
    }
    return used > 0 ? sum / double(used) : dvec3(0.0);
}

namespace {

/// Level 0 flattened once for the brute-force sums.
struct TexelTable {
    std::vector<dvec3> dir;
    std::vector<double> omega;
    std::vector<dvec3> radiance;
};

TexelTable texelTable(const CubeMap& cube) {
    TexelTable t;
    const CubeLevel& level = cube.levels[0];
    const std::vector<double> omegas = texelSolidAngles(level.size);
    for (int f = 0; f < kCubeFaces; ++f)
        for (int y = 0; y < level.size; ++y)
            for (int x = 0; x < level.size; ++x) {
                t.dir.push_back(texelDirection(f, level.size, x, y));
                t.omega.push_back(omegas[size_t(y) * size_t(level.size) + size_t(x)]);
                const float* L = level.texel(f, x, y);
                t.radiance.emplace_back(L[0], L[1], L[2]);
            }
    return t;
}

/// Density of l for the lobe at (N, V) (0 where l is not reachable).
struct LobeDensity {
    const SpecularLobe& lobe;
    dvec3 N, V, axis, T, B;

    LobeDensity(const SpecularLobe& l, const dvec3& n, const dvec3& v)
        : lobe(l)
        , N(glm::normalize(n))
        , V(glm::normalize(v)) {
        axis =
            lobe.distribution == SampleDistribution::Phong ? glm::normalize(2.0 * glm::dot(N, V) * N - V) : N;
        tangentFrame(axis, T, B);
    }
    double operator()(const dvec3& l) const {
        if (lobe.distribution == SampleDistribution::Phong)
            return lobePdfH(lobe, dvec3(glm::dot(l, T), glm::dot(l, B), glm::dot(l, axis)));
        const dvec3 hv = V + l;
        const double len = glm::length(hv);
        if (!(len > 0.0)) return 0.0;
        const dvec3 h = hv / len;
        const double VoH = glm::dot(V, h);
        if (!(VoH > 0.0)) return 0.0;
        return lobePdfH(lobe, dvec3(glm::dot(h, T), glm::dot(h, B), glm::dot(h, axis))) / (4.0 * VoH);
    }
};

dvec3 lobeReference(const TexelTable& t, const dvec3& N, const dvec3& V, const SpecularLobe& lobe) {
    const LobeDensity p(lobe, N, V);
    dvec3 sum(0.0);
    double wsum = 0.0;
    for (size_t i = 0; i < t.dir.size(); ++i) {
        if (!(glm::dot(t.dir[i], p.N) > 0.0)) continue;
        const double w = p(t.dir[i]) * t.omega[i];
        sum += w * t.radiance[i];
        wsum += w;
    }
    return wsum > 0.0 ? sum / wsum : dvec3(0.0);
}

dvec3 prefilterReference(const TexelTable& t, const dvec3& R, LobeModel lobe, double power) {
    dvec3 sum(0.0);
    double wsum = 0.0;
    for (size_t i = 0; i < t.dir.size(); ++i) {
        const double w = lobeWeight(lobe, power, glm::dot(R, t.dir[i])) * t.omega[i];
        sum += w * t.radiance[i];
        wsum += w;
    }
    return wsum > 0.0 ? sum / wsum : dvec3(0.0);
}

double seconds(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

double relativeRms(const std::vector<dvec3>& value, const std::vector<dvec3>& ref) {
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < value.size(); ++i) {
        const dvec3 d = value[i] - ref[i];
        num += glm::dot(d, d);
        den += glm::dot(ref[i], ref[i]);
    }
    return den > 0.0 ? std::sqrt(num / den) : std::sqrt(num);
}

} // namespace

glm::dvec3 referenceLobeRadiance(const CubeMap& cube, const glm::dvec3& N, const glm::dvec3& V,
                                 const SpecularLobe& lobe) {
    if (cube.levels.empty()) return {};
    return lobeReference(texelTable(cube), N, V, lobe);
}

glm::dvec3 sphereDirection(unsigned i, unsigned n) {
    const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(std::max(n, 1u));
    const double phi = 2.0 * kPi<double> * radicalInverse2(i);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

Result<ReferenceComparison> compareWithReference(const PrefilteredEnvironment& prefiltered,
                                                 const CubeMap& source, unsigned directions,
                                                 unsigned fisSamples, double fisTolerance) {
    if (source.levels.empty() || prefiltered.radiance.levels.empty())
        return Error{"nothing to compare: an empty cube"};
    if (directions == 0) return Error{"the comparison needs at least one direction"};
    if (prefiltered.powers.size() != size_t(prefiltered.radiance.mipCount()))
        return Error{"the prefiltered cube's powers do not match its mips"};
    const TexelTable table = texelTable(source);
    CubeMap chain;
    chain.levels.push_back(source.levels[0]);
    buildBoxMips(chain);

    ReferenceComparison out;
    out.directions = directions;
    out.fisTolerance = fisTolerance;
    std::vector<dvec3> dirs;
    for (unsigned i = 0; i < directions; ++i)
        dirs.push_back(sphereDirection(i, directions));
    for (int m = 0; m < prefiltered.radiance.mipCount(); ++m) {
        EnvironmentMipError row;
        row.mip = m;
        row.size = prefiltered.radiance.levels[size_t(m)].size;
        row.power = prefiltered.powers[size_t(m)];
        row.sourceLevel = m < int(prefiltered.sourceLevels.size()) ? prefiltered.sourceLevels[size_t(m)] : 0;
        row.prefilterSeconds = m < int(prefiltered.seconds.size()) ? prefiltered.seconds[size_t(m)] : 0.0;
        // The test directions snapped to the mip's texel centres, where the map holds the filter's value.
        const CubeLevel& level = prefiltered.radiance.levels[size_t(m)];
        std::vector<dvec3> centres(directions), ref(directions), map(directions), fis(directions),
            fisRef(directions), lookup(directions), lookupRef(directions);
        for (unsigned i = 0; i < directions; ++i) {
            const CubeCoord c = cubeCoord(dirs[i]);
            const int x = std::min(int(c.s * level.size), level.size - 1);
            const int y = std::min(int(c.t * level.size), level.size - 1);
            centres[i] = texelDirection(c.face, level.size, x, y);
            const float* v = level.texel(c.face, x, y);
            map[i] = dvec3(v[0], v[1], v[2]);
            lookup[i] = sampleCube(prefiltered.radiance, dirs[i], m);
        }
        auto t0 = std::chrono::steady_clock::now();
        tbb::parallel_for(0u, directions, [&](unsigned i) {
            ref[i] = prefilterReference(table, centres[i], prefiltered.lobe, row.power);
        });
        row.referenceSeconds = seconds(t0);
        tbb::parallel_for(0u, directions, [&](unsigned i) {
            lookupRef[i] = prefilterReference(table, dirs[i], prefiltered.lobe, row.power);
        });
        double maxAbs = 0.0, meanRef = 0.0;
        for (unsigned i = 0; i < directions; ++i) {
            const dvec3 d = glm::abs(map[i] - ref[i]);
            maxAbs = std::max({maxAbs, d.x, d.y, d.z});
            meanRef += (ref[i].x + ref[i].y + ref[i].z) / (3.0 * directions);
        }
        row.relativeRms = relativeRms(map, ref);
        row.maxRelativeToMean = meanRef > 0.0 ? maxAbs / meanRef : maxAbs;
        row.lookupRelativeRms = relativeRms(lookup, lookupRef);

        SpecularLobe lobe;
        lobe.distribution =
            prefiltered.lobe == LobeModel::Phong ? SampleDistribution::Phong : SampleDistribution::BlinnPhong;
        lobe.power = row.power;
        row.fisSamples = fisSamples;
        if (fisSamples > 0) {
            tbb::parallel_for(0u, directions, [&](unsigned i) {
                fisRef[i] = lobeReference(table, centres[i], centres[i], lobe);
            });
            t0 = std::chrono::steady_clock::now();
            tbb::parallel_for(0u, directions, [&](unsigned i) {
                fis[i] = filteredImportanceSample(chain, centres[i], centres[i], lobe, fisSamples);
            });
            row.fisSeconds = seconds(t0);
            row.fisRelativeRms = relativeRms(fis, fisRef);
        }
        for (unsigned n = 1; n <= kMaxFisSamples; n *= 2) {
            tbb::parallel_for(0u, directions, [&](unsigned i) {
                fis[i] = filteredImportanceSample(chain, centres[i], centres[i], lobe, n);
            });
            if (relativeRms(fis, map) <= fisTolerance) {
                row.fisSamplesToMatch = n;
                break;
            }
        }
        out.mips.push_back(row);
    }
    return out;
}

} // namespace burnish
