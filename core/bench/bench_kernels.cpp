// Google Benchmark over the same float kernels `burnish report approximations` times: for each
// approximation, "<id>/approx" and "<id>/exact" on the same inputs. s/eval is the time per
// evaluation (items_per_second counts evaluations; the Phong pair counts each light).
// Run: burnish_bench --benchmark_filter=fresnel  (this file holds the target's main).
#include <burnish/core/eval/approximations.h>

#include <benchmark/benchmark.h>

#include <algorithm>

namespace {

using namespace burnish;

// The report's default input count, so both tools time the same loop over the same data.
constexpr size_t kInputs = size_t(1) << 20;

void runKernel(benchmark::State& state, const TimedKernelPair* pair, bool exact) {
    const size_t n = exact && pair->exactInputCap > 0 ? std::min(kInputs, pair->exactInputCap) : kInputs;
    const KernelInputs in = pair->makeInputs(n, 1);
    std::vector<float> out(n);
    KernelArgs args;
    for (size_t k = 0; k < in.streams.size() && k < args.in.size(); ++k)
        args.in[k] = in.streams[k].data();
    args.out = out.data();
    args.count = n;
    const Kernel& kernel = exact ? pair->exact : pair->approx;
    for (auto _ : state) {
        kernel(args);
        benchmark::DoNotOptimize(out.data());
        benchmark::ClobberMemory();
    }
    const double evals = double(n) * pair->evalsPerElement;
    state.SetItemsProcessed(static_cast<int64_t>(double(state.iterations()) * evals));
    // Inverted rate: seconds per evaluation, printed with an SI prefix ("3.5n" is 3.5 ns).
    state.counters["s/eval"] = benchmark::Counter(evals, benchmark::Counter::kIsIterationInvariantRate |
                                                             benchmark::Counter::kInvert);
}

const bool kRegistered = [] {
    for (const TimedKernelPair& pair : timedKernelPairs()) {
        benchmark::RegisterBenchmark((pair.id + "/approx").c_str(), runKernel, &pair, false)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((pair.id + "/exact").c_str(), runKernel, &pair, true)
            ->Unit(benchmark::kMillisecond);
    }
    return true;
}();

} // namespace
