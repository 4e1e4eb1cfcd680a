// Benchmarks of the bake and the ground-truth evaluation (figures, not pass/fail):
//   BM_Bake/<method>/<roles>  in-memory bake of a 4096² normal map, all mips (pyramid included):
//                      every texture of the method as floats (0), or as `burnish bake --preset P`
//                      keeps them in memory (1): the textures P's files read, stored as the
//                      files' codes or half floats (compactStorage), P the method's own preset
//                      (toksvig-map, lean, clean, mixture), else blackops
//   BM_ViewportBake/<size>/<n>/<kept> the studio viewport's bake (a gloss or method change) of a
//                      size² map, levels above n skipped (0: none), from the pyramid its first bake
//                      kept (1) or its own (0)
//   BM_ReadImage       reading that map as an 8-bit RGB PNG (written once to the temp folder)
//   BM_DecodeNormalMap decoding the read floats into unit normals, with the diagnostics
//   BM_LoadNormalMap   that PNG straight to unit normals (what `burnish bake` does; no float image)
//   BM_Pyramid         the normal pyramid alone, 4096²
//   BM_MomentRows/<k>  the tent-filtered moment rows of level k alone (forEachMomentRow), 4096²
//   BM_Evaluate        `burnish evaluate`'s core on a 1024² map, mips 1-4, one power, all methods
// The map is BURNISH_BENCH_NORMAL_MAP (any normal map, tiled to the size) when set, else a
// deterministic synthetic bumpy map. Run: build/core/burnish_bench --benchmark_filter='Bake|Pyramid|Evaluate'
#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/export.h>
#include <burnish/core/bake/presets.h>
#include <burnish/core/eval/evaluate.h>
#include <burnish/core/io/image.h>
#include <burnish/core/jobs/bake_job.h>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <random>

namespace {

using namespace burnish;

// The source map tiled (or synthesized) to size×size; cached per size.
const NormalMap& benchMap(int size, std::string& label) {
    static std::map<int, NormalMap> cache;
    static std::map<int, std::string> labels;
    auto it = cache.find(size);
    if (it != cache.end()) {
        label = labels[size];
        return it->second;
    }
    std::vector<glm::vec3> normals(static_cast<size_t>(size) * static_cast<size_t>(size));
    const char* path = std::getenv("BURNISH_BENCH_NORMAL_MAP");
    std::optional<NormalMap> source;
    if (path) {
        auto loaded = loadNormalMap(path);
        if (loaded) source = std::move(*loaded);
    }
    if (source) {
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                normals[size_t(y) * size_t(size) + size_t(x)] =
                    source->at(x % source->width, y % source->height);
        labels[size] = std::string("tiled ") + path;
    } else {
        // Bumps at several scales plus noise: rough at every mip, like a real map.
        std::mt19937 rng(1);
        std::normal_distribution<float> noise(0.0f, 0.05f);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const float u = float(x), v = float(y);
                const float dx =
                    0.3f * std::sin(u * 0.05f) + 0.1f * std::sin(u * 0.7f + v * 0.3f) + noise(rng);
                const float dy =
                    0.3f * std::cos(v * 0.04f) + 0.1f * std::sin(v * 0.9f - u * 0.2f) + noise(rng);
                normals[size_t(y) * size_t(size) + size_t(x)] = glm::normalize(glm::vec3(dx, dy, 1.0f));
            }
        labels[size] = "synthetic";
    }
    label = labels[size];
    return cache.emplace(size, makeNormalMap(size, size, std::move(normals))).first->second;
}

// BM_Bake/<method>/<roles>: roles 0 bakes every texture the method has, as floats; roles 1 what
// `burnish bake --preset P` bakes in memory for the method: the textures P's files read, each kept
// as its files store it, with P's encoding (P its own preset for the Toksvig map, LEAN, CLEAN and
// the mixture, else blackops; core/bench/bake_vs_maketx.sh uses the same).
void BM_Bake(benchmark::State& state) {
    std::string label;
    const NormalMap& map = benchMap(4096, label);
    BakeOptions options;
    options.method = allMethods()[size_t(state.range(0))];
    std::string roles = "every texture";
    if (state.range(1) == 1) {
        const Method m = options.method;
        const bool own =
            m == Method::ToksvigMap || m == Method::Lean || m == Method::Clean || m == Method::Mixture;
        BakeJobSpec spec;
        spec.input = "sample:bumpy";
        spec.out = (std::filesystem::temp_directory_path() / "burnish-bench-bake").string(); // never written
        spec.preset = own ? std::string(methodName(m)) : "blackops";
        spec.method = std::string(methodName(m));
        auto job = resolveBakeJob(spec);
        if (!job) {
            state.SkipWithError(job.error().c_str());
            return;
        }
        options = job->bake;
        options.roles = presetRoles(job->preset);
        BakeRecord planned;
        auto shape = bakeJobShape(*job, map.width, map.height, planned);
        if (!shape) {
            state.SkipWithError(shape.error().c_str());
            return;
        }
        options.storage = compactStorage(*shape, job->preset, job->exportOptions, planned);
        roles = "preset " + job->preset.name + "'s textures as its files keep them";
    }
    for (auto _ : state) {
        auto out = bake(map, options);
        benchmark::DoNotOptimize(out);
    }
    state.SetLabel(std::string(methodName(options.method)) + ", " + roles + ", " + label);
    state.counters["Mtexels/s"] =
        benchmark::Counter(double(map.texelCount()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Bake)
    ->ArgsProduct({benchmark::CreateDenseRange(0, int(burnish::Method::Mixture), 1), {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2)
    ->UseRealTime();

// The benchmark map stored as an 8-bit RGB PNG (as `burnish bake` gets it), written once.
const std::filesystem::path& benchPng(std::string& label) {
    static std::filesystem::path path;
    const NormalMap& map = benchMap(4096, label);
    if (path.empty()) {
        std::vector<float> rgb(map.texelCount() * 3);
        for (size_t i = 0; i < map.texelCount(); ++i)
            for (int c = 0; c < 3; ++c)
                rgb[3 * i + size_t(c)] = 0.5f * map.normals[i][c] + 0.5f;
        const auto target = std::filesystem::temp_directory_path() / "burnish_bench_4096.png";
        ImageWriteOptions options;
        options.type = StoredType::UInt8;
        if (writeImageAtomic(target, map.width, map.height, 3, rgb, options)) path = target;
    }
    return path;
}

// Reads the benchmark PNG with `read` (returning a Result) each iteration.
template <class Read> void benchReadPng(benchmark::State& state, const Read& read) {
    std::string label;
    const auto& path = benchPng(label);
    if (path.empty()) {
        state.SkipWithError("cannot write the benchmark PNG");
        return;
    }
    for (auto _ : state) {
        auto result = read(path);
        benchmark::DoNotOptimize(result);
    }
    state.SetLabel(label);
}

// Reading the 4096² 8-bit PNG into floats (core's PNG decoder, the conversion on the other cores).
// The studio viewport's bake after a gloss or method change on a size² map: levels above its 2048
// texture cap skipped (BakeOptions::largestLevel, 2048) against the whole chain (0).
void BM_ViewportBake(benchmark::State& state) {
    std::string label;
    const NormalMap& map = benchMap(int(state.range(0)), label);
    BakeOptions options;
    options.largestLevel = int(state.range(1));
    // The studio's later bakes of a map read the pyramid its first bake kept (bakePyramid).
    const bool cached = state.range(2) != 0;
    if (cached) {
        const std::shared_ptr<const NormalMap> borrowed(&map, [](const NormalMap*) {});
        options.cachedPyramid = bakePyramid(borrowed, options);
    }
    for (auto _ : state) {
        auto out = bake(map, options);
        benchmark::DoNotOptimize(out);
    }
    state.SetLabel(std::string(methodName(options.method)) + ", levels up to " +
                   (options.largestLevel ? std::to_string(options.largestLevel) : std::to_string(map.width)) +
                   (cached ? ", kept pyramid" : ", own pyramid") + ", " + label);
}
BENCHMARK(BM_ViewportBake)
    ->Args({8192, 0, 0})
    ->Args({8192, 2048, 0})
    ->Args({8192, 2048, 1})
    ->Args({2048, 2048, 0})
    ->Args({2048, 2048, 1})
    ->Args({512, 2048, 0})
    ->Args({512, 2048, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2)
    ->UseRealTime();

void BM_ReadImage(benchmark::State& state) {
    benchReadPng(state, [](const std::filesystem::path& path) { return readImage(path); });
}
BENCHMARK(BM_ReadImage)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

// Decoding those floats into unit normals with the plausibility diagnostics.
void BM_DecodeNormalMap(benchmark::State& state) {
    std::string label;
    const auto& path = benchPng(label);
    auto image = path.empty() ? Result<Image>(Error{"no PNG"}) : readImage(path);
    if (!image) {
        state.SkipWithError(image.error().c_str());
        return;
    }
    for (auto _ : state) {
        auto map = decodeNormalMap(*image);
        benchmark::DoNotOptimize(map);
    }
    state.SetLabel(label);
}
BENCHMARK(BM_DecodeNormalMap)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

// The file straight to unit normals, as `burnish bake` reads its input: blocks of texels decode on
// the other cores while later rows are inflated and unfiltered, with no float copy of the image.
// Compare with BM_ReadImage + BM_DecodeNormalMap, the two steps it replaces.
void BM_LoadNormalMap(benchmark::State& state) {
    benchReadPng(state, [](const std::filesystem::path& path) { return loadNormalMap(path); });
}
BENCHMARK(BM_LoadNormalMap)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

void BM_Pyramid(benchmark::State& state) {
    std::string label;
    const NormalMap& map = benchMap(4096, label);
    const std::shared_ptr<const NormalMap> borrowed(&map, [](const NormalMap*) {});
    for (auto _ : state) {
        auto pyramid = NormalPyramid::build(borrowed);
        benchmark::DoNotOptimize(pyramid);
    }
    state.SetLabel(label);
}
BENCHMARK(BM_Pyramid)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

void BM_MomentRows(benchmark::State& state) {
    std::string label;
    const NormalMap& map = benchMap(4096, label);
    const std::shared_ptr<const NormalMap> borrowed(&map, [](const NormalMap*) {});
    const auto pyramid = NormalPyramid::build(borrowed);
    const int k = int(state.range(0));
    for (auto _ : state) {
        std::vector<float> sink(size_t(pyramid.level(k).height));
        pyramid.forEachMomentRow(k, [&](int y, const NormalMoments* row) {
            sink[size_t(y)] = row[0].cov[0] + row[pyramid.level(k).width - 1].slopeCov[2];
        });
        benchmark::DoNotOptimize(sink);
    }
    state.SetLabel(label);
}
BENCHMARK(BM_MomentRows)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

void BM_Evaluate(benchmark::State& state) {
    std::string label;
    const NormalMap& map = benchMap(1024, label);
    EvaluateOptions options;
    options.firstMip = 1;
    options.lastMip = 4;
    for (auto _ : state) {
        auto result = evaluateMethods(map, options);
        benchmark::DoNotOptimize(result);
    }
    state.SetLabel(label);
}
BENCHMARK(BM_Evaluate)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

} // namespace
