// Where LEAN's energy goes (evaluate.h LeanEnergySplit): the truth, the truth with one cosine, the
// Gaussian of the footprint's normals that are not steep, and LEAN, summed over texels and direction
// pairs per mip.
#include <burnish/core/eval/evaluate.h>

#include "band_batches.h"
#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/numeric.h>

#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace burnish {

namespace {

// The sums of one band of texels over every direction pair: truth, truth with one cosine, the steep
// normals' truth, the Gaussian without the steep normals, LEAN.
struct SplitSums {
    double truth = 0.0, oneCosine = 0.0, steepTruth = 0.0, withoutSteep = 0.0, lean = 0.0;
    void operator+=(const SplitSums& o) {
        truth += o.truth, oneCosine += o.oneCosine, steepTruth += o.steepTruth,
            withoutSteep += o.withoutSteep, lean += o.lean;
    }
};

double ratioOr1(double a, double b) {
    return b > 0.0 ? a / b : 1.0;
}

// What one texel's footprint adds up, per direction pair: Σ D_s(n_i·h), Σ D_s(n_i·h)·max(0, n_i·l) and
// that over the steep normals alone (3 × nd values from `sums`), and the raw slope moments of the
// normals that are not steep (count, Σb, Σbbᵀ: 6 values from `moments`).
struct BandLevel {
    int rowBegin = 0, rowEnd = 0, width = 0;
    std::vector<double> sums, moments;
    size_t texel(int x, int y) const { return size_t(y - rowBegin) * size_t(width) + size_t(x); }
};

} // namespace

std::vector<LeanEnergySplit> leanEnergySplit(const NormalPyramid& pyramid, double s, int firstMip,
                                             int lastMip, const std::vector<DirectionPair>& directions,
                                             double steepDeg, const MethodParams& params,
                                             const std::function<bool()>& cancelled) {
    std::vector<LeanEnergySplit> out;
    const NormalMap& map = pyramid.finest();
    // Steep: tilted more than steepDeg from +z, n.z < cos(steepDeg) for a unit normal.
    const double steepZ = std::cos(radians(steepDeg));
    size_t steepCount = 0;
    for (const glm::vec3& n : map.normals)
        steepCount += double(n.z) < steepZ ? 1 : 0;
    const size_t nd = directions.size();
    const size_t mips = size_t(lastMip - firstMip + 1);
    // A band at a time (a row of the last mip and the rows under it at every level down to the
    // first): the finest normals' values are computed once, for the first mip's footprints, and each
    // level above sums its children's (the pyramid nests), as evaluate's truth does.
    const int bands = pyramid.level(lastMip).height;
    std::vector<std::vector<SplitSums>> bandSums(size_t(bands), std::vector<SplitSums>(mips, SplitSums{}));
    const int batches = bandBatches(bands);
    for (int b = 0; b < batches; ++b) {
        if (cancelled && cancelled()) return out;
        const int from = int(int64_t(bands) * b / batches), to = int(int64_t(bands) * (b + 1) / batches);
        tbb::parallel_for(from, to, [&](int band) {
            std::vector<BandLevel> levels(mips);
            for (int k = lastMip; k >= firstMip; --k) {
                BandLevel& l = levels[size_t(k - firstMip)];
                const PyramidLevel& level = pyramid.level(k);
                if (k == lastMip) {
                    l.rowBegin = band, l.rowEnd = band + 1;
                } else {
                    const BandLevel& above = levels[size_t(k + 1 - firstMip)];
                    const PyramidLevel& parent = pyramid.level(k + 1);
                    l.rowBegin = parent.yChild[size_t(above.rowBegin)];
                    l.rowEnd = parent.yChild[size_t(above.rowEnd)];
                }
                l.width = level.width;
                const size_t texels = size_t(l.rowEnd - l.rowBegin) * size_t(l.width);
                l.sums.assign(texels * 3 * nd, 0.0);
                l.moments.assign(texels * 6, 0.0);
            }
            // The first mip's footprints from the finest normals.
            {
                BandLevel& l = levels.front();
                const PyramidLevel& level = pyramid.level(firstMip);
                for (int y = l.rowBegin; y < l.rowEnd; ++y)
                    for (int x = 0; x < l.width; ++x) {
                        double* sum = &l.sums[l.texel(x, y) * 3 * nd];
                        double* m = &l.moments[l.texel(x, y) * 6];
                        for (int j = level.yStart[size_t(y)]; j < level.yStart[size_t(y) + 1]; ++j)
                            for (int i = level.xStart[size_t(x)]; i < level.xStart[size_t(x) + 1]; ++i) {
                                const glm::dvec3 n(map.at(i, j));
                                const bool steep = n.z < steepZ;
                                for (size_t d = 0; d < nd; ++d) {
                                    const double D = blinnPhongNdf(glm::dot(n, directions[d].h), s);
                                    const double Dc = D * std::max(0.0, glm::dot(n, directions[d].l));
                                    sum[d] += D;
                                    sum[nd + d] += Dc;
                                    if (steep) sum[2 * nd + d] += Dc;
                                }
                                if (steep) continue;
                                // As the pyramid's slopes: b = n.xy / max(n.z, kMinSlopeZ).
                                const double zs = std::max(n.z, double(kMinSlopeZ));
                                const double sx = n.x / zs, sy = n.y / zs;
                                m[0] += 1.0, m[1] += sx, m[2] += sy, m[3] += sx * sx, m[4] += sy * sy,
                                    m[5] += sx * sy;
                            }
                    }
            }
            for (int k = firstMip + 1; k <= lastMip; ++k) {
                BandLevel& l = levels[size_t(k - firstMip)];
                const BandLevel& child = levels[size_t(k - 1 - firstMip)];
                const PyramidLevel& level = pyramid.level(k);
                for (int y = l.rowBegin; y < l.rowEnd; ++y)
                    for (int x = 0; x < l.width; ++x) {
                        double* sum = &l.sums[l.texel(x, y) * 3 * nd];
                        double* m = &l.moments[l.texel(x, y) * 6];
                        for (int j = level.yChild[size_t(y)]; j < level.yChild[size_t(y) + 1]; ++j)
                            for (int i = level.xChild[size_t(x)]; i < level.xChild[size_t(x) + 1]; ++i) {
                                const double* cs = &child.sums[child.texel(i, j) * 3 * nd];
                                const double* cm = &child.moments[child.texel(i, j) * 6];
                                for (size_t v = 0; v < 3 * nd; ++v)
                                    sum[v] += cs[v];
                                for (size_t v = 0; v < 6; ++v)
                                    m[v] += cm[v];
                            }
                    }
            }
            for (int k = firstMip; k <= lastMip; ++k) {
                const BandLevel& l = levels[size_t(k - firstMip)];
                SplitSums& row = bandSums[size_t(band)][size_t(k - firstMip)];
                for (int y = l.rowBegin; y < l.rowEnd; ++y)
                    for (int x = 0; x < l.width; ++x) {
                        const double* sum = &l.sums[l.texel(x, y) * 3 * nd];
                        const double* m = &l.moments[l.texel(x, y) * 6];
                        const double inv = 1.0 / double(pyramid.footprintCount(k, x, y));
                        const TexelLobe lean =
                            methodLobe(Method::Lean, pyramid.boxMoments(k, x, y), s, params);
                        // The Gaussian of the normals that are not steep, weighted by their share:
                        // with none left it adds nothing.
                        const double count = m[0], share = count * inv;
                        TexelLobe withoutSteep = lean;
                        if (count > 0.0) {
                            NormalMoments moments;
                            const double mx = m[1] / count, my = m[2] / count;
                            moments.slope = glm::vec2(float(mx), float(my));
                            moments.slopeCov = {float(std::max(0.0, m[3] / count - mx * mx)),
                                                float(std::max(0.0, m[4] / count - my * my)),
                                                float(m[5] / count - mx * my)};
                            withoutSteep = methodLobe(Method::Lean, moments, s, params);
                            // LEAN's cosine: this step changes the NDF alone.
                            withoutSteep.normal = lean.normal;
                        }
                        const glm::dvec3 normal(lean.normal);
                        for (size_t d = 0; d < nd; ++d) {
                            row.truth += sum[nd + d] * inv;
                            row.oneCosine += sum[d] * inv * std::max(0.0, glm::dot(normal, directions[d].l));
                            row.steepTruth += sum[2 * nd + d] * inv;
                            if (share > 0.0)
                                row.withoutSteep += share * methodValue(withoutSteep, directions[d]);
                            row.lean += methodValue(lean, directions[d]);
                        }
                    }
            }
        });
    }
    for (int k = firstMip; k <= lastMip; ++k) {
        SplitSums total; // in band order: the same figures on any number of threads
        for (const auto& band : bandSums)
            total += band[size_t(k - firstMip)];
        LeanEnergySplit e;
        e.basePower = s;
        e.mip = k;
        // A step whose result sums to 0 (one cosine facing away from every light, every normal steep)
        // is skipped: its factor is 1 and the next step starts from the one before, so the product is
        // the energy ratio whatever is 0.
        const double cosineBase = total.oneCosine > 0.0 ? total.oneCosine : total.truth;
        const double shapeBase = total.withoutSteep > 0.0 ? total.withoutSteep : cosineBase;
        e.energy = ratioOr1(total.lean, total.truth);
        e.cosine = ratioOr1(cosineBase, total.truth);
        e.shape = ratioOr1(shapeBase, cosineBase);
        e.steep = ratioOr1(total.lean, shapeBase);
        e.steepNormals = map.normals.empty() ? 0.0 : double(steepCount) / double(map.normals.size());
        e.steepTruth = total.truth > 0.0 ? total.steepTruth / total.truth : 0.0;
        out.push_back(e);
    }
    return out;
}

} // namespace burnish
