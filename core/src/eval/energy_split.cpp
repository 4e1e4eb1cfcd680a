// Where LEAN's energy goes (evaluate.h LeanEnergySplit): the truth, the truth with one cosine, the
// Gaussian of the footprint's normals that are not steep, and LEAN, summed over texels and direction
// pairs per mip.
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/numeric.h>

#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace burnish {

namespace {

// The sums of one row of texels over every direction pair: truth, truth with one cosine, the steep
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
    for (int k = firstMip; k <= lastMip; ++k) {
        if (cancelled && cancelled()) break;
        const PyramidLevel& level = pyramid.level(k);
        std::vector<SplitSums> rows(size_t(level.height));
        tbb::parallel_for(0, level.height, [&](int y) {
            std::vector<double> sumD(nd), sumDc(nd), sumSteep(nd);
            SplitSums& row = rows[size_t(y)];
            for (int x = 0; x < level.width; ++x) {
                std::fill(sumD.begin(), sumD.end(), 0.0);
                std::fill(sumDc.begin(), sumDc.end(), 0.0);
                std::fill(sumSteep.begin(), sumSteep.end(), 0.0);
                // The slope moments of the footprint's normals that are not steep, as the pyramid's
                // slopes: b = n.xy / max(n.z, kMinSlopeZ).
                double count = 0.0, bx = 0.0, by = 0.0, bxx = 0.0, byy = 0.0, bxy = 0.0;
                for (int j = level.yStart[size_t(y)]; j < level.yStart[size_t(y) + 1]; ++j)
                    for (int i = level.xStart[size_t(x)]; i < level.xStart[size_t(x) + 1]; ++i) {
                        const glm::dvec3 n(map.at(i, j));
                        const bool steep = n.z < steepZ;
                        for (size_t d = 0; d < nd; ++d) {
                            const double D = blinnPhongNdf(glm::dot(n, directions[d].h), s);
                            const double Dc = D * std::max(0.0, glm::dot(n, directions[d].l));
                            sumD[d] += D;
                            sumDc[d] += Dc;
                            if (steep) sumSteep[d] += Dc;
                        }
                        if (steep) continue;
                        const double zs = std::max(n.z, double(kMinSlopeZ));
                        const double sx = n.x / zs, sy = n.y / zs;
                        count += 1.0, bx += sx, by += sy, bxx += sx * sx, byy += sy * sy, bxy += sx * sy;
                    }
                const double inv = 1.0 / double(pyramid.footprintCount(k, x, y));
                const TexelLobe lean = methodLobe(Method::Lean, pyramid.boxMoments(k, x, y), s, params);
                // Weighted by their share: with no normal left it adds nothing.
                const double share = count * inv;
                TexelLobe withoutSteep = lean;
                if (count > 0.0) {
                    NormalMoments m;
                    const double mx = bx / count, my = by / count;
                    m.slope = glm::vec2(float(mx), float(my));
                    m.slopeCov = {float(std::max(0.0, bxx / count - mx * mx)),
                                  float(std::max(0.0, byy / count - my * my)), float(bxy / count - mx * my)};
                    withoutSteep = methodLobe(Method::Lean, m, s, params);
                    withoutSteep.normal = lean.normal; // LEAN's cosine: this step changes the NDF alone
                }
                const glm::dvec3 normal(lean.normal);
                for (size_t d = 0; d < nd; ++d) {
                    row.truth += sumDc[d] * inv;
                    row.oneCosine += sumD[d] * inv * std::max(0.0, glm::dot(normal, directions[d].l));
                    row.steepTruth += sumSteep[d] * inv;
                    if (share > 0.0) row.withoutSteep += share * methodValue(withoutSteep, directions[d]);
                    row.lean += methodValue(lean, directions[d]);
                }
            }
        });
        SplitSums total; // in row order: the same figures on any number of threads
        for (const SplitSums& r : rows)
            total += r;
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
