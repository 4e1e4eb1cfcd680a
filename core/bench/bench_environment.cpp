// Environment prefiltering: a 2048×1024 equirect (BURNISH_BENCH_ENV, or the procedural studio) to
// 256² faces with the full mip chain; counters give its error against the brute-force reference and
// the FIS taps that match the prefiltered map within 2%. Peak memory: run under /usr/bin/time -v.
// Speed: BM_Prefilter256Speed (medians of 3, seconds per mip as counters) and BM_EnvPipeline256, what
// `burnish env` does after reading its input, files included:
//   BURNISH_BENCH_ENV=courtyard.exr burnish_bench --benchmark_filter='Speed|Pipeline'
#include <burnish/core/env/cube.h>
#include <burnish/core/env/cube_dds.h>
#include <burnish/core/env/prefilter.h>
#include <burnish/core/env/sampling.h>
#include <burnish/core/env/sh.h>
#include <burnish/core/env/storage.h>
#include <burnish/core/util/files.h>

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace {

using namespace burnish;

const Image& sourceImage() {
    static const Image image = [] {
        if (const char* path = std::getenv("BURNISH_BENCH_ENV")) {
            auto loaded = readImage(path);
            if (loaded) return std::move(loaded.value());
        }
        return proceduralStudioEquirect(2048, 1024);
    }();
    return image;
}

void BM_EquirectToCube256(benchmark::State& state) {
    const Image& image = sourceImage();
    for (auto _ : state) {
        auto cube = equirectToCube(image, 256);
        benchmark::DoNotOptimize(cube);
    }
}
BENCHMARK(BM_EquirectToCube256)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Prefilter256FullChain(benchmark::State& state) {
    const auto source = equirectToCube(sourceImage(), 256);
    if (!source) {
        state.SkipWithError(source.error().c_str());
        return;
    }
    PrefilterOptions o;
    o.lobe = state.range(0) == 0 ? LobeModel::Phong : LobeModel::BlinnPhong;
    Result<PrefilteredEnvironment> p = Error{"not run"};
    for (auto _ : state) {
        p = prefilterRadiance(source->cube, o);
        benchmark::DoNotOptimize(p);
    }
    if (!p) {
        state.SkipWithError(p.error().c_str());
        return;
    }
    // Error against brute force over 32 directions per mip (outside the timed loop).
    const auto c = compareWithReference(*p, source->cube, 32, 64);
    if (c) {
        double worst = 0.0, worstLookup = 0.0;
        unsigned taps = 0;
        for (const EnvironmentMipError& row : c->mips) {
            worst = std::max(worst, row.relativeRms);
            worstLookup = std::max(worstLookup, row.lookupRelativeRms);
            state.counters["mip" + std::to_string(row.mip) + "_relRms"] = row.relativeRms;
            state.counters["mip" + std::to_string(row.mip) + "_fisTaps"] = row.fisSamplesToMatch;
            taps = std::max(taps, row.fisSamplesToMatch);
        }
        state.counters["worstRelRms"] = worst;
        state.counters["worstLookupRelRms"] = worstLookup;
    }
}
BENCHMARK(BM_Prefilter256FullChain)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

// The default chain's time, Phong (range(0) = 0) or Blinn-Phong with the Black Ops encoding (1): medians
// of three runs, the wall time of each mip as counters (mip0_s, ...).
void BM_Prefilter256Speed(benchmark::State& state) {
    const auto source = equirectToCube(sourceImage(), 256);
    if (!source) {
        state.SkipWithError(source.error().c_str());
        return;
    }
    PrefilterOptions o;
    if (state.range(0) == 1) {
        o.lobe = LobeModel::BlinnPhong;
        o.encoding = GlossEncoding::fromName("blackops").value();
    }
    for (auto _ : state) {
        auto p = prefilterRadiance(source->cube, o);
        if (!p) {
            state.SkipWithError(p.error().c_str());
            return;
        }
        for (size_t m = 0; m < p->seconds.size(); ++m)
            state.counters["mip" + std::to_string(m) + "_s"] = p->seconds[m];
    }
}
BENCHMARK(BM_Prefilter256Speed)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

// `burnish env`'s work after reading the image, default options: equirect → 256² cube, SH9, the
// prefiltered chain, the 32² irradiance cube, and the DDS cubes and half EXR faces staged and
// committed into a fresh folder (fsync per file, as the command does). Medians of three.
void BM_EnvPipeline256(benchmark::State& state) {
    const Image& image = sourceImage();
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() / ("burnish-bench-env-" + std::to_string(::getpid()));
    for (auto _ : state) {
        std::filesystem::remove_all(folder);
        std::filesystem::create_directories(folder);
        auto source = equirectToCube(image, 256);
        if (!source) {
            state.SkipWithError(source.error().c_str());
            break;
        }
        const Sh9 sh = projectSh9(source->cube);
        auto filtered = prefilterRadiance(source->cube, PrefilterOptions{});
        auto irradiance = irradianceCube(sh, 32);
        auto begun = FileSet::begin(folder);
        if (!filtered || !irradiance || !begun) {
            state.SkipWithError("the pipeline failed");
            break;
        }
        FileSet& set = begun.value();
        Status s = set.addBytes("radiance.dds", encodeCubeDds(filtered->radiance));
        if (s) s = set.addBytes("irradiance.dds", encodeCubeDds(*irradiance));
        if (s) s = stageCubeExrFaces(filtered->radiance, "radiance", set);
        if (s) s = stageCubeExrFaces(*irradiance, "irradiance", set);
        if (s) s = set.commit("", {}, Overwrite::Allow);
        if (!s) {
            state.SkipWithError(s.error().c_str());
            break;
        }
    }
    std::filesystem::remove_all(folder);
}
BENCHMARK(BM_EnvPipeline256)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

// What the studio does on the fly: the procedural studio at face size range(0) (64 or 128), the full
// chain with the default options, Phong (range(1) = 0) or Blinn-Phong (1). The cube is built once.
void BM_PrefilterStudio(benchmark::State& state) {
    const auto source = proceduralStudioEnvironment(int(state.range(0)));
    if (!source) {
        state.SkipWithError(source.error().c_str());
        return;
    }
    PrefilterOptions o;
    o.lobe = state.range(1) == 0 ? LobeModel::Phong : LobeModel::BlinnPhong;
    for (auto _ : state) {
        auto p = prefilterRadiance(*source, o);
        benchmark::DoNotOptimize(p);
    }
}
BENCHMARK(BM_PrefilterStudio)
    ->Args({64, 0})
    ->Args({64, 1})
    ->Args({128, 0})
    ->Args({128, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

} // namespace
