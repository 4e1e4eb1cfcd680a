// Benchmarks of the lobe-mixture fit (figures, not pass/fail):
//   BM_MixtureFit/<k>     MixturePyramid::build of a 1024² map, every level, K lobes
//   BM_MixtureError/<s>   the evaluate metric (texture space, box footprints, the default 49
//                         directions) of LEAN and of the mixture for K = 1..4 on every map of
//                         BURNISH_BENCH_MAPS (a folder of normal maps; default the checkout's
//                         ../shared/data/normal-maps), mips 1-4, base power s: a table on stdout
//   BM_MixtureRefine/<s>  the experiment behind --shaded-fit (prefilter/mixture_refine.h, which trains on
//                         several views with analytic derivatives): does fitting each texel's K = 3 lobes to
//                         the shaded ground truth itself pay? Up to 64 texels per map and mip (an even grid),
//                         each fitted mixture refined by Levenberg-Marquardt (Eigen, numerical derivatives)
//                         on a training direction set (half angles 1-40 deg every 1.5 deg, 16 azimuths), then
//                         measured on the default 49 directions; a table of LEAN, fitted and refined relative
//                         L1 and energy, and ms per texel
// Run: build/core/burnish_bench --benchmark_filter=Mixture
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/sample_maps.h>

#include <Eigen/Dense>
#include <benchmark/benchmark.h>
#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace burnish;
namespace fs = std::filesystem;

void BM_MixtureFit(benchmark::State& state) {
    const auto map = std::make_shared<NormalMap>(makeSampleNormalMap(SampleMapKind::Bumpy, 1024));
    const NormalPyramid pyramid = NormalPyramid::build(map, {BorderMode::Wrap, FilterKernel::Box});
    for (auto _ : state) {
        MixturePyramid m = MixturePyramid::build(pyramid, 256.0, int(state.range(0)));
        benchmark::DoNotOptimize(m);
    }
}
BENCHMARK(BM_MixtureFit)->DenseRange(1, 4)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

struct Figures {
    double truth = 0.0, abs = 0.0, sum = 0.0;
    double l1() const { return truth > 0.0 ? abs / truth : 0.0; }
    double energy() const { return truth > 0.0 ? sum / truth : 1.0; }
};

// The maps of BURNISH_BENCH_MAPS, or of the shared data beside the checkout (seen from the repository
// root or a build folder in it), sorted; none skips the benchmark with an error.
std::vector<fs::path> benchMaps(benchmark::State& state) {
    const char* env = std::getenv("BURNISH_BENCH_MAPS");
    fs::path folder = env ? fs::path(env) : fs::path("../shared/data/normal-maps");
    for (const char* up : {"../../shared/data/normal-maps", "../../../shared/data/normal-maps"})
        if (!env && !fs::is_directory(folder)) folder = up;
    std::vector<fs::path> maps;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(folder, ec))
        if (e.is_regular_file()) maps.push_back(e.path());
    std::sort(maps.begin(), maps.end());
    if (maps.empty())
        state.SkipWithError(("no normal maps in " + folder.string() + " (set BURNISH_BENCH_MAPS)").c_str());
    return maps;
}

// The table benchmarks: one run at each of s = 64, 256 and 1024.
void atThreePowers(benchmark::internal::Benchmark* b) {
    b->Arg(64)->Arg(256)->Arg(1024)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
}

// The box pyramid of a map file (evaluate's footprints), or nothing when it does not load.
std::optional<NormalPyramid> boxPyramid(const fs::path& path) {
    auto loaded = loadNormalMap(path);
    if (!loaded) return std::nullopt;
    return NormalPyramid::build(std::make_shared<NormalMap>(std::move(loaded).value()),
                                {BorderMode::Wrap, FilterKernel::Box});
}

void BM_MixtureError(benchmark::State& state) {
    const double s = double(state.range(0));
    const std::vector<fs::path> maps = benchMaps(state);
    if (maps.empty()) return;
    const auto dirs = evaluationDirections(EvaluateOptions{});
    for (auto _ : state) {
        std::printf(
            "\n| map | s | mip | LEAN L1 | K=1 | K=2 | K=3 | K=4 | LEAN energy | K=2 | K=3 | K=4 |\n");
        std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
        for (const fs::path& path : maps) {
            const auto pyramidOf = boxPyramid(path);
            if (!pyramidOf) continue;
            const NormalPyramid& pyramid = *pyramidOf;
            const int last = std::min(4, pyramid.levelCount() - 1);
            std::vector<MixturePyramid> mixtures;
            for (int k = 1; k <= kMaxMixtureLobes; ++k)
                mixtures.push_back(MixturePyramid::build(pyramid, s, k, last));
            for (int level = 1; level <= last; ++level) {
                const PyramidLevel& l = pyramid.level(level);
                Figures lean;
                std::vector<Figures> mix(static_cast<size_t>(kMaxMixtureLobes));
                for (int y = 0; y < l.height; ++y)
                    for (int x = 0; x < l.width; ++x) {
                        const TexelLobe lobe = methodLobe(Method::Lean, pyramid.boxMoments(level, x, y), s);
                        for (const DirectionPair& d : dirs) {
                            const double t = groundTruthTexel(pyramid, level, x, y, s, d);
                            const double v = methodValue(lobe, d);
                            lean.truth += t, lean.abs += std::abs(v - t), lean.sum += v;
                            for (int k = 0; k < kMaxMixtureLobes; ++k) {
                                const MixturePyramid& mp = mixtures[size_t(k)];
                                const double m = mixtureValue(mp.at(level, x, y), d.l, d.h, mp.minVariance());
                                Figures& f = mix[size_t(k)];
                                f.truth += t, f.abs += std::abs(m - t), f.sum += m;
                            }
                        }
                    }
                std::printf(
                    "| %s | %g | %d | %.4f | %.4f | %.4f | %.4f | %.4f | %.3f | %.3f | %.3f | %.3f |\n",
                    path.filename().string().c_str(), s, level, lean.l1(), mix[0].l1(), mix[1].l1(),
                    mix[2].l1(), mix[3].l1(), lean.energy(), mix[1].energy(), mix[2].energy(),
                    mix[3].energy());
            }
        }
        std::fflush(stdout);
    }
}
BENCHMARK(BM_MixtureError)->Apply(atThreePowers);

// BM_MixtureRefine: K = 3 lobes as parameters (per lobe: log weight, mean slope, log-Cholesky
// covariance), their residuals the mixture's value minus the truth at each training direction.
struct RefineResiduals {
    using Scalar = double;
    using InputType = Eigen::VectorXd;
    using ValueType = Eigen::VectorXd;
    using JacobianType = Eigen::MatrixXd;
    enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
    static constexpr int kLobes = 3;
    const std::vector<DirectionPair>* directions = nullptr;
    const std::vector<double>* truth = nullptr;
    int inputs() const { return 6 * kLobes; }
    int values() const { return int(directions->size()); }

    static DecodedMixture decode(const Eigen::VectorXd& p) {
        DecodedMixture d;
        double total = 0.0;
        for (int i = 0; i < kLobes; ++i)
            total += std::exp(p[6 * i]);
        for (int i = 0; i < kLobes; ++i) {
            DecodedMixture::Lobe& l = d.lobes[size_t(i)];
            l.share = std::exp(p[6 * i]) / total;
            l.mean = {p[6 * i + 1], p[6 * i + 2]};
            const double a = std::exp(p[6 * i + 3]), b = p[6 * i + 4], c = std::exp(p[6 * i + 5]);
            l.cov = {a * a, b * b + c * c, a * b};
            l.normal = normalOfSlope(l.mean);
        }
        d.count = kLobes;
        return d;
    }
    static Eigen::VectorXd encode(const DecodedMixture& m) {
        Eigen::VectorXd p(6 * kLobes);
        for (int i = 0; i < kLobes; ++i) {
            // A lobe the fit did not need starts as a faint copy of the first.
            const DecodedMixture::Lobe& l = m.lobes[size_t(i < m.count ? i : 0)];
            const double a = std::sqrt(l.cov[0]), b = l.cov[2] / a;
            const double c = std::sqrt(std::max(l.cov[1] - b * b, 1e-12));
            p.segment(6 * i, 6) << std::log(i < m.count ? l.share : 1e-4), l.mean.x, l.mean.y, std::log(a), b,
                std::log(c);
        }
        return p;
    }
    int operator()(const Eigen::VectorXd& p, Eigen::VectorXd& r) const {
        const DecodedMixture d = decode(p);
        for (size_t k = 0; k < directions->size(); ++k) {
            const double m = mixtureValue(d, (*directions)[k].l, (*directions)[k].h);
            r[Eigen::Index(k)] = std::isfinite(m) ? m - (*truth)[k] : 1e6;
        }
        return 0;
    }
};

void BM_MixtureRefine(benchmark::State& state) {
    const double s = double(state.range(0));
    const std::vector<fs::path> maps = benchMaps(state);
    if (maps.empty()) return;
    const auto measured = evaluationDirections(EvaluateOptions{});
    EvaluateOptions trainingOptions;
    trainingOptions.halfAnglesDeg.clear();
    for (double a = 1.0; a <= 40.0; a += 1.5)
        trainingOptions.halfAnglesDeg.push_back(a);
    trainingOptions.azimuths = 16;
    const auto training = evaluationDirections(trainingOptions);
    for (auto _ : state) {
        std::printf(
            "\n| map | s | mip | texels | LEAN L1 | fitted | refined | LEAN energy | fitted | refined | "
            "ms per texel |\n");
        std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
        for (const fs::path& path : maps) {
            const auto pyramidOf = boxPyramid(path);
            if (!pyramidOf) continue;
            const NormalPyramid& pyramid = *pyramidOf;
            const int last = std::min(4, pyramid.levelCount() - 1);
            const MixturePyramid mixture = MixturePyramid::build(pyramid, s, RefineResiduals::kLobes, last);
            for (int level = 1; level <= last; ++level) {
                const PyramidLevel& l = pyramid.level(level);
                const int step = std::max(1, std::max(l.width, l.height) / 8);
                Figures lean, fitted, refined;
                int texels = 0;
                const auto start = std::chrono::steady_clock::now();
                for (int y = 0; y < l.height; y += step)
                    for (int x = 0; x < l.width; x += step) {
                        std::vector<double> truth;
                        for (const DirectionPair& d : training)
                            truth.push_back(groundTruthTexel(pyramid, level, x, y, s, d));
                        const DecodedMixture fit =
                            decodeMixture(mixture.at(level, x, y), mixture.minVariance());
                        Eigen::VectorXd p = RefineResiduals::encode(fit);
                        Eigen::NumericalDiff<RefineResiduals> residuals(RefineResiduals{&training, &truth});
                        Eigen::LevenbergMarquardt<Eigen::NumericalDiff<RefineResiduals>> lm(residuals);
                        lm.parameters.maxfev = 400;
                        lm.minimize(p);
                        const DecodedMixture better = RefineResiduals::decode(p);
                        const TexelLobe lobe = methodLobe(Method::Lean, pyramid.boxMoments(level, x, y), s);
                        for (const DirectionPair& d : measured) {
                            const double t = groundTruthTexel(pyramid, level, x, y, s, d);
                            const double v[3] = {methodValue(lobe, d), mixtureValue(fit, d.l, d.h),
                                                 mixtureValue(better, d.l, d.h)};
                            Figures* f[3] = {&lean, &fitted, &refined};
                            for (int i = 0; i < 3; ++i)
                                f[i]->truth += t, f[i]->abs += std::abs(v[i] - t), f[i]->sum += v[i];
                        }
                        ++texels;
                    }
                const double ms =
                    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                        .count();
                std::printf("| %s | %g | %d | %d | %.4f | %.4f | %.4f | %.3f | %.3f | %.3f | %.1f |\n",
                            path.filename().string().c_str(), s, level, texels, lean.l1(), fitted.l1(),
                            refined.l1(), lean.energy(), fitted.energy(), refined.energy(), ms / texels);
            }
        }
        std::fflush(stdout);
    }
}
BENCHMARK(BM_MixtureRefine)->Apply(atThreePowers);

} // namespace
