// Benchmarks of the lobe-mixture fit (figures, not pass/fail):
//   BM_MixtureFit/<k>     MixturePyramid::build of a 1024² map, every level, K lobes
//   BM_MixtureError/<s>   the evaluate metric (texture space, box footprints, the default 49
//                         directions) of LEAN and of the mixture for K = 1..4 on every map of
//                         BURNISH_BENCH_MAPS (a folder of normal maps; default the checkout's
//                         ../shared/data/normal-maps), mips 1-4, base power s: a table on stdout
// Run: build/core/burnish_bench --benchmark_filter=Mixture
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/sample_maps.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
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

void BM_MixtureError(benchmark::State& state) {
    const double s = double(state.range(0));
    const char* env = std::getenv("BURNISH_BENCH_MAPS");
    // The shared data beside the checkout, seen from the repository root or a build folder in it.
    fs::path folder = env ? fs::path(env) : fs::path("../shared/data/normal-maps");
    for (const char* up : {"../../shared/data/normal-maps", "../../../shared/data/normal-maps"})
        if (!env && !fs::is_directory(folder)) folder = up;
    std::vector<fs::path> maps;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(folder, ec))
        if (e.is_regular_file()) maps.push_back(e.path());
    std::sort(maps.begin(), maps.end());
    if (maps.empty()) {
        state.SkipWithError(("no normal maps in " + folder.string() + " (set BURNISH_BENCH_MAPS)").c_str());
        return;
    }
    const auto dirs = evaluationDirections(EvaluateOptions{});
    for (auto _ : state) {
        std::printf(
            "\n| map | s | mip | LEAN L1 | K=1 | K=2 | K=3 | K=4 | LEAN energy | K=2 | K=3 | K=4 |\n");
        std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
        for (const fs::path& path : maps) {
            auto loaded = loadNormalMap(path);
            if (!loaded) continue;
            const auto map = std::make_shared<NormalMap>(std::move(loaded).value());
            const NormalPyramid pyramid = NormalPyramid::build(map, {BorderMode::Wrap, FilterKernel::Box});
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
BENCHMARK(BM_MixtureError)
    ->Arg(64)
    ->Arg(256)
    ->Arg(1024)
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

} // namespace
