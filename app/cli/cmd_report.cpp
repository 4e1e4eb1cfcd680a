// burnish report approximations: every approximation in core against its exact form, with its
// error and its measured cost (Markdown table on stdout; .md, .json and .png in --out).
#include "command.h"

#include <burnish/core/eval/approximations.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

namespace burnish::cli {
namespace {

struct ReportArgs {
    std::string out = "burnish-report";
    bool quick = false;
    bool json = false;
};

int runApproximations(const ReportArgs& args) {
    const auto start = std::chrono::steady_clock::now();
    std::error_code ec;
    std::filesystem::create_directories(args.out, ec);
    if (ec) return fail("cannot create output folder " + args.out + ": " + ec.message());
    if (args.quick)
        std::fprintf(stderr, "burnish: quick run: fewer inputs and repetitions, coarse error grids\n");

    ApproximationOptions options;
    options.quick = args.quick;
    auto report = measureApproximations(options);
    if (!report) return fail(report.error());
    if (auto st = writeApproximationReport(*report, args.out); !st) return fail(st.error());

    if (args.json)
        std::fputs((approximationsJson(*report).dump(2) + "\n").c_str(), stdout);
    else
        std::fputs(approximationsMarkdown(*report).c_str(), stdout);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string dir = std::filesystem::path(args.out).string();
    std::fprintf(stderr, "burnish: wrote %s/approximations.{md,json,png} in %.1f s\n", dir.c_str(), seconds);
    return 0;
}

const CommandRegistration registration(10, [](CLI::App& app) -> std::function<int()> {
    auto args = std::make_shared<ReportArgs>();
    CLI::App* report = app.add_subcommand("report", "Measure Burnish's formulas and write reports");
    report->require_subcommand(1);
    CLI::App* approx = report->add_subcommand(
        "approximations", "Every approximation in core against its exact form: error and measured cost");
    approx->add_option("--out", args->out, "Output folder (created if missing)")->capture_default_str();
    approx->add_flag("--quick", args->quick, "Fewer inputs and repetitions, coarser error grids (for tests)");
    approx->add_flag("--json", args->json, "Print the JSON instead of the Markdown table");
    return [args, approx]() -> int {
        if (approx->parsed()) return runApproximations(*args);
        return fail("report: no report named (see 'burnish report --help')");
    };
});

} // namespace
} // namespace burnish::cli
