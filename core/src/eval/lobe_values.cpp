#include "lobe_values.h"

#include <burnish/core/shading/ggx_specular.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/numeric.h>
#include <burnish/core/util/simd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace burnish {

namespace {

BURNISH_AVX512_CLONES void blinnPhongValues(const LobeTable& t, size_t begin, size_t count,
                                            const DirectionPair& d, double* out) {
    const double *nx = t.nx.data() + begin, *ny = t.ny.data() + begin, *nz = t.nz.data() + begin;
    const double *power = t.power.data() + begin, *norm = t.norm.data() + begin;
    const double hx = d.h.x, hy = d.h.y, hz = d.h.z, lx = d.l.x, ly = d.l.y, lz = d.l.z;
    for (size_t i = 0; i < count; ++i) {
        const double c = nx[i] * hx + ny[i] * hy + nz[i] * hz;
        const double nl = std::max(0.0, nx[i] * lx + ny[i] * ly + nz[i] * lz);
        out[i] = norm[i] * powCosFast(c, power[i]) * nl;
    }
}

// ggxSpecularTerm about each lobe's normal with its α (in `power`).
BURNISH_AVX512_CLONES void ggxValues(const LobeTable& t, size_t begin, size_t count, const DirectionPair& d,
                                     double* out) {
    const double *nx = t.nx.data() + begin, *ny = t.ny.data() + begin, *nz = t.nz.data() + begin;
    const double* alpha = t.power.data() + begin;
    const double hx = d.h.x, hy = d.h.y, hz = d.h.z, lx = d.l.x, ly = d.l.y, lz = d.l.z;
    const double vx = d.v.x, vy = d.v.y, vz = d.v.z;
    for (size_t i = 0; i < count; ++i)
        out[i] = ggxSpecularTerm(nx[i] * hx + ny[i] * hy + nz[i] * hz, nx[i] * lx + ny[i] * ly + nz[i] * lz,
                                 nx[i] * vx + ny[i] * vy + nz[i] * vz, alpha[i]);
}

// ggxAnisotropicSpecularTerm about each lobe's normal, in the geometric frame of its direction.
BURNISH_AVX512_CLONES void ggxAnisotropicValues(const LobeTable& t, size_t begin, size_t count,
                                                const DirectionPair& d, double* out) {
    const double *nx = t.nx.data() + begin, *ny = t.ny.data() + begin, *nz = t.nz.data() + begin;
    const double *ab = t.power.data() + begin, *at = t.alphaT.data() + begin;
    const double *ca = t.cosA.data() + begin, *sa = t.sinA.data() + begin;
    const double hx = d.h.x, hy = d.h.y, hz = d.h.z, lx = d.l.x, ly = d.l.y, lz = d.l.z;
    const double vx = d.v.x, vy = d.v.y, vz = d.v.z;
    for (size_t i = 0; i < count; ++i) {
        const double c = ca[i], s = sa[i];
        out[i] = ggxAnisotropicSpecularTerm(
            nx[i] * hx + ny[i] * hy + nz[i] * hz, c * hx + s * hy, c * hy - s * hx,
            nx[i] * lx + ny[i] * ly + nz[i] * lz, c * lx + s * ly, c * ly - s * lx,
            nx[i] * vx + ny[i] * vy + nz[i] * vz, c * vx + s * vy, c * vy - s * vx, at[i], ab[i]);
    }
}

// Σ over the slots of share·D(h)·max(0, n·l), D the slope-space Gaussian of slopeGaussianNdf.
BURNISH_AVX512_CLONES void gaussianValues(const LobeTable& t, size_t begin, size_t count,
                                          const DirectionPair& d, double* out) {
    std::fill(out, out + count, 0.0);
    // Directions below the horizon have no slope (slopeGaussianNdf's h_z <= 0 case).
    if (!(d.h.z > 0.0)) return;
    const double tx = d.h.x / d.h.z, ty = d.h.y / d.h.z;
    const double hz2 = d.h.z * d.h.z, invHz4 = 1.0 / (hz2 * hz2);
    const double lx = d.l.x, ly = d.l.y, lz = d.l.z;
    for (int s = 0; s < t.slots; ++s) {
        const size_t o = size_t(s) * t.count + begin;
        const double *coef = t.coef.data() + o, *mx = t.mx.data() + o, *my = t.my.data() + o;
        const double *ixx = t.ixx.data() + o, *iyy = t.iyy.data() + o, *ixy = t.ixy.data() + o;
        const double *nx = t.nx.data() + o, *ny = t.ny.data() + o, *nz = t.nz.data() + o;
        for (size_t i = 0; i < count; ++i) {
            const double dx = tx - mx[i], dy = ty - my[i];
            const double e = dx * dx * ixx[i] + dy * dy * iyy[i] + 2.0 * dx * dy * ixy[i];
            const double nl = std::max(0.0, nx[i] * lx + ny[i] * ly + nz[i] * lz);
            out[i] += coef[i] * expNonPositive(-0.5 * e) * invHz4 * nl;
        }
    }
}

// Σ over the slots of share·ggxSpecularTerm about the slot's normal with its α.
BURNISH_AVX512_CLONES void ggxMixtureValues(const LobeTable& t, size_t begin, size_t count,
                                            const DirectionPair& d, double* out) {
    std::fill(out, out + count, 0.0);
    const double hx = d.h.x, hy = d.h.y, hz = d.h.z, lx = d.l.x, ly = d.l.y, lz = d.l.z;
    const double vx = d.v.x, vy = d.v.y, vz = d.v.z;
    for (int s = 0; s < t.slots; ++s) {
        const size_t o = size_t(s) * t.count + begin;
        const double *share = t.coef.data() + o, *alpha = t.power.data() + o;
        const double *nx = t.nx.data() + o, *ny = t.ny.data() + o, *nz = t.nz.data() + o;
        for (size_t i = 0; i < count; ++i)
            out[i] += share[i] * ggxSpecularTerm(nx[i] * hx + ny[i] * hy + nz[i] * hz,
                                                 nx[i] * lx + ny[i] * ly + nz[i] * lz,
                                                 nx[i] * vx + ny[i] * vy + nz[i] * vz, alpha[i]);
    }
}

void putGgxLobe(LobeTable& t, size_t i, double weight, const MixtureGgxLobe& l) {
    t.coef[i] = weight * l.share;
    t.power[i] = l.alpha;
    t.nx[i] = l.normal.x, t.ny[i] = l.normal.y, t.nz[i] = l.normal.z;
}

// One Gaussian slot from its share, mean, covariance (xx, yy, xy) and normal.
void putGaussian(LobeTable& t, size_t i, double share, const glm::dvec2& mean,
                 const std::array<double, 3>& cov, const glm::dvec3& normal) {
    const double det = cov[0] * cov[1] - cov[2] * cov[2];
    // Σ = C + I/s with C positive semi-definite, so det >= 1/s² > 0; a rounding that breaks it gives
    // no lobe, as slopeGaussianNdf.
    const bool ok = det > 0.0 && share > 0.0;
    t.coef[i] = ok ? share / (2.0 * kPi<double> * std::sqrt(det)) : 0.0;
    t.mx[i] = mean.x, t.my[i] = mean.y;
    t.ixx[i] = ok ? cov[1] / det : 0.0;
    t.iyy[i] = ok ? cov[0] / det : 0.0;
    t.ixy[i] = ok ? -cov[2] / det : 0.0;
    t.nx[i] = normal.x, t.ny[i] = normal.y, t.nz[i] = normal.z;
}

void resizeGaussian(LobeTable& t, size_t n) {
    for (auto* v : {&t.coef, &t.mx, &t.my, &t.ixx, &t.iyy, &t.ixy, &t.nx, &t.ny, &t.nz})
        v->assign(n, 0.0);
}

} // namespace

LobeTable LobeTable::of(const std::vector<TexelLobe>& lobes, Brdf brdf) {
    LobeTable t;
    t.count = lobes.size();
    const bool gaussian = !lobes.empty() && lobes.front().slopeGaussian;
    for (const TexelLobe& l : lobes)
        if (l.slopeGaussian != gaussian)
            throw std::logic_error("a level mixes Gaussian and Blinn-Phong lobes");
    if (gaussian && brdf == Brdf::Ggx) throw std::logic_error("a slope-space lobe has no GGX form");
    if (brdf == Brdf::Ggx) {
        t.kind = Kind::Ggx;
        for (auto* v : {&t.nx, &t.ny, &t.nz, &t.power})
            v->resize(t.count);
        for (size_t i = 0; i < t.count; ++i) {
            const glm::dvec3 n(lobes[i].normal);
            t.nx[i] = n.x, t.ny[i] = n.y, t.nz[i] = n.z;
            t.power[i] = ggxAlphaFromPower(lobes[i].power);
        }
        return t;
    }
    if (gaussian) {
        t.kind = Kind::Gaussian;
        resizeGaussian(t, t.count);
        for (size_t i = 0; i < t.count; ++i)
            putGaussian(t, i, 1.0, lobes[i].slopeMean, lobes[i].slopeCov, glm::dvec3(lobes[i].normal));
        return t;
    }
    for (auto* v : {&t.nx, &t.ny, &t.nz, &t.power, &t.norm})
        v->resize(t.count);
    for (size_t i = 0; i < t.count; ++i) {
        const glm::dvec3 n(lobes[i].normal);
        t.nx[i] = n.x, t.ny[i] = n.y, t.nz[i] = n.z;
        t.power[i] = clampPower(lobes[i].power);
        t.norm[i] = blinnPhongNdfNorm(lobes[i].power);
    }
    return t;
}

LobeTable LobeTable::ofAnisotropic(const std::vector<glm::dvec3>& normals,
                                   const std::vector<AnisotropicLobe>& lobes) {
    if (normals.size() != lobes.size()) throw std::logic_error("one normal per anisotropic lobe");
    LobeTable t;
    t.kind = Kind::GgxAnisotropic;
    t.count = lobes.size();
    for (auto* v : {&t.nx, &t.ny, &t.nz, &t.power, &t.alphaT, &t.cosA, &t.sinA})
        v->resize(t.count);
    for (size_t i = 0; i < t.count; ++i) {
        t.nx[i] = normals[i].x, t.ny[i] = normals[i].y, t.nz[i] = normals[i].z;
        t.power[i] = lobes[i].alphaB, t.alphaT[i] = lobes[i].alphaT;
        t.cosA[i] = std::cos(lobes[i].angle), t.sinA[i] = std::sin(lobes[i].angle);
    }
    return t;
}

LobeTable LobeTable::of(const std::vector<DecodedMixture>& mixtures) {
    LobeTable t;
    t.kind = Kind::Gaussian;
    t.count = mixtures.size();
    t.slots = 1;
    for (const DecodedMixture& m : mixtures)
        t.slots = std::max(t.slots, m.count);
    resizeGaussian(t, size_t(t.slots) * t.count);
    for (size_t i = 0; i < t.count; ++i)
        for (int s = 0; s < mixtures[i].count; ++s) {
            const DecodedMixture::Lobe& l = mixtures[i].lobes[size_t(s)];
            putGaussian(t, size_t(s) * t.count + i, l.share, l.mean, l.cov, l.normal);
        }
    return t;
}

LobeTable LobeTable::ofBlends(const std::vector<DecodedMixture>& texels,
                              const std::vector<std::array<size_t, 4>>& at,
                              const std::array<double, 4>& weights) {
    LobeTable t;
    t.kind = Kind::Gaussian;
    t.count = at.size();
    int lobes = 1; // slots per texel of the blend
    for (const DecodedMixture& m : texels)
        lobes = std::max(lobes, m.count);
    t.slots = 4 * lobes;
    resizeGaussian(t, size_t(t.slots) * t.count);
    for (size_t i = 0; i < t.count; ++i)
        for (size_t c = 0; c < 4; ++c) {
            const DecodedMixture& m = texels[at[i][c]];
            for (int s = 0; s < m.count; ++s) {
                const DecodedMixture::Lobe& l = m.lobes[size_t(s)];
                putGaussian(t, (c * size_t(lobes) + size_t(s)) * t.count + i, weights[c] * l.share, l.mean,
                            l.cov, l.normal);
            }
        }
    return t;
}

LobeTable LobeTable::ofGgxMixture(const std::vector<GgxMixtureTexel>& texels, int lobes) {
    LobeTable t;
    t.kind = Kind::GgxMixture;
    t.count = texels.size();
    t.slots = std::clamp(lobes, 1, kMaxMixtureLobes);
    for (auto* v : {&t.coef, &t.power, &t.nx, &t.ny, &t.nz})
        v->assign(size_t(t.slots) * t.count, 0.0);
    for (size_t i = 0; i < t.count; ++i)
        for (int s = 0; s < t.slots; ++s)
            putGgxLobe(t, size_t(s) * t.count + i, 1.0, texels[i][size_t(s)]);
    return t;
}

LobeTable LobeTable::ofGgxBlends(const std::vector<GgxMixtureTexel>& texels, int lobes,
                                 const std::vector<std::array<size_t, 4>>& at,
                                 const std::array<double, 4>& weights) {
    LobeTable t;
    t.kind = Kind::GgxMixture;
    t.count = at.size();
    lobes = std::clamp(lobes, 1, kMaxMixtureLobes);
    t.slots = 4 * lobes;
    for (auto* v : {&t.coef, &t.power, &t.nx, &t.ny, &t.nz})
        v->assign(size_t(t.slots) * t.count, 0.0);
    for (size_t i = 0; i < t.count; ++i)
        for (size_t c = 0; c < 4; ++c)
            for (int s = 0; s < lobes; ++s)
                putGgxLobe(t, (c * size_t(lobes) + size_t(s)) * t.count + i, weights[c],
                           texels[at[i][c]][size_t(s)]);
    return t;
}

MixtureGgxStored mixtureGgxStored(const MixturePyramid& mix, const NormalMap& map, int k, int x, int y,
                                  double s) {
    const auto lobes = mix.storedTexel(map, k, x, y, s);
    const double v = mixtureBaseVariance(s, mix.lobeCount());
    MixtureGgxStored out{};
    for (size_t i = 0; i < lobes.size(); ++i)
        out[i] = mixtureGgxTexel(lobes[i], v);
    return out;
}

LobeTable::GgxMixtureTexel mixtureGgxDecoded(const MixtureGgxStored& stored, int lobes, double s) {
    lobes = std::clamp(lobes, 1, kMaxMixtureLobes);
    double total = 0.0;
    for (int i = 0; i < lobes; ++i)
        total += std::max(stored[size_t(i)][0], 0.0);
    const double alpha0 = ggxAlphaFromPower(std::max(clampPower(s), kMinBasePower));
    LobeTable::GgxMixtureTexel out{};
    for (int i = 0; i < lobes; ++i)
        out[size_t(i)] = mixtureGgxLobe(stored[size_t(i)], total, alpha0);
    return out;
}

void lobeValues(const LobeTable& table, size_t begin, size_t end, const DirectionPair& d, double* out) {
    if (table.kind == LobeTable::Kind::BlinnPhong)
        blinnPhongValues(table, begin, end - begin, d, out);
    else if (table.kind == LobeTable::Kind::Ggx)
        ggxValues(table, begin, end - begin, d, out);
    else if (table.kind == LobeTable::Kind::GgxAnisotropic)
        ggxAnisotropicValues(table, begin, end - begin, d, out);
    else if (table.kind == LobeTable::Kind::GgxMixture)
        ggxMixtureValues(table, begin, end - begin, d, out);
    else
        gaussianValues(table, begin, end - begin, d, out);
}

} // namespace burnish
